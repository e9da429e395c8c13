"""A run's wall time with a second CPU-bound process on the machine, over its time
alone (run: .venv/bin/python scripts/bench_contention.py --out
results/performance/contention.md).

The run: scenarios/panda.yaml's DAC loop for --duration simulated seconds, in a
fresh process whose environment sets no thread count (OMP_NUM_THREADS and the
like removed: the library's defaults, as a user's shell has them). The second
process (COMPETITORS): a busy loop in Python (one core), or numpy matrix
products at the default thread count. Pairs alternate alone / contended
(--pairs of them); the figure is the median of the pairs' ratios, and each
side's median wall time. The runs limit BLAS and OpenMP to one thread
themselves (loop.threads): before that, such a run's idle BLAS/OpenMP threads
spun against the second process.
"""
import argparse
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RUN = ("from dacph_drake.loop.simulate import simulate; "
       "from dacph_drake.assembly.scenario_files import load_scenario; "
       "simulate(load_scenario({path!r}), 'dac', duration={duration})")
# The second process: a busy loop (one core), or numpy matrix products at the
# library's default thread count (their BLAS threads spin on both cores).
COMPETITORS = {"busy": "while True: pass",
               "blas": "import numpy as np\na = np.random.rand(300, 300)\n"
                       "while True: a = np.tanh(a @ a)"}
THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
                    "NUMBA_NUM_THREADS")


def timed_run(duration: float, competitor: str = "") -> float:
    """The wall time of one run [s], alone or with a competitor process beside it."""
    env = {k: v for k, v in os.environ.items() if k not in THREAD_VARIABLES}
    busy = (subprocess.Popen([sys.executable, "-c", COMPETITORS[competitor]], env=env)
            if competitor else None)
    try:
        start = time.perf_counter()
        subprocess.run([sys.executable, "-c", RUN.format(
            path=str(ROOT / "scenarios" / "panda.yaml"), duration=duration)],
            env=env, check=True, capture_output=True)
        return time.perf_counter() - start
    finally:
        if busy is not None:
            busy.kill()
            busy.wait()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pairs", type=int, default=7)
    parser.add_argument("--duration", type=float, default=3.0, help="[s] simulated")
    parser.add_argument("--out", default=None, help="also write the table there")
    args = parser.parse_args()
    timed_run(args.duration)                      # compiles and caches the kernels
    lines = [f"| second process (Panda DAC, {args.duration:g} s simulated, whole "
             f"process) | alone [s] | with it [s] | ratio (median of {args.pairs} "
             "pairs) |", "|---|---|---|---|"]
    for competitor in COMPETITORS:
        alone, contended = [], []
        for _ in range(args.pairs):
            alone.append(timed_run(args.duration))
            contended.append(timed_run(args.duration, competitor))
        ratios = [c / a for a, c in zip(alone, contended)]
        lines.append(f"| {competitor} | {statistics.median(alone):.2f} | "
                     f"{statistics.median(contended):.2f} | "
                     f"{statistics.median(ratios):.2f} (range {min(ratios):.2f}-"
                     f"{max(ratios):.2f}) |")
    table = "\n".join(lines) + "\n"
    print(table)
    if args.out:
        Path(args.out).write_text(table)


if __name__ == "__main__":
    main()
