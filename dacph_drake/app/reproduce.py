"""Reproducing the paper: DAC, dac-nominal and the model-based baseline on one scenario,
the six panels, the metrics table beside the paper's values and the ablation table."""
import json
import multiprocessing
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Union


from dacph_drake.controllers import (BASELINE, NAMES as CONTROLLERS,  # reproduce()
                                     REFERENCE)                         # runs them all
from dacph_drake.scenario.errors import ConfigError
from dacph_drake.app.figures import plot_panels
from dacph_drake.loop.metrics import (PHASE_NAMES, PHASES, RunMetrics, comparison,
                                          run_metrics)
from dacph_drake.loop.simulate import simulate
from dacph_drake.atomic_files import prepare_out_dir
from dacph_drake.loop.run_store import (load_logs, load_run_meta, require_run_files,
                                        require_run_of, versions)
from dacph_drake.scenario import Scenario
from dacph_drake.assembly.scenario_files import load_saved_scenario, save_scenario

REQUIRED = (REFERENCE, BASELINE)       # report() also reads directories without
#                                        the other controllers' runs


@dataclass(frozen=True)
class TableRow:
    """One row of the metrics table: this project's value beside the paper's.

    Attributes:
        key: A key of the metrics dictionaries (flat_metrics).
        label: The row's label.
        unit: The value's unit ("%", "-", "samples" or a physical unit).
        paper: The paper's value, where it reports one.
        target: "<= x" / ">= x": the acceptance bound ("": none)."""
    key: str            # a key of the metrics dictionaries
    label: str
    unit: str
    paper: Optional[float] = None       # the paper's value, where it reports one
    target: str = ""                    # "<= x" / ">= x": the acceptance bound


# The paper's numbers (section "Simulations and Validations") and the metrics of
# this project adds.
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


@dataclass(frozen=True)
class AblationRow:
    """One row of the ablation table.

    Attributes:
        key: "CONTROLLER.NAME", looked up as "CONTROLLER.phaseK.NAME" for each phase.
        label: The row's label.
        unit: The value's unit.
        over: Another key: the row is ``key``'s ratio to it in the same phase (None: none).
    """
    key: str
    label: str
    unit: str
    over: Optional[str] = None


def ablation_rows(metrics: Dict[str, Dict[str, float]]) -> List[AblationRow]:
    """The ablation table's rows for the controllers that ran: each one's tracking error;
    with an RHS loop its e_tau, DAC's over it, and chi; then DAC's learner rows.

    Args:
        metrics: Controller -> its run's metrics (run_metrics), for those that ran."""
    ran = [c for c in CONTROLLERS if c in metrics]
    rhs_loop = [c for c in ran if f"{PHASES[0]}.chi_rms" in metrics[c]]
    label = {c: "DAC" if c == REFERENCE else c for c in ran}
    rows = [AblationRow(f"{c}.tracking_error_rms", f"RMS alpha~, {label[c]}", "rad")
            for c in ran]
    rows += [AblationRow(f"{c}.e_tau_rms", f"RMS ||e_tau||, {label[c]}", "N m")
             for c in rhs_loop]
    rows += [AblationRow(f"{REFERENCE}.e_tau_rms",
                         f"RMS ||e_tau||, {label[REFERENCE]} / {c}", "-",
                         over=f"{c}.e_tau_rms") for c in rhs_loop
             if c != REFERENCE and REFERENCE in ran]
    rows += [AblationRow(f"{c}.chi_rms", f"RMS chi, {label[c]}", "N m") for c in rhs_loop]
    return rows + list(LEARNER_ROWS)


LEARNER_ROWS = (
    AblationRow("dac.B_error", "B error, learned", "-"),
    AblationRow("dac.B_error_nominal", "B error, nominal prior B0", "-"),
    AblationRow("dac.B_error_ratio", "B error, learned / nominal", "-"),
    AblationRow("dac.D_error", "D error, learned", "-"),
    AblationRow("dac.D_error_nominal", "D error, nominal prior D0", "-"),
    AblationRow("dac.D_error_ratio", "D error, learned / nominal", "-"),
    AblationRow("dac.rejected_share", "rejected B_hat, DAC", "%"),
    AblationRow("dac.beta_clipped_share", "beta_hat above rhs.beta_max, DAC", "%"),
)


def flat_metrics(metrics: Dict[str, Dict[str, float]]) -> Dict[str, float]:
    """The comparison's metrics, DAC's estimation errors, all as "CONTROLLER.NAME".

    Args:
        metrics: Controller (REQUIRED ones at least) -> its run's metrics."""
    out = dict(comparison(metrics[REFERENCE], metrics[BASELINE]))
    out["estimation_error_B"] = metrics[REFERENCE]["estimation_error_B"]
    out["estimation_error_D"] = metrics[REFERENCE]["estimation_error_D"]
    for controller, values in metrics.items():
        out.update({f"{controller}.{k}": v for k, v in values.items()})
    return out


