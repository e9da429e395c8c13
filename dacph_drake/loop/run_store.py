"""The run layout: a run directory holds scenario.yaml and, per controller,
logs_CONTROLLER.npz and run_CONTROLLER.json (status, reason, times, seed, the scenario's
fingerprint, versions); one writer per run (LockRun); files replaced atomically."""
import fcntl
import hashlib
import json
import os
import platform
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from dacph_drake.assembly.registry import task_of
from dacph_drake.scenario.errors import ConfigError
from dacph_drake.atomic_files import read_json_record, replaced_atomically
from dacph_drake.loop.signals import Signals
from dacph_drake.scenario import Scenario
from dacph_drake.assembly.scenario_files import load_saved_scenario, save_scenario, saved_forms


@dataclass
class RunResult:
    """The result of one run (loop.simulate.simulate, simulate_batch).

    Attributes:
        controller: The controller's registered name.
        status: "ok", "diverged", "interrupted" or "incomplete" (a checkpoint's).
        reason: Why the run stopped early ("" when it did not).
        final_time: The simulated time reached [s].
        wall_time: The wall time of the simulation [s] (a batch's share per trial).
        logs: Signal name -> samples (T x k), with "time".
        peak_memory_mib: This process's peak memory so far [MiB] (ru_maxrss).
        duration: The duration asked for [s].
        scenario: The trial's scenario (None: not known, e.g. a file's logs)."""
    controller: str
    status: str
    reason: str
    final_time: float
    wall_time: float
    logs: Dict[str, np.ndarray] = field(default_factory=dict)
    peak_memory_mib: float = float("nan")
    duration: float = float("nan")
    scenario: Optional[Scenario] = None

    @property
    def signals(self) -> Signals:
        """The logs' signals by name (loop.signals.Signals): ``run.signals["e_tau"]``."""
        return Signals(self.logs["time"], [self.logs])

    def to_pandas(self, names: Sequence[str] = ()):
        """The signals as a pandas DataFrame indexed by time (Signals.to_pandas).

        Args:
            names: The signals (none: all)."""
        return self.signals.to_pandas(names)

    def plot(self, *names: str, ax: Optional[object] = None, logy: bool = False) -> object:
        """Plots signals over time (Signals.plot).

        Args:
            *names: The signals.
            ax: A matplotlib Axes (None: a new figure's).
            logy: Absolute values on a log scale."""
        return self.signals.plot(*names, ax=ax, logy=logy)

    @property
    def metrics(self) -> "loop.metrics.RunMetrics":
        """The run's metrics by phase, with units (loop.metrics.RunMetrics)."""
        from dacph_drake.loop.metrics import RunMetrics
        if self.scenario is None:
            raise ValueError("the run's scenario is not known; allowed: a result of "
                             "simulate(), or loop.metrics.RunMetrics.Of(logs, "
                             "scenario)")
        return RunMetrics.Of(self.logs, self.scenario)


def scenario_fingerprint(scenario: Scenario) -> str:
    """A hash (16 hexadecimal digits) of a scenario's YAML form, recorded in run.json so
    that report() can refuse runs of different scenarios in one directory.

    Args:
        scenario: The scenario."""
    return scenario_fingerprints(scenario)[0]


def scenario_fingerprints(scenario: Scenario) -> List[str]:
    """scenario_fingerprint's, then older layouts' (assembly.scenario_files.saved_forms).

    Args:
        scenario: The scenario."""
    return [hashlib.sha256(text.encode()).hexdigest()[:16]
            for text in saved_forms(scenario)]


def versions() -> Dict[str, str]:
    """The versions of Python and the libraries a run depends on, for run.json."""
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


def LockRun(out: Path, controller: str) -> IO:
    """Takes the exclusive lock (flock on out/.run_CONTROLLER.lock, released by the kernel
    however its holder exits) of a controller's run; returns the open lock file.

    Args:
        out: The run directory.
        controller: The controller's name.

    Raises:
        ConfigError: Another process holds it."""
    path = out / f".run_{controller}.lock"
    while True:
        lock = open(path, "a")
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            lock.close()
            raise ConfigError(f"--out = {str(out)!r}: another process is writing a "
                              f"{controller} run there; allowed: one writer per run")
        try:            # the file locked is still the one at path (no ReleaseRun since)
            if os.stat(path).st_ino == os.fstat(lock.fileno()).st_ino:
                return lock
        except FileNotFoundError:
            pass
        lock.close()


def ReleaseRun(lock: IO) -> None:
    """Removes a run's lock file (LockRun), while still held, and releases the lock.

    Args:
        lock: LockRun's open lock file."""
    try:
        os.unlink(lock.name)
    except FileNotFoundError:
        pass
    lock.close()


def require_run_files(run_dir: Union[str, Path], controllers: Sequence[str]) -> Path:
    """Requires the files save_run writes for some controllers; returns run_dir as a Path.

    Args:
        run_dir: The run directory.
        controllers: The controllers' names.

    Raises:
        ConfigError: Naming the first file missing, or run_dir is not a directory."""
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


def save_run(result: RunResult, scenario: Scenario, out_dir: Union[str, Path],
             compress: bool = True) -> Path:
    """Saves logs_C.npz, scenario.yaml and run_C.json atomically; returns out_dir as a Path.

    Args:
        result: The run.
        scenario: Its scenario.
        out_dir: The run directory (created if missing).
        compress: Compress the logs (checkpoints do not, for speed)."""
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


