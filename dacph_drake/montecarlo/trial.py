"""One trial, as a worker runs it: plain data in (a scenario with the sample
applied, its seed), one row out. Every trial builds its own diagrams."""
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Dict, List, Optional

from dacph_drake.scenario.errors import ConfigError
from dacph_drake.assembly.registry import validate_scenario
from dacph_drake.scenario import Scenario


@dataclass
class Trial:
    """What a worker receives (picklable, no Drake objects).

    Attributes:
        trial: The trial's id.
        seed: Its seed (definition.trial_seed).
        scenario: Its sampled scenario.
        sampled: The sampled values, by distribution name.
        controllers: The controllers to run.
        log_dir: Save each run's logs under log_dir/trial_NNNNN (None: not saved).
        verify: Verify each run with the RHS integrator (Sweep.verify)."""
    trial: int
    seed: int
    scenario: Scenario
    sampled: Dict[str, object]
    controllers: List[str]
    log_dir: Optional[str] = None
    verify: bool = False


def run_trial(task: Trial) -> Dict:
    """Runs one trial (run_trials of a batch of one); returns its row.

    Args:
        task: The trial."""
    return run_trials([task])[0]


def run_trials(tasks: List[Trial]) -> List[Dict]:
    """Runs each controller on a batch of trials, one diagram per controller, each trial's
    run its solo run. A trial's failure never raises: it is recorded for it alone (a batch
    that raises is rerun trial by trial).

    Args:
        tasks: The batch's trials.

    Returns:
        Each trial's row: trial, seed, sampled, status ("ok"/"failed"), reason, wall_time
            [s] and runs (per controller: status, reason, final_time, wall_time,
            metrics)."""
    import torch
    torch.set_num_threads(1)        # one thread per worker, whatever the executor
    start = time.perf_counter()
    rows, valid = {}, []
    for task in tasks:
        try:
            validate_scenario(task.scenario)
            valid.append(task)
        except ConfigError as e:
            rows[task.trial] = failed_row(task, f"invalid sample: {e}", 0.0)
    from dacph_drake.controllers.closed_loop import DiagramSettings
    runs = {task.trial: {} for task in valid}
    # Trials whose sampled settings shape the diagram (sensing) share it by groups.
    groups: Dict[str, List[Trial]] = {}
    for task in valid:
        groups.setdefault(DiagramSettings(task.scenario), []).append(task)
    for controller in tasks[0].controllers if valid else []:
        for group in groups.values():
            if len(group) == 1:
                _run_one(group[0], controller, runs)
                continue
            try:
                _run_batch(group, controller, runs)
            except Exception:   # noqa: BLE001 -- each trial alone says whose it was
                for task in group:
                    _run_one(task, controller, runs)
    share = (time.perf_counter() - start) / max(1, len(valid))
    for task in valid:
        failures = [f"{c} {r['status']}: {r['reason']}" for c, r in runs[task.trial].items()
                    if r["status"] != "ok"]
        rows[task.trial] = {"trial": task.trial, "seed": task.seed,
                            "sampled": task.sampled,
                            "status": "failed" if failures else "ok",
                            "reason": "; ".join(failures), "wall_time": share,
                            "runs": runs[task.trial]}
    return [rows[task.trial] for task in tasks]


def _run_one(task: Trial, controller: str, runs: Dict) -> None:
    """One trial's run of ``controller`` alone, an exception recorded as its failure."""
    try:
        _run_batch([task], controller, runs)
    except Exception as e:   # noqa: BLE001 -- recorded as the run's failure
        runs[task.trial][controller] = {
            "status": "error", "reason": f"{type(e).__name__}: {e}", "final_time": None,
            "wall_time": None, "metrics": None}


def _run_batch(tasks: List[Trial], controller: str, runs: Dict) -> None:
    """The batch's run of ``controller``: each trial's entry in ``runs``."""
    from dacph_drake.loop.metrics import run_metrics
    from dacph_drake.loop.simulate import simulate_batch
    out_dirs = [Path(task.log_dir) / f"trial_{task.trial:05d}" if task.log_dir else None
                for task in tasks]
    results = simulate_batch([task.scenario for task in tasks], controller,
                             out_dirs=out_dirs)
    for task, result in zip(tasks, results):
        metrics = (run_metrics(result.logs, task.scenario) if result.status == "ok"
                   else None)
        runs[task.trial][controller] = {
            "status": result.status, "reason": result.reason,
            "final_time": result.final_time, "wall_time": result.wall_time / len(tasks),
            "metrics": metrics}
        if task.verify and result.status == "ok" and "rhs_log" in result.logs:
            runs[task.trial][controller]["verify"] = _verdict(result.logs, task.scenario)


def _verdict(logs, scenario: Scenario) -> Dict:
    """dacph verify's verdict on a run (the region of attraction skipped): ok, the
    failed checks, and the delay tolerance."""
    from dacph_drake.loop.verify import verify_logs
    report = verify_logs(logs, scenario, {"status": "ok"}, region_budget=0.0)
    return {"ok": report["ok"],
            "failed": [name for name, check in report["checks"].items()
                       if not check["ok"]],
            "delay_tolerance": report["delay_tolerance"]}


def failed_row(task: Trial, reason: str, wall_time: Optional[float] = None) -> Dict:
    """The row (status "failed") of a trial whose controllers did not run.

    Args:
        task: The trial.
        reason: Why (an invalid sample, or a worker that died running it).
        wall_time: The time spent on it [s], if known."""
    return {"trial": task.trial, "seed": task.seed, "sampled": task.sampled,
            "status": "failed", "reason": reason, "wall_time": wall_time, "runs": {}}