def metrics_table(metrics: Dict[str, Dict[str, float]]) -> List[Dict]:
    """One row (metric, key, unit, paper, this_project, target) per TableRow.

    Args:
        metrics: Controller -> its run's metrics (run_metrics)."""
    flat = flat_metrics(metrics)
    return [{"metric": r.label, "key": r.key, "unit": r.unit, "paper": r.paper,
             "this_project": flat[r.key], "target": r.target} for r in PAPER_ROWS]


def ablation_table(metrics: Dict[str, Dict[str, float]]) -> List[Dict]:
    """The ablation_rows whose controllers ran (metric, key, over, unit, phases).

    Args:
        metrics: Controller -> its run's metrics (run_metrics)."""
    flat = {f"{c}.{k}": v for c, values in metrics.items() for k, v in values.items()}
    rows = []
    for r in ablation_rows(metrics):
        controller, name = r.key.split(".", 1)
        if controller not in metrics or (r.over and r.over.split(".")[0] not in metrics):
            continue
        values = []
        for phase in PHASES:
            value = flat[f"{controller}.{phase}.{name}"]
            if r.over:
                over_controller, over_name = r.over.split(".", 1)
                value = value / flat[f"{over_controller}.{phase}.{over_name}"]
            values.append(value)
        rows.append({"metric": r.label, "key": r.key, "over": r.over, "unit": r.unit,
                     "phases": values})
    return rows


def ablation_markdown(rows: List[Dict], title: str) -> str:
    """A Markdown table of per-phase ablation rows.

    Args:
        rows: The rows (ablation_table): metric, phase 1, phase 2, phase 3.
        title: The table's heading."""
    lines = [f"## {title}", "", "| metric | phase 1 (linear) | phase 2 (+ nonlinear) | "
             "phase 3 (+ disturbance) |", "|---|---|---|---|"]
    for row in rows:
        metric = row["metric"].replace("|", "\\|")
        lines.append(f"| {metric} | " + " | ".join(
            format_value(v, row["unit"], NOT_REACHED) for v in row["phases"]) + " |")
    return "\n".join(lines) + "\n"


NOT_REACHED = "n/a (phase not reached)"


def format_value(value: Optional[float], unit: str, missing: str = "n/a") -> str:
    """``value`` with its unit, as text (4 significant digits).

    Args:
        value: The value; None: "not reported".
        unit: Its unit ("%": shown in percent; "samples": a count; "-": none).
        missing: The text for NaN (no samples to compute it from)."""
    if value is None:
        return "not reported"
    if value != value:
        return missing
    if unit == "%":
        return f"{100 * value:+.2f} %" if value < 0 else f"{100 * value:.2f} %"
    if unit == "samples":
        return f"{value:.0f}"
    return f"{value:.4g}" if unit == "-" else f"{value:.4g} {unit}"


def table_markdown(rows: List[Dict], title: str) -> str:
    """A Markdown table of the metrics table's rows.

    Args:
        rows: The rows (metrics_table): metric, the paper's value, this project's, target.
        title: The table's heading."""
    lines = [f"## {title}", "", "| metric | paper | this project | target |",
             "|---|---|---|---|"]
    for row in rows:
        metric = row["metric"].replace("|", "\\|")      # a literal | in a cell
        lines.append(f"| {metric} | {format_value(row['paper'], row['unit'])} | "
                     f"{format_value(row['this_project'], row['unit'])} | {row['target']} |")
    return "\n".join(lines) + "\n"


def check_runs_belong_together(run_dir: Path, scenario: Scenario,
                               runs: Dict[str, Dict]) -> None:
    """Requires that a directory's runs share the scenario and duration (if recorded).

    Args:
        run_dir: The run directory (for the messages).
        scenario: The directory's scenario (its scenario.yaml).
        runs: Controller -> its run's metadata (its run_CONTROLLER.json).

    Raises:
        ConfigError: A run was made from another scenario, or the runs' durations differ."""
    for controller, run in runs.items():
        require_run_of(scenario, run, run_dir, controller)
    durations = {c: run["duration"] for c, run in runs.items() if "duration" in run}
    if len(set(durations.values())) > 1:
        listed = ", ".join(f"{c} {d:g} s" for c, d in durations.items())
        raise ConfigError(f"{run_dir}: the runs have different durations ({listed}); "
                          "allowed: runs of one duration in one directory")


def runs_in(run_dir: Union[str, Path]) -> List[str]:
    """The registered controllers with a run in a directory, in the registry's order.

    Args:
        run_dir: The run directory."""
    return [c for c in CONTROLLERS if (Path(run_dir) / f"logs_{c}.npz").exists()
            or (Path(run_dir) / f"run_{c}.json").exists()]


