"""Simulating a closed loop of any robot: initial state, divergence monitor, progress
bar, SIGINT/SIGTERM, checkpoints and the saved run (loop.run_store)."""
import gc
import logging
import resource
import signal
import threading
import time
from pathlib import Path
from typing import Callable, Dict, List, Optional, Sequence, Union

import numpy as np
from pydrake.geometry import Meshcat
from pydrake.systems.analysis import InitializeParams, Simulator
from pydrake.systems.framework import Context

from dacph_drake.controllers import build_closed_loop, require_controller
from dacph_drake.scenario.errors import ConfigError, require_positive
from dacph_drake.loop.progress import progress_bar
from dacph_drake.loop.threads import single_threaded
from dacph_drake.atomic_files import prepare_out_dir
from dacph_drake.loop.run_store import (LockRun, ReleaseRun, RunResult,
                                        remove_outputs_of, require_one_scenario,
                                        save_run)
from dacph_drake.dynamics.plant import ArmCoordinates, trial_coordinates
from dacph_drake.controllers.closed_loop import ClosedLoop
from dacph_drake.scenario import Scenario
from dacph_drake.scenario.checks import scheduled_events


MONITOR_PERIOD = 0.01      # [s] of simulated time between checks of the plant state


class _Terminated(KeyboardInterrupt):
    """SIGTERM, raised in the main thread while an interruptible run simulates."""


def _RaiseTerminated(signum, frame):
    raise _Terminated()


def simulate(scenario: Scenario, controller: str = "dac", duration: Optional[float] = None,
             out_dir: Optional[Union[str, Path]] = None, progress: bool = False,
             interruptible: bool = False, checkpoint_seconds: Optional[float] = None,
             meshcat: Optional[Meshcat] = None) -> RunResult:
    """Builds a controller's closed loop for a scenario and simulates it; returns the run's
    RunResult (status "ok", "diverged" or "interrupted"). A run whose state turns
    non-finite or whose rates exceed RUNAWAY_RATE stops with a reason and saves what it has.

    Args:
        scenario: The scenario (robot, task, uncertainty, phases, settings).
        controller: A name of controllers.REGISTRY ("dac", "dac-nominal", "model-based").
        duration: Simulated time [s]; default: the scenario's phases.
        out_dir: Where to save logs_C.npz, scenario.yaml, run_C.json (None: not saved);
            locked first, refused beside another scenario's runs; stale outputs removed
            (run_store.remove_outputs_of).
        progress: Show a progress bar.
        interruptible: SIGINT and SIGTERM stop the run as "interrupted", its logs saved
            (sweeps leave it off to redo the trial on resume).
        checkpoint_seconds: With ``out_dir``, save the logs every this many wall seconds
            with status "incomplete".
        meshcat: A Meshcat drawing the ground truth as it simulates (robots.Robot.LiveView,
            paced by scenario.simulator.target_realtime_rate); results are unchanged.

    Raises:
        ConfigError: Naming the setting, controller, duration or out_dir not allowed."""
    require_controller(controller)
    duration = scenario.duration if duration is None else duration
    require_positive("duration", duration, "s")
    late = [f"{name} = {time:g} s" for name, time in scheduled_events(scenario)
            if time >= duration]
    if late:
        logging.getLogger(__name__).warning(
            "the run ends at %g s, before %s: never in effect in this run", duration,
            ", ".join(late))
    if checkpoint_seconds is not None:
        require_positive("checkpoint_seconds (--checkpoint)", checkpoint_seconds, "s")
    lock = None
    if out_dir is not None:
        lock = LockRun(prepare_out_dir(out_dir), controller)
        try:
            require_one_scenario(Path(out_dir), scenario, controller)
        except ConfigError:
            ReleaseRun(lock)
            raise
        removed = remove_outputs_of(Path(out_dir), controller)
        if removed:
            logging.getLogger(__name__).warning(
                "%s: removed %s, made from the runs this %s run joins or replaces "
                "(dacph simulate and report write them anew)", out_dir,
                ", ".join(removed), controller)
    checkpoint = None
    if out_dir is not None and checkpoint_seconds is not None:
        checkpoint = (checkpoint_seconds,
                      lambda partial: save_run(partial, scenario, out_dir, compress=False))
    try:
        result = _Simulate([scenario], controller, duration, progress, interruptible,
                           checkpoint, meshcat)[0]
        if out_dir is not None:
            save_run(result, scenario, out_dir)
    finally:
        if lock is not None:
            ReleaseRun(lock)
    return result


