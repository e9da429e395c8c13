"""Sweep throughput (run: .venv/bin/python scripts/bench_sweep.py).

First, batches (--batch-sizes, default 1 4 16 64): the per-trial wall time per
simulated second of the planar DAC and model-based loops when that many trials
share one diagram (loop.simulate.simulate_batch, its monitor included; each batch
size in a fresh process, with its peak memory; the trials the short scenario with
sampled link masses and q0, phases compressed to --batch-duration), beside the
ground-truth plant of one arm alone (same step), and the trials per hour of one
worker. Then the satellite_6dof DAC loop in batches (--spatial-batch-sizes,
default 1 4 16), against its batch of 1 (a single run). Then the sensors' cost in
batches (--sensing-batch-sizes, default 1 16 64): the planar DAC batch with sensing
off, with the sensors at work reading the truth (a star tracker without noise) and
with the spacecraft's sensors (scenario.built_in.spacecraft_sensing without its delays
and lag), per trial; one diagram's sensors serve every trial of its batch.

Then, on the same trials, in one run (the machines are shared, so only ratios
measured together mean something), with one trial per diagram:
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
from dacph_drake.scenario import Phases
from dacph_drake.scenario.built_in import short_scenario
from dacph_drake.assembly.scenario_files import save_scenario

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


BATCH = """\
import resource, sys
import numpy as np
from dacph_drake.loop.simulate import simulate_batch
import dataclasses
from dacph_drake.scenario import Phases, Sensing
from dacph_drake.scenario.built_in import short_scenario, spacecraft_sensing
controller, size, duration = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
sensing = {"off": Sensing(),
           "at_work": Sensing(enabled=True, star_tracker_rate=10.0),
           "sensors": dataclasses.replace(spacecraft_sensing(), lhs_delay=0, rhs_delay=0,
                                          actuator_lag=0.0)}[
    sys.argv[4] if len(sys.argv) > 4 else "off"]
rng = np.random.default_rng(1)
trials = []
for i in range(size):
    s = short_scenario()
    s.sensing = sensing
    s.phases = Phases(duration / 8, duration / 4, duration / 4, 3 * duration / 8)
    for link in s.robot.truth.links:
        link.mass *= rng.uniform(0.9, 1.1)
    s.q0 = [rng.uniform(0.2, 0.4), rng.uniform(0.8, 1.2)]
    s.seed = i
    trials.append(s)
results = simulate_batch(trials, controller, duration=duration)
print(results[0].wall_time / duration / size,
      resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
      sum(r.status != "ok" for r in results))
"""

SPATIAL_BATCH = """\
import copy, resource, sys
import numpy as np
from dacph_drake.loop.simulate import simulate_batch
from dacph_drake.assembly.scenario_files import load_scenario
name, size, duration = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
rng = np.random.default_rng(1)
trials = []
for i in range(size):
    s = load_scenario(name)
    s.q0 = list(np.asarray(s.q0) + rng.uniform(-0.05, 0.05, len(s.q0)))
    s.seed = i
    trials.append(s)
results = simulate_batch(trials, "dac", duration=duration)
print(results[0].wall_time / duration / size,
      resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
      sum(r.status != "ok" for r in results))
"""

PLANT = """\
import sys, time
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import ConstantVectorSource
from dacph_drake.dynamics.plant import AddFreeFloatingArm, SetArmAtRest
from dacph_drake.scenario.simulator import MakeSimulator
from dacph_drake.scenario.built_in import short_scenario
duration = float(sys.argv[1])
scenario = short_scenario()
builder = DiagramBuilder()
plant, _ = AddFreeFloatingArm(builder, scenario.robot.truth)
torque = builder.AddSystem(ConstantVectorSource([0.01, -0.01]))
builder.Connect(torque.get_output_port(), plant.get_actuation_input_port())
simulator = MakeSimulator(builder.Build(), scenario.simulator)
SetArmAtRest(plant, plant.GetMyContextFromRoot(simulator.get_mutable_context()),
             scenario.q0)