def report(run_dir: Union[str, Path], controllers: Optional[List[str]] = None,
           formats: Sequence[str] = ("png", "pdf")) -> Dict:
    """Writes the panels and tables of a directory's runs (figures/, metrics.md,
    ablation.md, metrics.json); returns metrics.json's summary. DAC's and the baseline's
    runs are set beside the paper's numbers; a run alone gets its per-phase metrics.

    Args:
        run_dir: The runs' directory (saved by dacph simulate or reproduce).
        controllers: The runs to report (default: every run in it, runs_in).
        formats: The panels' file formats (plot_panels).

    Raises:
        ConfigError: A required file is missing or damaged, or the runs do not belong
            together."""
    controllers = controllers or runs_in(run_dir) or [REFERENCE]
    run_dir = require_run_files(run_dir, controllers)
    scenario = load_saved_scenario(run_dir / "scenario.yaml")
    runs = {c: load_run_meta(run_dir, c) for c in controllers}
    check_runs_belong_together(run_dir, scenario, runs)
    logs = {c: load_logs(run_dir, c, scenario) for c in controllers}
    metrics = {c: run_metrics(logs[c], scenario) for c in controllers}
    compared = all(c in metrics for c in REQUIRED)
    rows = metrics_table(metrics) if compared else []
    ablation = ablation_table(metrics)
    figures = plot_panels(logs, scenario, run_dir / "figures", formats)
    summary = {"scenario": "scenario.yaml", "duration": scenario.duration,
               "runs": runs, "table": rows, "ablation": ablation, "metrics": metrics,
               "figures": [str(p.relative_to(run_dir)) for p in figures],
               "versions": versions()}
    (run_dir / "metrics.json").write_text(json.dumps(summary, indent=2))
    status = ", ".join(f"{c}: {runs[c]['status']} in {runs[c].get('wall_time', 0):.0f} s "
                       "wall" for c in controllers)
    (run_dir / "metrics.md").write_text(table_markdown(
        rows, f"DAC-pH against the paper ({scenario.duration:g} s scenario; {status})")
        if compared else phase_metrics_markdown(metrics, scenario, status))
    (run_dir / "ablation.md").write_text(ablation_markdown(
        ablation, f"Learning per phase: {', '.join(controllers)} "
                  f"({scenario.duration:g} s scenario)"))
    return summary


def phase_metrics_markdown(metrics: Dict[str, Dict[str, float]], scenario: Scenario,
                           status: str) -> str:
    """A Markdown table of each run's metrics by phase, with units (RunMetrics).

    Args:
        metrics: Controller -> its run's metrics (run_metrics).
        scenario: The scenario the runs ran.
        status: The runs' status, for the heading."""
    records = {c: RunMetrics.FromFlat(values) for c, values in metrics.items()}
    lines = [f"## Metrics per phase ({scenario.duration:g} s scenario; {status})", "",
             "| metric | unit | " + " | ".join(
                 f"{c}, {phase}" for c in records for phase in PHASE_NAMES.values())
             + " |", "|---|---|" + "---|" * len(records) * len(PHASE_NAMES)]
    first = next(iter(records.values()))
    for name in first.phases[next(iter(PHASE_NAMES.values()))]:
        unit = first.units.get(name, "")
        lines.append(f"| {name} | {unit or '-'} | " + " | ".join(
            format_value(record.phases[phase].get(name), "-", NOT_REACHED)
            for record in records.values() for phase in PHASE_NAMES.values()) + " |")
    return "\n".join(lines) + "\n"


CHECKPOINT_SECONDS = 60.0    # wall time between saves of a run's logs so far


def _simulate_into(scenario: Scenario, controller: str, out: Path) -> str:
    return simulate(scenario, controller, out_dir=out,
                    checkpoint_seconds=CHECKPOINT_SECONDS).status


def reproduce(scenario: Scenario, out_dir: Union[str, Path], progress: bool = True,
              jobs: int = 1) -> Dict:
    """Runs the CONTROLLERS on ``scenario`` and writes the report; returns its summary.

    Args:
        scenario: The scenario.
        out_dir: Where the runs (logs, scenario.yaml, run_*.json) and the report go.
        progress: Show progress bars (with jobs 1).
        jobs: Run the controllers in this many processes (above 1: no progress bars).

    Raises:
        ValueError: jobs is not between 1 and the number of controllers."""
    if jobs not in range(1, len(CONTROLLERS) + 1):
        raise ValueError(f"jobs = {jobs!r}; allowed: 1 to {len(CONTROLLERS)}")
    out = prepare_out_dir(out_dir)
    save_scenario(scenario, out / "scenario.yaml")
    if jobs == 1:
        for controller in CONTROLLERS:
            simulate(scenario, controller, out_dir=out, progress=progress,
                     checkpoint_seconds=CHECKPOINT_SECONDS)
    else:
        with ProcessPoolExecutor(jobs,
                                 mp_context=multiprocessing.get_context("spawn")) as pool:
            list(pool.map(_simulate_into, [scenario] * len(CONTROLLERS), CONTROLLERS,
                          [out] * len(CONTROLLERS)))
    return report(out)