def simulate_batch(scenarios: Sequence[Scenario], controller: str = "dac",
                   duration: Optional[float] = None,
                   out_dirs: Optional[Sequence] = None) -> List[RunResult]:
    """Simulates a batch of trials in one diagram (controllers.build_closed_loop); returns
    each trial's RunResult in trial order, its solo simulate's bit for bit.

    A trial that diverges, collides or leaves its limits stops alone: its torque is zero
    from the integrator stage where it turned unsound (TrueRhsSystem) and it is brought to
    rest at the next check (every MONITOR_PERIOD). If its state fails a whole batch step
    first, the batch goes back to the last check, stops it there and retakes the step
    (advance_in_chunks' recover).

    Args:
        scenarios: The trials (differing in robot, q0, uncertainty, disturbance, seed only).
        controller: A name of controllers.REGISTRY.
        duration: Simulated time [s]; default: the first trial's phases.
        out_dirs: Each trial's simulate out_dir (None, or None entries: not saved).

    Raises:
        ConfigError: Trials differ in a diagram-shaping setting, or a setting is invalid."""
    require_controller(controller)
    scenarios = list(scenarios)
    duration = scenarios[0].duration if duration is None else duration
    require_positive("duration", duration, "s")
    out_dirs = list(out_dirs) if out_dirs is not None else [None] * len(scenarios)
    locks = []
    try:
        for scenario, out_dir in zip(scenarios, out_dirs, strict=True):
            if out_dir is not None:
                locks.append(LockRun(prepare_out_dir(out_dir), controller))
                require_one_scenario(Path(out_dir), scenario, controller)
                remove_outputs_of(Path(out_dir), controller)
        results = _Simulate(scenarios, controller, duration, progress=False,
                            interruptible=False)
        for result, scenario, out_dir in zip(results, scenarios, out_dirs):
            if out_dir is not None:
                save_run(result, scenario, out_dir)
    finally:
        for lock in locks:
            ReleaseRun(lock)
    return results


def _TrialStop(x, coordinates: ArmCoordinates, clearance, limits, t: float):
    """The reason for a trial to stop at time t, or None: a joint beyond its limits,
    or a link touching the base where the robot measures it (robots.Robot.Clearance:
    the ground truth has no collision geometry); ``x`` the batch's plant state."""
    _, q, _, _ = coordinates.Split(x)
    beyond = limits(q) if limits is not None else None
    if beyond:
        return f"joint limit: {beyond} at t = {t:.4f} s"
    rho = clearance(q) if clearance is not None else np.inf
    if rho <= 0:
        return (f"collision: a link touched the base at t = {t:.4f} s (clearance "
                f"{rho:.4f} m)")
    return None


def _Simulate(scenarios: List[Scenario], controller: str, duration: float,
              progress: bool, interruptible: bool, checkpoint=None,
              meshcat=None) -> List[RunResult]:
    """The run of a batch (one trial: a single run), each trial's result;
    ``checkpoint`` = (wall seconds, save); ``meshcat`` gets a LiveView."""
    try:
        with single_threaded():
            return _SimulateLoop(scenarios, controller, duration, progress,
                                 interruptible, checkpoint, meshcat)
    finally:
        if meshcat is not None:
            # The loop's viewer holds the Meshcat from C++ (its MeshcatVisualizer)
            # inside reference cycles; Drake's Meshcat must be destroyed on the thread
            # that made it, so the cycles are collected here, not by whichever thread
            # the garbage collector next runs on.
            gc.collect()


