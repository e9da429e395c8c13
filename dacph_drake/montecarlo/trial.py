"""One trial, as a worker runs it: plain data in (a scenario with the sample
applied, its seed), one row out. Every trial builds its own diagrams."""
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Dict, List, Optional

from dacph_drake.errors import ConfigError
from dacph_drake.scenario import Scenario


@dataclass
class Trial:
    """What a worker receives (picklable, no Drake objects)."""
    trial: int
    seed: int
    scenario: Scenario
    sampled: Dict[str, object]
    controllers: List[str]
    log_dir: Optional[str] = None   # save each run's logs under log_dir/trial_NNNNN


def run_trial(task: Trial) -> Dict:
    """Runs each controller on the trial's scenario and returns the trial's row:
    trial, seed, sampled, status ("ok" or "failed"), reason, wall_time [s] and runs
    (per controller: status "ok" | "diverged" | "error", reason, final_time,
    wall_time, metrics). A trial's own failure never raises: an invalid sampled
    scenario (ConfigError), a divergence or an exception in a run is recorded with
    its reason."""
    import torch
    from dacph_drake.analysis.metrics import run_metrics
    from dacph_drake.loop.simulate import simulate
    torch.set_num_threads(1)        # one thread per worker, whatever the executor
    start = time.perf_counter()
    try:
        task.scenario.Validate()
    except ConfigError as e:
        return failed_row(task, f"invalid sample: {e}", time.perf_counter() - start)
    runs = {}
    for controller in task.controllers:
        out_dir = (Path(task.log_dir) / f"trial_{task.trial:05d}" if task.log_dir
                   else None)
        try:
            result = simulate(task.scenario, controller, out_dir=out_dir)
        except Exception as e:   # noqa: BLE001 -- recorded as the run's failure
            runs[controller] = {"status": "error", "reason": f"{type(e).__name__}: {e}",
                                "final_time": None, "wall_time": None, "metrics": None}
            continue
        metrics = run_metrics(result.logs, task.scenario) if result.status == "ok" else None
        runs[controller] = {"status": result.status, "reason": result.reason,
                            "final_time": result.final_time,
                            "wall_time": result.wall_time, "metrics": metrics}
    failures = [f"{c} {r['status']}: {r['reason']}" for c, r in runs.items()
                if r["status"] != "ok"]
    return {"trial": task.trial, "seed": task.seed, "sampled": task.sampled,
            "status": "failed" if failures else "ok", "reason": "; ".join(failures),
            "wall_time": time.perf_counter() - start, "runs": runs}


def failed_row(task: Trial, reason: str, wall_time: Optional[float] = None) -> Dict:
    """The row of a trial whose controllers did not run (an invalid sample, or a
    worker that died running it)."""
    return {"trial": task.trial, "seed": task.seed, "sampled": task.sampled,
            "status": "failed", "reason": reason, "wall_time": wall_time, "runs": {}}