simulator.Initialize()
start = time.perf_counter()
simulator.AdvanceTo(duration)
print((time.perf_counter() - start) / duration)
"""


def batch_scaling(sizes, duration: float) -> None:
    """Per-trial wall per simulated second and peak memory of batches of each size
    (a fresh process each), beside the plant alone."""
    plant = _run(PLANT, duration)[0]
    print(f"batches ({duration:g} s simulated, every phase; the planar plant alone: "
          f"{plant:.4f} s wall per simulated s)")
    for controller in ("dac", "model-based"):
        for size in sizes:
            per_trial, memory, stopped = _run(BATCH, controller, size, duration)
            print(f"  {controller:11s} batch {size:3d}: {per_trial:.4f} s per trial per "
                  f"simulated s = {per_trial / plant:5.2f}x the plant alone; "
                  f"{3600 / (per_trial * 26.0):7.0f} trials of 26 s per hour per worker; "
                  f"peak memory {memory / 1024:.2f} GiB"
                  + (f"; {stopped:.0f} trials stopped early" if stopped else ""))


def sensing_batches(sizes, duration: float) -> None:
    """Per-trial wall per simulated second of planar DAC batches with sensing off, the
    sensors at work reading the truth, and the spacecraft's sensors, and their ratios
    to off at each size (a fresh process each; target: the sensors <= 1.10x)."""
    print(f"sensing in batches ({duration:g} s simulated, DAC)")
    for size in sizes:
        walls = {label: _run(BATCH, "dac", size, duration, label)[0]
                 for label in ("off", "at_work", "sensors")}
        print(f"  batch {size:3d}: off {walls['off']:.4f} s per trial per simulated s; "
              f"sensors at work {walls['at_work'] / walls['off']:5.3f}x, the spacecraft's "
              f"{walls['sensors'] / walls['off']:5.3f}x")


def _run(script, *arguments):
    """A script's printed numbers, run in a fresh process."""
    return [float(x) for x in subprocess.run(
        [sys.executable, "-c", script, *map(str, arguments)], check=True,
        capture_output=True, text=True).stdout.split()]


def spatial_batch_scaling(name: str, sizes, duration: float) -> None:
    """The DAC loop of a spatial arm's scenario (its q0 jittered by +-0.05 rad
    per trial, its own seed) in batches of each size (a fresh process each):
    per-trial wall per simulated second against the batch of 1 (a single run)."""
    print(f"{name} DAC batches ({duration:g} s simulated)")
    single = None
    for size in sizes:
        per_trial, memory, stopped = _run(SPATIAL_BATCH, name, size, duration)
        single = per_trial if single is None else single
        print(f"  batch {size:3d}: {per_trial:.4f} s per trial per simulated s = "
              f"{per_trial / single:4.2f}x the batch of {sizes[0]}; peak memory "
              f"{memory / 1024:.2f} GiB" + (f"; {stopped:.0f} trials stopped early"
                                            if stopped else ""))


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
    rows = run_sweep(definition, out, slots=workers, batch_size=1)
    _check(rows)
    return time.perf_counter() - start, rows


def on_dask(definition, out: Path, workers: int):
    """(wall including the cluster's start, wall of the sweep alone)."""
    start = time.perf_counter()
    with dask_executor("local", workers) as (executor, slots):
        ready = time.perf_counter()
        _check(run_sweep(definition, out, executor, slots, batch_size=1))
        done = time.perf_counter()
    return done - start, done - ready


def _check(rows) -> None:
    failed = [(r["trial"], r["reason"]) for r in rows if r["status"] != "ok"]
    if failed:
        print(f"  note: failed trials {failed}")


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--trials", type=int, default=6,
                        help="trials of the sweep comparison (0: batches only)")
    parser.add_argument("--batch-sizes", type=int, nargs="*", default=[1, 4, 16, 64])
    parser.add_argument("--batch-duration", type=float, default=4.0,
                        help="[s] simulated by each batch")
    parser.add_argument("--phases", type=float, nargs=4, default=[0.5, 2.0, 2.0, 2.0],
                        metavar=("WARMUP", "LINEAR", "NONLINEAR", "DISTURBANCE"),
                        help="[s] of the benchmark's scenario")
    parser.add_argument("--spatial-batch-sizes", type=int, nargs="*", default=[1, 4, 16],
                        help="batch sizes of the satellite_6dof DAC loop (the first: "
                             "the reference)")
    parser.add_argument("--spatial-duration", type=float, default=3.0,
                        help="[s] simulated by each spatial batch")
    parser.add_argument("--sensing-batch-sizes", type=int, nargs="*", default=[1, 16, 64],
                        help="batch sizes of the sensors' cost")
    args = parser.parse_args()
    if args.batch_sizes:
        batch_scaling(args.batch_sizes, args.batch_duration)
    if args.spatial_batch_sizes:
        spatial_batch_scaling("satellite_6dof", args.spatial_batch_sizes,
                              args.spatial_duration)
    if args.sensing_batch_sizes:
        sensing_batches(args.sensing_batch_sizes, args.batch_duration)
    if args.trials <= 0:
        return
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
