"""What a sweep's rows say: per-controller quantiles and success rates, the paired
DAC-vs-baseline improvement with a bootstrap interval, a flat table (Parquet), plots."""
import json
from pathlib import Path
from typing import Dict, List, Union

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from dacph_drake.loop.metrics import PHASES, comparison  # noqa: E402
from dacph_drake.controllers import ABLATION, BASELINE, REFERENCE  # noqa: E402
from dacph_drake.montecarlo.definition import SweepDefinition  # noqa: E402
from dacph_drake.montecarlo.store import read_manifest, read_rows, sorted_rows  # noqa: E402

QUANTILES = (0.05, 0.25, 0.5, 0.75, 0.95)
BOOTSTRAP_RESAMPLES = 2000
PLOTTED_METRICS = ("tracking_error_rms", "tracking_error_rms_phase3", "control_effort_rms",
                   "e_tau_rms", "sliding_rms", "min_clearance")
SENSITIVITY_METRIC = "tracking_error_rms"


def flat_row(row: Dict) -> Dict:
    """A row as one level of columns: trial, seed, status, reason, wall_time,
    sampled.NAME[k], CONTROLLER.status/reason/final_time/wall_time and CONTROLLER.METRIC.

    Args:
        row: A trial's row (rows.jsonl)."""
    out = {k: row[k] for k in ("trial", "seed", "status", "reason", "wall_time")}
    for name, value in row["sampled"].items():
        if isinstance(value, list):
            out.update({f"sampled.{name}[{k}]": v for k, v in enumerate(value)})
        else:
            out[f"sampled.{name}"] = value
    for controller, run in row["runs"].items():
        for key in ("status", "reason", "final_time", "wall_time"):
            out[f"{controller}.{key}"] = run[key]
        for metric, value in (run["metrics"] or {}).items():
            out[f"{controller}.{metric}"] = value
    return out


def summarize(rows: List[Dict], controllers: List[str], seed: int) -> Dict:
    """Summarizes a sweep's rows (summary.json): success rates, quantiles of each metric
    over the successful runs, and the paired DAC vs model-based comparison with a 95 %
    bootstrap interval of the mean.

    Args:
        rows: The trials' rows, in trial order.
        controllers: The controllers the sweep runs.
        seed: The sweep's seed, for the bootstrap's resampling."""
    summary = {"trials": len(rows), "succeeded": sum(r["status"] == "ok" for r in rows),
               "controllers": {}, "paired": {},
               "failures": [{"trial": r["trial"], "reason": r["reason"]}
                            for r in rows if r["status"] != "ok"]}
    summary["success_rate"] = summary["succeeded"] / max(len(rows), 1)
    for controller in controllers:
        ok = [r["runs"][controller]["metrics"] for r in rows
              if r["runs"].get(controller, {}).get("status") == "ok"]
        names = list(dict.fromkeys(k for metrics in ok for k in metrics))
        summary["controllers"][controller] = {
            "succeeded": len(ok), "success_rate": len(ok) / max(len(rows), 1),
            "metrics": {name: _quantiles([m[name] for m in ok]) for name in names}}
    if REFERENCE in controllers:
        summary["learning"] = learning_summary(rows)
    if {REFERENCE, ABLATION} <= set(controllers):
        summary["learning_in_tracking"] = tracking_summary(rows)
    if {REFERENCE, BASELINE} <= set(controllers):
        pairs = [comparison(r["runs"][REFERENCE]["metrics"], r["runs"][BASELINE]["metrics"])
                 for r in rows if r["runs"].get(REFERENCE, {}).get("status") == "ok"
                 and r["runs"].get(BASELINE, {}).get("status") == "ok"]
        rng = np.random.default_rng(seed)
        for name in (pairs[0] if pairs else {}):
            summary["paired"][name] = _mean_interval([p[name] for p in pairs], rng)
    return summary