def _SimulateLoop(scenarios, controller, duration, progress, interruptible, checkpoint,
                  meshcat) -> List[RunResult]:
    loop = build_closed_loop(controller, *scenarios)
    live_view = loop.robot.LiveView(loop, meshcat) if meshcat is not None else None
    simulator = loop.CreateSimulator()
    context = simulator.get_mutable_context()
    plant = loop.plant
    plant_context = plant.GetMyContextFromRoot(context)
    truth = loop.systems["true_rhs"]
    watched = [(coordinates, robot.Clearance(), robot.LimitViolation())
               for coordinates, robot in zip(trial_coordinates(plant), loop.robots)]
    stops = [None] * len(watched)        # (reason, time) of each stopped trial

    def check(t: float):
        """Stops trials that must stop at t (_TrialStop) or went unsound before it
        (TrueRhsSystem.Unsound); the reason to stop the run, once none runs."""
        x = plant_context.get_continuous_state_vector().CopyToVector()
        unsound = truth.Unsound()
        for i, (coordinates, clearance, limits) in enumerate(watched):
            if stops[i] is not None:
                continue
            if i in unsound:
                stops[i] = unsound[i]
            else:
                reason = _TrialStop(x, coordinates, clearance, limits, t)
                stops[i] = (reason, t) if reason else None
            if stops[i] is not None:
                if any(stop is None for stop in stops):
                    _Freeze(plant, plant_context, coordinates, scenarios[i].q0)
                    truth.Stop(truth.GetMyMutableContextFromRoot(context), i)
        if all(stop is not None for stop in stops):
            return stops[0][0] if len(stops) == 1 else "every trial stopped"
        return None

    simulator.Initialize()
    start = time.perf_counter()
    bar = progress_bar(duration, f"{controller:>11s}", "s", enabled=progress)
    handle_term = interruptible and threading.current_thread() is threading.main_thread()
    previous_term = signal.signal(signal.SIGTERM, _RaiseTerminated) if handle_term else None
    interrupted = False

    def results(status: str, reason: str) -> List[RunResult]:
        """Each trial's result: a stopped trial's reason and time, else the run's."""
        logs, wall = collect_logs(loop, context), time.perf_counter() - start
        memory = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        out = []
        for i, (stop, (coordinates, _, _)) in enumerate(zip(stops, watched)):
            final = context.get_time() if stop is None else stop[1]
            out.append(RunResult(
                controller=controller,
                status=status if stop is None else "diverged",
                reason=reason if stop is None else stop[0], final_time=final,
                wall_time=wall, logs=trial_logs(loop, logs, coordinates, i, final),
                peak_memory_mib=memory, duration=duration, scenario=loop.scenarios[i]))
        return out

    def result(status: str, reason: str) -> RunResult:
        return results(status, reason)[0]

    last_checkpoint = start

    def after_chunk(last: bool) -> None:
        nonlocal last_checkpoint
        if live_view is not None:
            live_view.Update(context)
        bar.update(context.get_time() - bar.n)
        if checkpoint and time.perf_counter() - last_checkpoint >= checkpoint[0] \
                and not last:
            checkpoint[1](result("incomplete", "checkpoint at t = "
                                 f"{context.get_time():.4f} s; the run had not "
                                 "finished"))
            last_checkpoint = time.perf_counter()

    def recover(snapshot: Context) -> bool:
        """After a failed step of a batch: back to the last step's end, the trials
        whose state went unsound stopped there (check), the logs cut to that time;
        False (the run ends) when no trial newly went unsound or none runs on."""
        unsound = truth.Unsound()
        if not any(stops[i] is None for i in unsound):
            return False
        context.SetTimeStateAndParametersFrom(snapshot)
        _CutLogs(loop, context, snapshot.get_time())
        if check(snapshot.get_time()):
            return False
        simulator.Initialize(InitializeParams(suppress_initialization_events=True))
        return True

    reason = ""
    try:
        reason = (advance_in_chunks(simulator, duration, check, after_chunk,
                                    recover=recover) if len(watched) > 1 else
                  advance_in_chunks(simulator, duration, check, after_chunk))
        if reason and not all(stops):     # the simulation failed: every trial stops,
            unsound = truth.Unsound()     # one whose state went unsound with its reason
            stops = [stop or unsound.get(i) or (reason, context.get_time())
                     for i, stop in enumerate(stops)]
    except BaseException as e:
        interruption = _Interruption(e)
        if interruption is None:
            raise
        if not interruptible:
            raise interruption from None
        interrupted = True
        source = "SIGTERM" if isinstance(interruption, _Terminated) else "SIGINT"
        reason = f"interrupted by {source} at t = {context.get_time():.4f} s"
    finally:
        bar.close()
        if handle_term:
            signal.signal(signal.SIGTERM, previous_term)
    return results("interrupted" if interrupted else "diverged" if reason else "ok",
                   reason)


def _Interruption(error: BaseException) -> Optional[KeyboardInterrupt]:
    """The KeyboardInterrupt behind ``error`` (itself, or the cause of numba's or
    pybind11's error made of it), or None."""
    while error is not None:
        if isinstance(error, KeyboardInterrupt):
            return error
        error = error.__cause__ or error.__context__
    return None


def _Freeze(plant, plant_context, coordinates: ArmCoordinates, q0) -> None:
    """A stopped trial at rest: velocities zero, non-finite positions at q0."""
    x = plant_context.get_continuous_state_vector().CopyToVector()
    nq = plant.num_positions()
    positions, velocities = x[:nq], x[nq:]
    velocities[np.concatenate([coordinates.base_v, coordinates.joint_v])] = 0.0
    if not np.all(np.isfinite(positions[np.concatenate([coordinates.base_q,
                                                        coordinates.joint_q])])):
        positions[coordinates.base_q] = coordinates.base_origin
        positions[coordinates.joint_q] = q0
    plant.SetPositionsAndVelocities(plant_context, np.concatenate([positions,
                                                                   velocities]))


