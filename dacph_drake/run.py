"""Simulating a closed loop of any robot: initial state, divergence monitor,
progress bar, and the run layout: a run directory holds scenario.yaml and, per
controller, logs_CONTROLLER.npz and run_CONTROLLER.json (status, reason, times,
seed, the scenario's fingerprint, versions), all runs of one scenario."""
import fcntl
import hashlib
import json
import os
import platform
import resource
import signal
import threading
import time
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, List, Optional

import numpy as np

from dacph_drake.controllers import build_closed_loop, require_controller
from dacph_drake.errors import ConfigError, require_positive
from dacph_drake.files import replaced_atomically
from dacph_drake.plant import ArmCoordinates
from dacph_drake.progress import progress_bar
from dacph_drake.scenario import Scenario, load_scenario, save_scenario, saved_forms

MAX_JOINT_RATE = 50.0      # [rad/s]: beyond this the run is declared diverged
MONITOR_PERIOD = 0.01      # [s] of simulated time between checks of the plant state


@dataclass
class RunResult:
    controller: str
    status: str                    # "ok", "diverged", "interrupted" or, in a
    #                                checkpoint of a run still going, "incomplete"
    reason: str
    final_time: float
    wall_time: float
    logs: Dict[str, np.ndarray] = field(default_factory=dict)   # name -> (T, k); "time"
    peak_memory_mib: float = float("nan")    # of this process so far (ru_maxrss)
    duration: float = float("nan")           # the duration asked for [s]


def scenario_fingerprint(scenario: Scenario) -> str:
    """A hash of every setting of ``scenario`` (its YAML form): run.json records it,
    so that report() can refuse runs of different scenarios in one directory."""
    return scenario_fingerprints(scenario)[0]


def scenario_fingerprints(scenario: Scenario) -> List[str]:
    """scenario_fingerprint and the fingerprints the same settings had in the older
    layouts a saved run may come from (scenario.saved_forms)."""
    return [hashlib.sha256(text.encode()).hexdigest()[:16]
            for text in saved_forms(scenario)]


def versions() -> Dict[str, str]:
    import drake
    import torch
    out = {"python": platform.python_version(), "numpy": np.__version__,
           "torch": torch.__version__}
    try:
        from importlib.metadata import version
        out["drake"] = version("drake")
    except Exception:   # a source build of drake has no distribution metadata
        out["drake"] = getattr(drake, "__version__", "unknown")
    from dacph_drake import __version__
    out["dacph_drake"] = __version__
    return out


class _Terminated(KeyboardInterrupt):
    """SIGTERM, raised in the main thread while an interruptible run simulates."""


def _RaiseTerminated(signum, frame):
    raise _Terminated()


def prepare_out_dir(out_dir) -> Path:
    """Creates ``out_dir`` and checks that it is a writable directory, before any
    simulation time is spent (ConfigError naming the path otherwise)."""
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise ConfigError(f"--out = {str(out)!r} is an existing file; allowed: a "
                          "directory (created if missing)")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise ConfigError(f"--out = {str(out)!r} cannot be created ({e.strerror}); "
                          "allowed: a writable directory") from e
    if not os.access(out, os.W_OK | os.X_OK):
        raise ConfigError(f"--out = {str(out)!r} is not writable; allowed: a writable "
                          "directory")
    return out


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
        lock = _LockRun(prepare_out_dir(out_dir), controller)
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


def _LockRun(out: Path, controller: str):
    """An exclusive lock on out/.run_CONTROLLER.lock, held while the run simulates
    and saves (ConfigError when another process holds it)."""
    lock = open(out / f".run_{controller}.lock", "w")
    try:
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        lock.close()
        raise ConfigError(f"--out = {str(out)!r}: another process is writing a "
                          f"{controller} run there; allowed: one writer per run")
    return lock


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


