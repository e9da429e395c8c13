"""Simulating a closed loop of any robot (controllers.REGISTRY): initial state,
divergence monitor, progress bar, SIGINT/SIGTERM, checkpoints and the saved run
(loop.run_store)."""
import resource
import signal
import threading
import time
from pathlib import Path
from typing import Dict, Optional

import numpy as np

from dacph_drake.controllers import build_closed_loop, require_controller
from dacph_drake.errors import ConfigError, require_positive
from dacph_drake.loop.progress import progress_bar
from dacph_drake.loop.run_store import (LockRun, RunResult, prepare_out_dir,
                                        require_one_scenario, save_run)
from dacph_drake.dynamics.plant import ArmCoordinates
from dacph_drake.scenario import Scenario


MAX_JOINT_RATE = 50.0      # [rad/s]: beyond this the run is declared diverged


MONITOR_PERIOD = 0.01      # [s] of simulated time between checks of the plant state


class _Terminated(KeyboardInterrupt):
    """SIGTERM, raised in the main thread while an interruptible run simulates."""


def _RaiseTerminated(signum, frame):
    raise _Terminated()


def simulate(scenario: Scenario, controller: str = "dac", duration: Optional[float] = None,
             out_dir=None, progress: bool = False, interruptible: bool = False,
             checkpoint_seconds: Optional[float] = None, meshcat=None) -> RunResult:
    """Builds the ``controller`` (controllers.REGISTRY) loop for ``scenario``,
    simulates it for ``duration`` (default: the scenario's) and, when ``out_dir`` is
    given, saves logs.npz, scenario.yaml and run.json there (out_dir is checked
    before the simulation starts and locked against a second writer of the same
    controller; run.json records the duration and scenario_fingerprint). A run
    whose state turns non-finite or whose joint rates exceed MAX_JOINT_RATE stops
    with a reason and still saves what it has. With ``interruptible`` (the CLI's
    single runs), SIGINT and SIGTERM stop the run the same way, with status
    "interrupted"; sweeps and pools leave it off so that an interrupted trial is
    redone on resume. With ``checkpoint_seconds`` and out_dir, the logs so far are
    saved every checkpoint_seconds of wall time with status "incomplete", so that a
    crash or kill -9 loses at most that much (every file is replaced atomically).
    A directory holding another controller's run of another scenario is refused
    (require_one_scenario). With ``meshcat`` (a pydrake Meshcat), the ground truth
    is drawn there while it simulates (robots.Robot.LiveView;
    scenario.simulator.target_realtime_rate paces it); the diagram and the results
    are the same as without."""
    require_controller(controller)
    duration = scenario.duration if duration is None else duration
    require_positive("duration", duration, "s")
    if checkpoint_seconds is not None:
        require_positive("checkpoint_seconds (--checkpoint)", checkpoint_seconds, "s")
    lock = None
    if out_dir is not None:
        lock = LockRun(prepare_out_dir(out_dir), controller)
        try:
            require_one_scenario(Path(out_dir), scenario, controller)
        except ConfigError:
            lock.close()
            raise
    checkpoint = None
    if out_dir is not None and checkpoint_seconds is not None:
        checkpoint = (checkpoint_seconds,
                      lambda partial: save_run(partial, scenario, out_dir, compress=False))
    try:
        result = _Simulate(scenario, controller, duration, progress, interruptible,
                           checkpoint, meshcat)
        if out_dir is not None:
            save_run(result, scenario, out_dir)
    finally:
        if lock is not None:
            lock.close()
    return result