def advance_in_chunks(simulator: Simulator, duration: float,
                      check: Callable[[float], Optional[str]],
                      after_chunk: Callable[[bool], None],
                      recover: Optional[Callable[[Context], bool]] = None) -> str:
    """Advances a simulator in steps of MONITOR_PERIOD; returns why the run stopped early
    (a RuntimeError or failed Drake assertion), or "" at ``duration``.

    Args:
        simulator: The Drake Simulator.
        duration: Where to stop [s].
        check: ``check(t)`` after each step: the reason to stop, or None.
        after_chunk: ``after_chunk(last)`` after each step (last: the final one).
        recover: For a batch: ``recover(snapshot)`` after a failed step (snapshot: the last
            step's end); True when it restored it and stopped the trials at fault, so the
            step is taken again (None: a failed step ends the run)."""
    context = simulator.get_context()
    snapshot = context.Clone() if recover is not None else None
    chunks = max(1, int(np.ceil(duration / MONITOR_PERIOD - 1e-9)))
    k = 1
    while k <= chunks:
        failure = _FailedStep(simulator, min(k * MONITOR_PERIOD, duration))
        if failure:
            if snapshot is not None and recover(snapshot):
                continue
            return failure
        reason = check(context.get_time())
        if reason:
            return reason
        if snapshot is not None:
            snapshot.SetTimeStateAndParametersFrom(context)
        after_chunk(k == chunks)
        k += 1
    return ""


def _FailedStep(simulator: Simulator, t: float) -> str:
    """Advances the simulator to t: "" or why it failed (RuntimeError or SystemExit)."""
    try:
        simulator.AdvanceTo(t)
    except RuntimeError as e:
        if _Interruption(e) is not None:
            raise
        return str(e).splitlines()[0]
    except SystemExit as e:
        if not str(e).startswith("Failure at "):
            raise
        return (f"Drake stopped the simulation at t = "
                f"{simulator.get_context().get_time():.4f} s ({str(e).splitlines()[0]})")
    return ""


def _CutLogs(loop: ClosedLoop, context: Context, t: float) -> None:
    """Drops every logger's samples from t on (a failed batch step is retaken)."""
    for logger in loop.loggers.values():
        log = logger.FindMutableLog(context)
        times, data = log.sample_times().copy(), log.data().copy()
        log.Clear()
        for k in np.flatnonzero(times < t):
            log.AddData(times[k], data[:, k])


def collect_logs(loop: ClosedLoop, context: Context) -> Dict[str, np.ndarray]:
    """Every logger's samples of a closed loop, signal name -> samples (T x k), with "time",
    cut to the samples all loggers hold (a run stopped mid-publish has some one ahead).

    Args:
        loop: The closed_loop.ClosedLoop.
        context: Its simulator's root context."""
    logs, times = {}, None
    for name, logger in loop.loggers.items():
        log = logger.FindLog(context)
        logs[name] = log.data().T
        times = log.sample_times() if times is None else times
    count = min(len(data) for data in logs.values())
    logs = {name: data[:count].copy() for name, data in logs.items()}
    logs["time"] = times[:count].copy()
    return logs


def trial_logs(loop: ClosedLoop, logs: Dict[str, np.ndarray], coordinates: ArmCoordinates,
               trial: int, final_time: float) -> Dict[str, np.ndarray]:
    """One trial's part of a batch's logs: its plant state laid out as its own plant's
    ([positions, velocities]) and its share of every stacked signal.

    Args:
        loop: The batch's closed_loop.ClosedLoop.
        logs: The batch's logs.
        coordinates: The trial's coordinates in the batch's plant (plant.trial_coordinates).
        trial: The trial's index.
        final_time: The trial's last time [s] (a trial that stopped early is cut)."""
    nq, count = loop.plant.num_positions(), loop.trials
    kept = logs["time"] <= final_time
    solo = ArmCoordinates.FromPlant(loop.robots[trial].model.plant)
    state = np.empty(solo.plant_positions + len(solo.base_v) + solo.num_joints, int)
    state[solo.base_q], state[solo.joint_q] = coordinates.base_q, coordinates.joint_q
    state[solo.plant_positions + solo.base_v] = nq + coordinates.base_v
    state[solo.plant_positions + solo.joint_v] = nq + coordinates.joint_v
    out = {}
    for name, data in logs.items():
        data = data[kept]
        if name == "time":
            out[name] = data
        elif name == "state":
            out[name] = data[:, state]
        else:
            out[name] = data.reshape(len(data), count, -1)[:, trial].copy()
    return out