def require_run_files(run_dir, controllers) -> Path:
    """ConfigError naming the first file that ``save_run`` would have written for
    ``controllers`` and that run_dir lacks (scenario.yaml, logs_C.npz, run_C.json)."""
    run_dir = Path(run_dir)
    if not run_dir.is_dir():
        raise ConfigError(f"{str(run_dir)!r} is not a directory; allowed: a run "
                          "directory saved by dacph simulate or reproduce")
    names = ["scenario.yaml"] + [f"{kind}_{c}.{ext}" for c in controllers
                                 for kind, ext in (("logs", "npz"), ("run", "json"))]
    for name in names:
        if not (run_dir / name).is_file():
            raise ConfigError(f"{run_dir}: {name} is missing; allowed: a run directory "
                              "saved by dacph simulate or reproduce")
    return run_dir


def save_run(result: RunResult, scenario: Scenario, out_dir, compress: bool = True
             ) -> Path:
    """Writes logs_C.npz, scenario.yaml and run_C.json into out_dir, each replaced
    atomically (a reader or a crash never sees half a file)."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    with replaced_atomically(out / f"logs_{result.controller}.npz") as path, \
            open(path, "wb") as f:
        (np.savez_compressed if compress else np.savez)(f, **result.logs)
    with replaced_atomically(out / "scenario.yaml") as path:
        save_scenario(scenario, path)
    meta = {"controller": result.controller, "status": result.status,
            "reason": result.reason, "final_time": result.final_time,
            "wall_time": result.wall_time, "seed": scenario.seed,
            "duration": result.duration,
            "scenario_fingerprint": scenario_fingerprint(scenario),
            "peak_memory_mib": result.peak_memory_mib,
            "versions": versions()}
    with replaced_atomically(out / f"run_{result.controller}.json") as path, \
            open(path, "w") as f:
        json.dump(meta, f, indent=2)
    return out


def require_one_scenario(out: Path, scenario: Scenario, controller: str) -> None:
    """ConfigError when ``out`` holds a run that a run of ``controller`` on
    ``scenario`` would leave beside runs of another scenario (report() then
    refuses the directory): another controller's run_C.json whose scenario
    fingerprint is not ``scenario``'s, or a run of the layout before one run
    layout (run.json, logs.npz)."""
    if (out / "run.json").is_file() or (out / "logs.npz").is_file():
        raise ConfigError(f"--out = {str(out)!r} holds a run of the older spatial "
                          "layout (run.json, logs.npz); allowed: a directory without it")
    fingerprints = scenario_fingerprints(scenario)
    for path in sorted(out.glob("run_*.json")):
        other = path.stem[len("run_"):]
        if other == controller:
            continue
        try:
            recorded = json.loads(path.read_text()).get("scenario_fingerprint")
        except (OSError, ValueError):
            recorded = None
        if recorded not in fingerprints:
            raise ConfigError(
                f"--out = {str(out)!r} holds a {other} run of another scenario; "
                "allowed: a directory whose runs are of this scenario (runs of one "
                "scenario in one directory), or another directory")


def load_run(run_dir, controller: str):
    """(logs, scenario, run.json contents) of ``controller``'s run saved in run_dir
    (ConfigError naming a missing or damaged file)."""
    run_dir = require_run_files(run_dir, [controller])
    scenario = load_scenario(run_dir / "scenario.yaml")
    return load_logs(run_dir, controller), scenario, load_run_meta(run_dir, controller)


def load_logs(run_dir, controller: str) -> Dict[str, np.ndarray]:
    """logs_CONTROLLER.npz of run_dir (ConfigError naming it when damaged)."""
    path = Path(run_dir) / f"logs_{controller}.npz"
    try:
        with np.load(path) as data:
            return {k: data[k] for k in data.files}
    except (OSError, ValueError, EOFError, zipfile.BadZipFile) as e:
        raise ConfigError(f"{path} is damaged ({type(e).__name__}: {e}); allowed: a "
                          "logs file saved by dacph simulate") from e


def load_run_meta(run_dir, controller: str) -> Dict:
    """run_CONTROLLER.json of run_dir (ConfigError naming it when damaged)."""
    path = Path(run_dir) / f"run_{controller}.json"
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError) as e:
        raise ConfigError(f"{path} is damaged ({e}); allowed: a run file saved by "
                          "dacph simulate") from e
