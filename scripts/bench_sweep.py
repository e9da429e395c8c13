"""Sweep throughput (run: .venv/bin/python scripts/bench_sweep.py).

On the same trials, in one run (the machines are shared, so only ratios measured
together mean something):
  bare       each trial's simulate() calls, one after the other, in this process
  1 worker   dacph's sweep on a local process pool of 1 worker
  2 workers  the same on 2 workers                 -> speed-up (target >= 1.8x)
  Dask       the same on a LocalCluster of 2 single-threaded workers
The machine's own ceiling, for reference: the throughput of 2 independent CPU-bound
Python processes against 1 (no project code; a 2-vCPU VM may give far less than 2x).
Sweep overhead per trial = (1-worker wall - bare wall) / trials, against the bare
wall per trial (target <= 5 %); it includes starting the worker process; the part
inside the trials (metrics, the row) is the rows' wall times minus the bare ones.
"""
import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from dacph_drake.montecarlo.definition import load_sweep, sample_trial
from dacph_drake.montecarlo.executors import dask_executor
from dacph_drake.montecarlo.runner import run_sweep
from dacph_drake.loop.simulate import simulate
from dacph_drake.scenario import Phases, short_scenario
from dacph_drake.scenario_files import save_scenario

SWEEP = """\
scenario: bench.yaml
trials: {trials}
seed: 1
controllers: [dac, model-based]
distributions:
  link_mass_scale: !Uniform {{min: 0.9, max: 1.1}}
  delta_B_scale: !Uniform {{min: 0.5, max: 1.5}}
  delta_D_scale: !Uniform {{min: 0.5, max: 1.5}}
  disturbance_scale: !Uniform {{min: 0.5, max: 2.0}}
  q0: !UniformVector {{min: [0.2, 0.8], max: [0.4, 1.2]}}
"""


SPIN = "x = 0\nfor i in range(40_000_000):\n    x += i * i\n"


def machine_ceiling() -> float:
    """Throughput of 2 concurrent CPU-bound processes / that of 1."""
    def run(copies: int) -> float:
        start = time.perf_counter()
        processes = [subprocess.Popen([sys.executable, "-c", SPIN]) for _ in range(copies)]
        for process in processes:
            process.wait()
        return time.perf_counter() - start
    return 2 * run(1) / run(2)


def bare(definition):
    """Wall time of each trial's simulate() calls [s]."""
    walls = []
    for trial in range(definition.sweep.trials):
        scenario = sample_trial(definition, trial).scenario
        start = time.perf_counter()
        for controller in definition.sweep.controllers:
            simulate(scenario, controller)
        walls.append(time.perf_counter() - start)
    return walls


def swept(definition, out: Path, workers: int):
    """(wall of the sweep, its rows)."""
    start = time.perf_counter()
    rows = run_sweep(definition, out, slots=workers)
    _check(rows)
    return time.perf_counter() - start, rows


def on_dask(definition, out: Path, workers: int):
    """(wall including the cluster's start, wall of the sweep alone)."""
    start = time.perf_counter()
    with dask_executor("local", workers) as (executor, slots):
        ready = time.perf_counter()
        _check(run_sweep(definition, out, executor, slots))
        done = time.perf_counter()
    return done - start, done - ready


def _check(rows) -> None:
    failed = [(r["trial"], r["reason"]) for r in rows if r["status"] != "ok"]
    if failed:
        print(f"  note: failed trials {failed}")


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--trials", type=int, default=6)
    parser.add_argument("--phases", type=float, nargs=4, default=[0.5, 2.0, 2.0, 2.0],
                        metavar=("WARMUP", "LINEAR", "NONLINEAR", "DISTURBANCE"),
                        help="[s] of the benchmark's scenario")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        scenario = short_scenario()
        scenario.phases = Phases(*args.phases)
        save_scenario(scenario, folder / "bench.yaml")
        (folder / "sweep.yaml").write_text(SWEEP.format(trials=args.trials))
        definition = load_sweep(folder / "sweep.yaml")
        n = args.trials
        print(f"{n} trials of {scenario.duration:g} s simulated, DAC and model-based each")
        bare_walls = bare(definition)
        t_bare = sum(bare_walls)
        print(f"  bare simulate() in this process   {t_bare:7.1f} s   "
              f"{n / t_bare * 60:6.2f} trials/min")
        t1, rows = swept(definition, folder / "one", 1)
        print(f"  sweep, 1 worker                   {t1:7.1f} s   "
              f"{n / t1 * 60:6.2f} trials/min")
        t2, _ = swept(definition, folder / "two", 2)
        print(f"  sweep, 2 workers                  {t2:7.1f} s   "
              f"{n / t2 * 60:6.2f} trials/min")
        t_dask, t_dask_run = on_dask(definition, folder / "dask", 2)
        print(f"  Dask LocalCluster, 2 workers      {t_dask:7.1f} s   "
              f"{n / t_dask * 60:6.2f} trials/min  ({t_dask_run:.1f} s after the "
              "cluster started)")
        ceiling = machine_ceiling()
        overhead = (t1 - t_bare) / n
        in_worker = (sum(r["wall_time"] for r in rows) - t_bare) / n
        print("ratios (same run):")
        print(f"  speed-up 2 workers / 1 worker     {t1 / t2:6.2f}x  (target >= 1.8x)")
        print(f"  machine ceiling, 2 processes / 1  {ceiling:6.2f}x  (CPU-bound, no project "
              "code)")
        print(f"  sweep overhead per trial          {overhead:+6.2f} s = "
              f"{100 * overhead / (t_bare / n):+.1f} % of a bare trial (target <= 5 %), "
              "worker start included")
        print(f"    of which inside the trial       {in_worker:+6.2f} s = "
              f"{100 * in_worker / (t_bare / n):+.1f} % (row wall time - bare wall time)")
        print(f"  Dask / process pool throughput    {t2 / t_dask:6.2f}  "
              f"({t2 / t_dask_run:.2f} excluding the cluster's start)")


if __name__ == "__main__":
    main()
