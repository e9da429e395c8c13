"""Reproducing the paper: DAC and the model-based baseline on one scenario, the six
panels of SPEC section 10, and the metrics table with the paper's values beside
this project's (SPEC section 9)."""
import json
import multiprocessing
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Dict, List, Optional

import numpy as np

from dacph_drake.figures import plot_panels
from dacph_drake.metrics import comparison, run_metrics
from dacph_drake.run import simulate, versions
from dacph_drake.scenario import Scenario, load_scenario, save_scenario

CONTROLLERS = ("dac", "model-based")


@dataclass(frozen=True)
class TableRow:
    key: str            # a key of the metrics dictionaries
    label: str
    unit: str
    paper: Optional[float] = None       # the paper's value, where it reports one
    target: str = ""                    # "<= x" / ">= x": the acceptance bound


# The paper's numbers (section "Simulations and Validations") and the metrics of
# SPEC section 9 it does not report.
PAPER_ROWS = (
    TableRow("tracking_error_reduction", "tracking-error reduction 1 - e_DAC/e_MB", "%",
             0.775, ">= 77.5 %"),
    TableRow("control_effort_increase", "control-effort increase", "%", 0.16, "<= 16 %"),
    TableRow("estimation_error_B", "relative estimation error of B (end of phase 2)", "%",
             0.63, "<= 63 %"),
    TableRow("estimation_error_D", "relative estimation error of D (end of phase 2)", "%",
             0.30, "<= 30 %"),
    TableRow("tracking_error_reduction_phase3", "tracking-error reduction in phase 3",
             "%"),
    TableRow("dac.tracking_error_rms", "RMS alpha~, DAC", "rad"),
    TableRow("model-based.tracking_error_rms", "RMS alpha~, model-based", "rad"),
    TableRow("dac.control_effort_rms", "RMS ||u||, DAC", "N m"),
    TableRow("model-based.control_effort_rms", "RMS ||u||, model-based", "N m"),
    TableRow("dac.e_tau_rms", "RMS ||e_tau||, DAC", "N m"),
    TableRow("dac.sliding_rms", "RMS ||s||, DAC", "rad/s"),
    TableRow("model-based.sliding_rms", "RMS ||s||, model-based", "rad/s"),
    TableRow("dac.base_attitude_max_excursion", "max base-attitude excursion, DAC", "rad"),
    TableRow("dac.min_clearance", "min arm-to-base clearance, DAC", "m"),
    TableRow("model-based.min_clearance", "min arm-to-base clearance, model-based", "m"),
    TableRow("dac.c_min_over_bound", "min c / c_min (eq. 48), DAC", "-"),
    TableRow("dac.rejected_estimates", "log samples with a rejected B_hat (DIC/trust)",
             "samples"),
)


def flat_metrics(metrics: Dict[str, Dict[str, float]]) -> Dict[str, float]:
    """{"dac": {...}, "model-based": {...}} -> comparison keys plus "dac.x" keys."""
    out = dict(comparison(metrics["dac"], metrics["model-based"]))
    out["estimation_error_B"] = metrics["dac"]["estimation_error_B"]
    out["estimation_error_D"] = metrics["dac"]["estimation_error_D"]
    for controller, values in metrics.items():
        out.update({f"{controller}.{k}": v for k, v in values.items()})
    return out


def metrics_table(metrics: Dict[str, Dict[str, float]]) -> List[Dict]:
    """One row per TableRow with this project's value beside the paper's."""
    flat = flat_metrics(metrics)
    return [{"metric": r.label, "key": r.key, "unit": r.unit, "paper": r.paper,
             "this_project": flat[r.key], "target": r.target} for r in PAPER_ROWS]


def format_value(value, unit: str) -> str:
    if value is None:
        return "not reported"
    if unit == "%":
        return f"{100 * value:+.2f} %" if value < 0 else f"{100 * value:.2f} %"
    if unit == "samples":
        return f"{value:.0f}"
    return f"{value:.4g} {unit}"


def table_markdown(rows: List[Dict], title: str) -> str:
    lines = [f"## {title}", "", "| metric | paper | this project | target |",
             "|---|---|---|---|"]
    for row in rows:
        metric = row["metric"].replace("|", "\\|")      # a literal | in a cell
        lines.append(f"| {metric} | {format_value(row['paper'], row['unit'])} | "
                     f"{format_value(row['this_project'], row['unit'])} | {row['target']} |")
    return "\n".join(lines) + "\n"


def load_logs(run_dir, controller: str) -> Dict[str, np.ndarray]:
    with np.load(Path(run_dir) / f"logs_{controller}.npz") as data:
        return {k: data[k] for k in data.files}


def report(run_dir) -> Dict:
    """Panels and table for a directory holding both runs (as ``reproduce`` or two
    ``dacph simulate`` calls leave it). Writes figures/, metrics.md, metrics.json."""
    run_dir = Path(run_dir)
    scenario = load_scenario(run_dir / "scenario.yaml")
    logs = {c: load_logs(run_dir, c) for c in CONTROLLERS}
    runs = {c: json.loads((run_dir / f"run_{c}.json").read_text()) for c in CONTROLLERS}
    metrics = {c: run_metrics(logs[c], scenario) for c in CONTROLLERS}
    rows = metrics_table(metrics)
    figures = plot_panels(logs["dac"], logs["model-based"], scenario, run_dir / "figures")
    summary = {"scenario": "scenario.yaml", "duration": scenario.duration,
               "runs": runs, "table": rows, "metrics": metrics,
               "figures": [str(p.relative_to(run_dir)) for p in figures],
               "versions": versions()}
    (run_dir / "metrics.json").write_text(json.dumps(summary, indent=2))
    status = ", ".join(f"{c}: {runs[c]['status']} in {runs[c]['wall_time']:.0f} s wall"
                       for c in CONTROLLERS)
    (run_dir / "metrics.md").write_text(table_markdown(
        rows, f"DAC-pH against the paper ({scenario.duration:g} s scenario; {status})"))
    return summary


def _simulate_into(scenario: Scenario, controller: str, out: Path) -> str:
    return simulate(scenario, controller, out_dir=out).status


def reproduce(scenario: Scenario, out_dir, progress: bool = True, jobs: int = 1) -> Dict:
    """Runs both controllers on ``scenario`` into out_dir (logs, scenario.yaml,
    run_*.json with versions and seed), then writes the panels and the table.
    jobs = 2 runs the two controllers in two processes (no progress bars)."""
    if jobs not in (1, 2):
        raise ValueError(f"jobs = {jobs!r}; allowed: 1 or 2")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    save_scenario(scenario, out / "scenario.yaml")
    if jobs == 1:
        for controller in CONTROLLERS:
            simulate(scenario, controller, out_dir=out, progress=progress)
    else:
        with ProcessPoolExecutor(len(CONTROLLERS),
                                 mp_context=multiprocessing.get_context("spawn")) as pool:
            list(pool.map(_simulate_into, [scenario] * 2, CONTROLLERS, [out] * 2))
    return report(out)