def _Simulate(scenario: Scenario, controller: str, duration: float, progress: bool,
              interruptible: bool, checkpoint=None, meshcat=None) -> RunResult:
    """The run itself; ``checkpoint`` = (wall seconds, save) calls save with the
    partial result that often; ``meshcat`` gets a LiveView."""
    loop = build_closed_loop(controller, scenario)
    live_view = loop.robot.LiveView(loop, meshcat) if meshcat is not None else None
    simulator = loop.CreateSimulator()
    context = simulator.get_mutable_context()
    plant = loop.plant
    plant_context = plant.GetMyContextFromRoot(context)
    coordinates = ArmCoordinates.FromPlant(plant)
    clearance = loop.robot.Clearance()
    limits = loop.robot.LimitViolation()

    def check(t: float):
        """The reason to stop at time t, or None: a non-finite state, a joint rate
        beyond MAX_JOINT_RATE, or a link touching the base where the robot measures
        it (robots.Robot.Clearance: the ground truth has no collision geometry)."""
        x = plant_context.get_continuous_state_vector().CopyToVector()
        if not np.all(np.isfinite(x)):
            return f"non-finite plant state at t = {t:.4f} s"
        _, q, base_velocity, qdot = coordinates.Split(x)
        if max(np.max(np.abs(base_velocity)), np.max(np.abs(qdot))) > MAX_JOINT_RATE:
            return f"runaway: a rate exceeded {MAX_JOINT_RATE} rad/s at t = {t:.4f} s"
        beyond = limits(q) if limits is not None else None
        if beyond:
            return f"joint limit: {beyond} at t = {t:.4f} s"
        rho = clearance(q) if clearance is not None else np.inf
        if rho <= 0:
            return (f"collision: a link touched the base at t = {t:.4f} s (clearance "
                    f"{rho:.4f} m)")
        return None

    simulator.Initialize()
    start = time.perf_counter()
    bar = progress_bar(duration, f"{controller:>11s}", "s", enabled=progress)
    handle_term = interruptible and threading.current_thread() is threading.main_thread()
    previous_term = signal.signal(signal.SIGTERM, _RaiseTerminated) if handle_term else None
    interrupted = False

    def result(status: str, reason: str) -> RunResult:
        return RunResult(controller=controller, status=status, reason=reason,
                         final_time=context.get_time(),
                         wall_time=time.perf_counter() - start,
                         logs=collect_logs(loop, context),
                         peak_memory_mib=resource.getrusage(
                             resource.RUSAGE_SELF).ru_maxrss / 1024,
                         duration=duration)

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

    reason = ""
    try:
        reason = advance_in_chunks(simulator, duration, check, after_chunk)
    except KeyboardInterrupt as e:
        if not interruptible:
            raise
        interrupted = True
        source = "SIGTERM" if isinstance(e, _Terminated) else "SIGINT"
        reason = f"interrupted by {source} at t = {context.get_time():.4f} s"
    finally:
        bar.close()
        if handle_term:
            signal.signal(signal.SIGTERM, previous_term)
    return result("interrupted" if interrupted else "diverged" if reason else "ok",
                  reason)


def advance_in_chunks(simulator, duration: float, check, after_chunk) -> str:
    """Advances ``simulator`` to ``duration`` in steps of MONITOR_PERIOD of simulated
    time; after each, ``check(t)`` gives the reason to stop (or None) and
    ``after_chunk(last)`` runs (last: the final step). Returns why the run stopped
    early (a RuntimeError of the simulation, such as a failed callback, included),
    or "" when it reached ``duration``."""
    context = simulator.get_context()
    chunks = max(1, int(np.ceil(duration / MONITOR_PERIOD - 1e-9)))
    for k in range(1, chunks + 1):
        try:
            simulator.AdvanceTo(min(k * MONITOR_PERIOD, duration))
        except RuntimeError as e:
            return str(e).splitlines()[0]
        reason = check(context.get_time())
        if reason:
            return reason
        after_chunk(k == chunks)
    return ""


def collect_logs(loop, context) -> Dict[str, np.ndarray]:
    """Every logger's samples of a closed_loop.ClosedLoop, with "time", cut to the samples all of them hold: a run stopped
    inside the loggers' publish at one instant (SIGINT, a failed callback) has some
    loggers one sample ahead of the others."""
    logs, times = {}, None
    for name, logger in loop.loggers.items():
        log = logger.FindLog(context)
        logs[name] = log.data().T
        times = log.sample_times() if times is None else times
    count = min(len(data) for data in logs.values())
    logs = {name: data[:count].copy() for name, data in logs.items()}
    logs["time"] = times[:count].copy()
    return logs