def learning_summary(rows: List[Dict]) -> Dict:
    """Per phase: how often learned B, D beat the prior, the ratios' median and 95 %
    quantile, the share of B_hat rejected, median RMS e_tau with and without learning.

    Args:
        rows: The trials' rows."""
    ok = [r for r in rows if r["runs"].get(REFERENCE, {}).get("status") == "ok"]
    runs = [r["runs"][REFERENCE]["metrics"] for r in ok]
    nominal = [(r["runs"][REFERENCE]["metrics"], r["runs"][ABLATION]["metrics"])
               for r in ok if r["runs"].get(ABLATION, {}).get("status") == "ok"]
    out = {"trials": len(runs), "phases": {}}
    if not runs:
        return out
    for phase in PHASES:
        entry = {}
        for name in ("B", "D", "B_scaled", "D_scaled"):
            key = f"{phase}.{name[0]}_error_ratio" + name[1:]
            if key not in runs[0]:
                continue
            ratios = np.array([m[key] for m in runs], float)
            entry[name] = {"beats_prior": float(np.mean(ratios <= 1.0)),
                           "median": float(np.median(ratios)),
                           "q95": float(np.quantile(ratios, 0.95))}
        rejected = np.array([m[f"{phase}.rejected_share"] for m in runs], float)
        entry["rejected_share_max"] = float(rejected.max())
        entry["trials_rejecting_over_5_percent"] = int(np.sum(rejected > 0.05))
        key = f"{phase}.e_tau_rms"
        entry["e_tau_ratio_median"] = (float(np.median([a[key] / b[key]
                                                        for a, b in nominal]))
                                       if nominal else None)
        out["phases"][phase] = entry
    return out


# An actuator error beyond this factor (either way) is a "large" one.
LARGE_ACTUATOR_ERROR = 2.0


def tracking_summary(rows: List[Dict]) -> Dict:
    """How often DAC tracked better than dac-nominal over phases 2-3 (a diverged dac-nominal
    counts as worse), in all trials and with an actuator off by more than
    LARGE_ACTUATOR_ERROR, weaker and stronger (None for an empty group).

    Args:
        rows: The trials' rows."""
    key = "tracking_error_rms_phases_2_3"

    def better(row) -> bool:
        nominal = row["runs"][ABLATION]
        return nominal["status"] != "ok" or (row["runs"][REFERENCE]["metrics"][key]
                                             < nominal["metrics"][key])

    def share(trials):
        return float(np.mean([better(r) for r in trials])) if trials else None

    finished = [r for r in rows if r["runs"].get(REFERENCE, {}).get("status") == "ok"
                and ABLATION in r["runs"]]
    large = [r for r in finished if "actuator_gain_log10" in r["sampled"] and np.max(
        np.abs(r["sampled"]["actuator_gain_log10"])) > np.log10(LARGE_ACTUATOR_ERROR)]
    weaker = [r for r in large if -np.min(r["sampled"]["actuator_gain_log10"])
              >= np.max(r["sampled"]["actuator_gain_log10"])]
    return {"dac_not_finished": sum(r["runs"].get(REFERENCE, {}).get("status") not in
                                    (None, "ok") for r in rows),
            "trials": len(finished), "dac_better": share(finished),
            "large_actuator_error_trials": len(large),
            "dac_better_large_actuator_error": share(large),
            "weaker_trials": len(weaker), "dac_better_weaker": share(weaker),
            "stronger_trials": len(large) - len(weaker),
            "dac_better_stronger": share([r for r in large if r not in weaker]),
            "dac_nominal_diverged": sum(r["runs"][ABLATION]["status"] != "ok"
                                        for r in finished)}


def _quantiles(values) -> Dict:
    values = np.asarray(values, float)
    return {"n": int(values.size),
            **{f"q{round(100 * q):02d}": float(np.quantile(values, q)) for q in QUANTILES}}


def _mean_interval(values, rng) -> Dict:
    """Mean, median and 95 % percentile-bootstrap interval of the mean (None below 2)."""
    values = np.asarray(values, float)
    interval = None
    if values.size >= 2:
        means = rng.choice(values, (BOOTSTRAP_RESAMPLES, values.size)).mean(axis=1)
        interval = [float(np.quantile(means, 0.025)), float(np.quantile(means, 0.975))]
    return {"n": int(values.size), "mean": float(values.mean()),
            "median": float(np.median(values)), "ci95": interval}