# The files derived from a directory's runs: the report's (app.reproduce.report, of
# every run there), and per controller the HTML replay and verify's report.
REPORT_OUTPUTS = ("metrics.json", "metrics.md", "ablation.md", "figures")
VERIFICATION_OUTPUTS = ("verification.json", "verification.md", "verification.png")


def remove_outputs_of(out: Path, controller: str) -> List[str]:
    """Removes the files a controller's new run makes stale: the report (REPORT_OUTPUTS),
    animation_CONTROLLER.html and verify's report of that controller; returns their names.

    Args:
        out: The run directory.
        controller: The controller whose run is replaced."""
    import shutil
    names = list(REPORT_OUTPUTS) + [f"animation_{controller.replace('-', '_')}.html"]
    try:
        verified = json.loads((out / "verification.json").read_text()).get(
            "controller", "dac")
    except (OSError, ValueError, AttributeError):
        verified = controller           # unreadable: it cannot be told apart
    if verified == controller:
        names += VERIFICATION_OUTPUTS
    removed = []
    for name in names:
        path = out / name
        if path.is_dir():
            shutil.rmtree(path)
        elif path.exists():
            path.unlink()
        else:
            continue
        removed.append(name)
    return removed


def require_one_scenario(out: Path, scenario: Scenario, controller: str) -> None:
    """Refuses, before the run, a directory holding another scenario's run.

    Args:
        out: The run directory.
        scenario: The new run's scenario.
        controller: The new run's controller.

    Raises:
        ConfigError: ``out`` holds another scenario's run, or one of the older layout."""
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


RUN_STATUSES = ("ok", "diverged", "interrupted", "incomplete")   # RunResult.status


def load_run(run_dir: Union[str, Path], controller: str
             ) -> Tuple[Dict[str, np.ndarray], Scenario, Dict]:
    """A saved run checked against scenario.yaml: (logs, scenario, run_C.json).

    Args:
        run_dir: The run directory.
        controller: The run's controller.

    Raises:
        ConfigError: Naming a missing or damaged file, or a run of another scenario."""
    run_dir = require_run_files(run_dir, [controller])
    scenario = load_saved_scenario(run_dir / "scenario.yaml")
    meta = load_run_meta(run_dir, controller)
    require_run_of(scenario, meta, run_dir, controller)
    return load_logs(run_dir, controller, scenario), scenario, meta


def require_run_of(scenario: Scenario, meta: Dict, run_dir: Union[str, Path],
                   controller: str) -> None:
    """Requires that a saved run was made from ``scenario`` (by its recorded fingerprint).

    Args:
        scenario: The directory's scenario (its scenario.yaml).
        meta: The run's record (run_CONTROLLER.json).
        run_dir: The run directory, for the message.
        controller: The run's controller, for the message.

    Raises:
        ConfigError: The run's fingerprint is not one of the scenario's."""
    fingerprints = scenario_fingerprints(scenario)
    if meta.get("scenario_fingerprint", fingerprints[0]) not in fingerprints:
        raise ConfigError(
            f"{run_dir}: the {controller} run was made from another scenario than "
            "scenario.yaml (the file was edited, or the run's files come from another "
            "directory); allowed: runs of one scenario in one directory, with the "
            "scenario.yaml they were saved with")


def load_logs(run_dir: Union[str, Path], controller: str,
              scenario: Optional[Scenario] = None) -> Dict[str, np.ndarray]:
    """Loads a run's logs (logs_CONTROLLER.npz): signal name -> samples.

    Args:
        run_dir: The run directory.
        controller: The run's controller.
        scenario: Its scenario: the logs must then hold its task's signals (time, state,
            u, tau, the task's log), one sample per time.

    Raises:
        ConfigError: Naming the file when it is damaged or lacks a signal."""
    path = Path(run_dir) / f"logs_{controller}.npz"
    try:
        with np.load(path) as data:
            logs = {k: data[k] for k in data.files}
    except (OSError, ValueError, EOFError, zipfile.BadZipFile) as e:
        raise ConfigError(f"{path} is damaged ({type(e).__name__}: {e}); allowed: a "
                          "logs file saved by dacph simulate") from e
    if scenario is not None:
        required = ("time", "state", "u", "tau", task_of(scenario).log_name)
        missing = [name for name in required if name not in logs]
        uneven = [name for name, values in logs.items()
                  if "time" in logs and np.shape(values)[:1] != logs["time"].shape]
        if missing or uneven:
            problem = (f"no {', '.join(missing)}" if missing else
                       f"{', '.join(uneven)} not one sample per time")
            raise ConfigError(f"{path} is damaged ({problem}); allowed: a logs file "
                              "saved by dacph simulate")
    return logs


def load_run_meta(run_dir: Union[str, Path], controller: str) -> Dict:
    """Loads a run's record (run_CONTROLLER.json's contents).

    Args:
        run_dir: The run directory.
        controller: The run's controller.

    Raises:
        ConfigError: Naming the file when it is damaged (an unknown status, a non-numeric
            final time)."""
    path = Path(run_dir) / f"run_{controller}.json"
    meta = read_json_record(path, ("status", "final_time"), "dacph simulate")
    final_time = meta["final_time"]
    if meta["status"] not in RUN_STATUSES or isinstance(final_time, bool) or not (
            isinstance(final_time, (int, float)) and np.isfinite(final_time)):
        raise ConfigError(f"{path} is damaged (status {meta['status']!r}, final_time "
                          f"{final_time!r}); allowed: a file saved by dacph simulate "
                          f"(status one of {', '.join(RUN_STATUSES)})")
    return meta
