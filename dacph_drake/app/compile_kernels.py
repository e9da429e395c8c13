"""`python -m dacph_drake.app.compile_kernels`: fills numba's on-disk cache by simulating
0.5 s of the DAC loop on the short scenario with its phases compressed (every phase
and the learner's updates are reached), alone without sensors and as a batch of two
trials with the spacecraft's sensors (the batch's own signatures)
(scripts/setup.sh runs it)."""
import time

from dacph_drake.loop.simulate import simulate, simulate_batch
from dacph_drake.scenario import Phases
from dacph_drake.scenario.built_in import short_scenario, with_spacecraft_sensing

DURATION = 0.5   # [s]


def _compressed(scenario):
    scenario.phases = Phases(warmup=0.05, linear=0.15, nonlinear=0.15, disturbance=0.15)
    return scenario


def main() -> None:
    """Compiles the kernels, printing how long it took."""
    start = time.perf_counter()
    simulate(_compressed(short_scenario()), "dac", duration=DURATION)
    trials = [_compressed(with_spacecraft_sensing(short_scenario())) for _ in range(2)]
    trials[1].seed = 1
    simulate_batch(trials, "dac", duration=DURATION)
    print(f"dacph_drake kernels compiled and cached in {time.perf_counter() - start:.1f} s")


if __name__ == "__main__":
    main()