def format_summary(summary: Dict) -> str:
    """Formats a summary as Markdown tables (summary.md's text).

    Args:
        summary: A summary (summarize)."""
    lines = [f"trials: {summary['trials']}, succeeded: {summary['succeeded']} "
             f"({100 * summary['success_rate']:.1f} %)"]
    lines += [f"{c}: ran to the end in {s['succeeded']} trials "
              f"({100 * s['success_rate']:.1f} %)"
              for c, s in summary["controllers"].items()]
    lines += ["", "| controller | metric | n | 5 % | 25 % | median | 75 % | 95 % |",
              "|---|---|---|---|---|---|---|---|"]
    for controller, s in summary["controllers"].items():
        for name, q in s["metrics"].items():
            cells = " | ".join(f"{q[f'q{round(100 * p):02d}']:.4g}" for p in QUANTILES)
            lines.append(f"| {controller} | {name} | {q['n']} | {cells} |")
    if summary["paired"]:
        lines += ["", "| DAC vs model-based, paired | n | mean | 95 % CI of the mean | "
                      "median |", "|---|---|---|---|---|"]
        for name, p in summary["paired"].items():
            ci = (f"[{100 * p['ci95'][0]:.2f} %, {100 * p['ci95'][1]:.2f} %]"
                  if p["ci95"] else "-")
            lines.append(f"| {name} | {p['n']} | {100 * p['mean']:.2f} % | {ci} | "
                         f"{100 * p['median']:.2f} % |")
    if summary.get("learning"):
        learning = summary["learning"]
        header = ["| phase | B ratio <= 1 | B median | B 95 % | D ratio <= 1 | "
                  "D median | D 95 % | max rejected B_hat | trials rejecting > 5 % | "
                  "median e_tau DAC / dac-nominal |",
                  "|---|---|---|---|---|---|---|---|---|---|"]
        lines += ["", f"Learning (DAC, {learning['trials']} finished trials): learned / "
                      "nominal error ratio", "", *header]
        lines += _learning_rows(learning, "")
        if all("B_scaled" in e for e in learning["phases"].values()):
            lines += ["", "The same against k B~, k D~, k the identified scale (the "
                          "common factor of the inertias that momentum data leave to "
                          "the prior):", "", *header]
            lines += _learning_rows(learning, "_scaled")
    tracking = summary.get("learning_in_tracking")
    if tracking and tracking["trials"]:
        lines += ["", f"DAC against dac-nominal, RMS tracking error over phases 2-3 "
                      f"({tracking['trials']} trials where DAC ran to the end; "
                      f"{tracking['dac_not_finished']} DAC runs did not finish; "
                      f"dac-nominal diverged in {tracking['dac_nominal_diverged']}): "
                      f"DAC tracked better in {100 * tracking['dac_better']:.0f} % of "
                      "them"]
        if tracking["large_actuator_error_trials"]:
            def percent(x):
                return "-" if x is None else f"{100 * x:.0f} %"
            lines[-1] += (
                f"; in {percent(tracking['dac_better_large_actuator_error'])} of the "
                f"{tracking['large_actuator_error_trials']} with an actuator off by "
                f"more than x{LARGE_ACTUATOR_ERROR:g} ("
                f"{percent(tracking['dac_better_weaker'])} of the "
                f"{tracking['weaker_trials']} whose largest error is a weaker "
                f"actuator, {percent(tracking['dac_better_stronger'])} of the "
                f"{tracking['stronger_trials']} whose largest is a stronger one)")
    for failure in summary["failures"]:
        lines.append(f"failed trial {failure['trial']}: {failure['reason']}")
    return "\n".join(lines) + "\n"


def _learning_rows(learning: Dict, scaled: str) -> List[str]:
    """The learning table's rows, against the truth ("") or its identified scale."""
    rows = []
    for phase, e in learning["phases"].items():
        e_tau = e["e_tau_ratio_median"]
        B, D = e[f"B{scaled}"], e[f"D{scaled}"]
        rows.append(
            f"| {phase} | {100 * B['beats_prior']:.0f} % | {B['median']:.3g} "
            f"| {B['q95']:.3g} | {100 * D['beats_prior']:.0f} % | "
            f"{D['median']:.3g} | {D['q95']:.3g} | "
            f"{100 * e['rejected_share_max']:.2f} % | "
            f"{e['trials_rejecting_over_5_percent']} | "
            f"{'-' if e_tau is None else f'{e_tau:.3g}'} |")
    return rows


