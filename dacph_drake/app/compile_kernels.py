"""`python -m dacph_drake.app.compile_kernels`: fills numba's on-disk cache by simulating
10 ms of the DAC loop on the short scenario, without and with the spacecraft's sensors
(scripts/setup.sh runs it)."""
import time

from dacph_drake.loop.simulate import simulate
from dacph_drake.scenario.built_in import short_scenario, with_spacecraft_sensing


def main() -> None:
    """Compiles the kernels, printing how long it took."""
    start = time.perf_counter()
    simulate(short_scenario(), "dac", duration=0.01)
    simulate(with_spacecraft_sensing(short_scenario()), "dac", duration=0.01)
    print(f"dacph_drake kernels compiled and cached in {time.perf_counter() - start:.1f} s")


if __name__ == "__main__":
    main()