def write_summary(out_dir: Union[str, Path], definition: SweepDefinition) -> Dict:
    """Writes summary.json, summary.md, rows.parquet and figures/; returns the summary.

    Args:
        out_dir: The sweep's directory OUT.
        definition: The sweep that created it.

    Raises:
        ConfigError: The directory holds no sweep, or another sweep's."""
    out = Path(out_dir)
    read_manifest(out, definition)
    rows = sorted_rows(read_rows(out))
    summary = summarize(rows, definition.sweep.controllers, definition.sweep.seed)
    flat = [flat_row(r) for r in rows]
    summary["parquet"] = write_parquet(flat, out / "rows.parquet")
    summary["figures"] = [str(p.relative_to(out)) for p in
                          plot_sweep(flat, definition.sweep.controllers, out / "figures")]
    (out / "summary.json").write_text(json.dumps(summary, indent=2))
    (out / "summary.md").write_text(format_summary(summary))
    return summary


def write_parquet(flat: List[Dict], path: Path) -> str:
    """Writes the flat rows to Parquet; returns its name, or why it was not written.

    Args:
        flat: The flat rows (flat_row).
        path: The file to write."""
    try:
        import pyarrow
        import pyarrow.parquet
    except ImportError:
        return ("not written: pyarrow is not installed (pip install "
                "'dacph-drake[parquet]'); the rows are in rows.jsonl")
    pyarrow.parquet.write_table(pyarrow.Table.from_pylist(flat), path)
    return str(path.name)


def plot_sweep(flat: List[Dict], controllers: List[str], folder: Path) -> List[Path]:
    """Plots distributions.png and sensitivity.png; returns their paths.

    Args:
        flat: The flat rows (flat_row).
        controllers: The controllers the sweep runs.
        folder: The folder to write to (created if missing)."""
    folder.mkdir(parents=True, exist_ok=True)
    metrics = [m for m in PLOTTED_METRICS if any(f"{c}.{m}" in r for r in flat
                                                 for c in controllers)]
    paths = []
    if metrics:
        fig, axes = plt.subplots(1, len(metrics), figsize=(3.2 * len(metrics), 3.6),
                                 squeeze=False)
        for ax, metric in zip(axes[0], metrics):
            data = [[r[f"{c}.{metric}"] for r in flat if f"{c}.{metric}" in r]
                    for c in controllers]
            ax.boxplot([d if d else [np.nan] for d in data], tick_labels=controllers)
            values = [v for d in data for v in d]
            if values and min(values) > 0 and max(values) > 10 * min(values):
                ax.set_yscale("log")
            ax.set_title(metric, fontsize=9)
        fig.tight_layout()
        paths.append(folder / "distributions.png")
        fig.savefig(paths[-1], dpi=110)
        plt.close(fig)
    parameters = list(dict.fromkeys(k for r in flat for k in r if k.startswith("sampled.")))
    if parameters:
        columns = min(4, len(parameters))
        rows = -(-len(parameters) // columns)
        fig, axes = plt.subplots(rows, columns, figsize=(3.4 * columns, 3.0 * rows),
                                 squeeze=False)
        for ax, parameter in zip(axes.flat, parameters):
            for controller in controllers:
                key = f"{controller}.{SENSITIVITY_METRIC}"
                points = [(r[parameter], r[key]) for r in flat if key in r]
                if points:
                    ax.scatter(*zip(*points), s=12, label=controller)
            failed = [r[parameter] for r in flat if r["status"] != "ok"]
            ax.scatter(failed, np.full(len(failed), 0.02), marker="x", color="red",
                       transform=ax.get_xaxis_transform(), label="failed trial")
            ax.set_xlabel(parameter.removeprefix("sampled."), fontsize=8)
            ax.set_ylabel(SENSITIVITY_METRIC, fontsize=8)
        for ax in list(axes.flat)[len(parameters):]:
            ax.axis("off")
        axes.flat[0].legend(fontsize=7)
        fig.tight_layout()
        paths.append(folder / "sensitivity.png")
        fig.savefig(paths[-1], dpi=110)
        plt.close(fig)
    return paths
