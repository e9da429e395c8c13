"""Families of trials for the learning targets (run: .venv/bin/python
scripts/learning_families.py [--families NAME ...] [--variant NAME] [--trials N]).

Each family is a Monte Carlo sweep (montecarlo.run_sweep, DAC and dac-nominal on
every sample, resumable) of trials the project was not tuned on:

- compressed: the short scenario's phases compressed to 0.5 + 1 + 1 + 1 s, the
  robot's masses +-10 %, the RHS's unknown parts x0.5-1.5, d(t) x0.5-2, q0 drawn;
- model_error: the robot's link masses +-20 %, link lengths +-5 %, base +-20 %,
  the controller's link and base masses +-15 %, the RHS's unknown parts x0.5-1.5,
  actuators x0.4-2.5 each, one actuator fault in phase 2, d(t) x0.5-2, q0 drawn
  (the lengths stated known to 3 %: inertia.kinematic_tolerance);
- kinematic: the robot's link lengths +-5 % (stated: inertia.kinematic_tolerance
  0.03), masses +-10 %, actuators x0.4-2.5 each, the RHS's unknown parts x0.5-1.5;
- actuators: actuators x0.3-3 each and one fault in phase 2, q0 drawn;
- links: planar arms of 2 to 8 links (9 trials each), masses +-20 %, the
  RHS's unknown parts x0.5-1.5, d(t) x0.5-2;
- described: satellite_3dof, satellite_6dof and the Panda, q0 drawn around
  each shipped one, the RHS's unknown parts x0.5-1.5, d(t) x0.5-2.

A variant (--variant) changes settings of every family's base scenario: the
learner (network against local_bayes), the adoption rule (trust_band against
certified_set), the identifier's anchor. The rows go to
OUT/VARIANT/FAMILY/rows.jsonl, the per-family table of the learning targets to
OUT/VARIANT/summary.md and .json (family_table).
"""
import argparse
import json
import sys
from pathlib import Path
from typing import Callable, Dict, List

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
PHASES = ("phase1", "phase2", "phase3")


def _planar_arm_file(n: int) -> str:
    """A planar arm of n tapering links (a file naming only the links and the short
    scenario's phases; the rest is sized to the arm)."""
    links = "\n".join(
        f"      - {{mass: {0.9**k:.6g}, length: {0.5 * 0.9**k:.6g}, "
        f"inertia: {0.02 * 0.9**(3 * k):.6g}, com: {0.25 * 0.9**k:.6g}}}"
        for k in range(n))
    return ("robot: !PlanarArm\n  truth:\n    links:\n" + links + "\n"
            "phases: {warmup: 2.0, linear: 8.0, nonlinear: 8.0, disturbance: 8.0}\n")


def _load(text_or_name: str, folder: Path, name: str):
    from dacph_drake.assembly.scenario_files import load_scenario
    if "\n" not in text_or_name:
        return load_scenario(text_or_name if not text_or_name.endswith(".yaml")
                             else ROOT / "scenarios" / text_or_name)
    path = folder / f"{name}_source.yaml"
    path.write_text(text_or_name)
    return load_scenario(path)


RHS_SPREAD = {"delta_B_scale": "!Uniform {min: 0.5, max: 1.5}",
              "delta_D_scale": "!Uniform {min: 0.5, max: 1.5}",
              "disturbance_scale": "!Uniform {min: 0.5, max: 2.0}"}


def _compressed(scenario):
    scenario.phases.warmup, scenario.phases.linear = 0.5, 1.0
    scenario.phases.nonlinear, scenario.phases.disturbance = 1.0, 1.0
    return scenario


def _knows_lengths_to_5_percent(scenario):
    """The user states what the family draws: link lengths within +-5 % of the
    model's (a uniform draw's sd, 2.9 %, as the kinematic tolerance)."""
    scenario.inertia.kinematic_tolerance = 0.03
    return scenario


# name -> list of (sweep name, base scenario source, scenario edit, trials share,
# distributions).
FAMILIES: Dict[str, List] = {
    "compressed": [("compressed", "short", _compressed, 1.0, {
        "link_mass_scale": "!Uniform {min: 0.9, max: 1.1}",
        "base_mass_scale": "!Uniform {min: 0.9, max: 1.1}", **RHS_SPREAD,
        "q0": "!UniformVector {min: [0.1, 0.7], max: [0.6, 1.5]}"})],
    "model_error": [("model_error", "model_error.yaml", _knows_lengths_to_5_percent, 1.0, {
        "link_mass_scale": "!Uniform {min: 0.8, max: 1.2}",
        "link_length_scale": "!Uniform {min: 0.95, max: 1.05}",
        "base_mass_scale": "!Uniform {min: 0.8, max: 1.2}",
        "nominal_link_mass_scale": "!Uniform {min: 0.85, max: 1.15}",
        "nominal_base_mass_scale": "!Uniform {min: 0.85, max: 1.15}", **RHS_SPREAD,
        "actuator_gain_log10": "!Uniform {min: -0.398, max: 0.398}",
        "fault_time": "!Uniform {min: 11.0, max: 17.0}",
        "fault_joint": "!UniformDiscrete {values: [1, 2]}",
        "fault_gain": "!Uniform {min: 0.3, max: 0.7}",
        "q0": "!UniformVector {min: [0.1, 0.7], max: [0.6, 1.5]}"})],
    "kinematic": [("kinematic", "model_error.yaml", _knows_lengths_to_5_percent, 1.0, {
        "link_length_scale": "!Uniform {min: 0.95, max: 1.05}",
        "link_mass_scale": "!Uniform {min: 0.9, max: 1.1}", **RHS_SPREAD,
        "actuator_gain_log10": "!Uniform {min: -0.398, max: 0.398}",
        "q0": "!UniformVector {min: [0.1, 0.7], max: [0.6, 1.5]}"})],
    "actuators": [("actuators", "model_error.yaml", None, 1.0, {
        "actuator_gain_log10": "!Uniform {min: -0.523, max: 0.477}",
        "fault_time": "!Uniform {min: 11.0, max: 17.0}",
        "fault_joint": "!UniformDiscrete {values: [1, 2]}",
        "fault_gain": "!Uniform {min: 0.3, max: 0.7}", **RHS_SPREAD,
        "q0": "!UniformVector {min: [0.1, 0.7], max: [0.6, 1.5]}"})],
    "links": [(f"links{n}", _planar_arm_file(n), None, 1.0 / 7, {
        "link_mass_scale": "!Uniform {min: 0.8, max: 1.2}", **RHS_SPREAD})
        for n in range(2, 9)],
    "described": [
        ("satellite_3dof", "satellite_3dof", None, 0.34, {
            **RHS_SPREAD, "q0": "!UniformVector {min: [0.2, -0.9, 1.5], "
                                "max: [0.4, -0.7, 1.7]}"}),
        ("satellite_6dof", "satellite_6dof", None, 0.33, {
            **RHS_SPREAD, "q0": "!UniformVector {min: [0.25, -0.85, 1.55, 0.15, 0.55, "
                                "-0.35], max: [0.35, -0.75, 1.65, 0.25, 0.65, -0.25]}"}),
        ("panda", "panda.yaml", None, 0.33, dict(RHS_SPREAD))],
}

# A variant's settings, applied to every base scenario: name -> edit.
VARIANTS: Dict[str, Callable] = {
    "default": lambda s: s,
    "network": lambda s: (setattr(s.learner, "model", "network"),
                          setattr(s.rhs, "adoption", "trust_band"), s)[-1],
    "local_bayes_trust_band": lambda s: (setattr(s.rhs, "adoption", "trust_band"), s)[-1],
}


def _apply_settings(scenario, settings: List[str]):
    """Applies KEY=VALUE overrides (a dotted path into the scenario, a YAML value)."""
    import yaml
    for item in settings:
        key, value = item.split("=", 1)
        *path, last = key.split(".")
        target = scenario
        for name in path:
            target = getattr(target, name)
        setattr(target, last, yaml.safe_load(value))
    return scenario


def run_family(family: str, variant: str, trials: int, out: Path, workers: int,
               seed: int, settings: List[str] = (), label: str = "",
               saved: bool = False) -> List[Dict]:
    """Runs (or resumes) one family of one variant; its rows, each tagged with its
    sweep's name (``saved``: only the rows already saved)."""
    from dacph_drake.montecarlo.definition import load_sweep
    from dacph_drake.montecarlo.runner import run_sweep
    from dacph_drake.montecarlo.store import read_rows, sorted_rows
    from dacph_drake.assembly.scenario_files import save_scenario
    rows = []
    for k, (name, source, edit, share, distributions) in enumerate(FAMILIES[family]):
        folder = out / (label or variant) / family / name
        if saved:
            for row in sorted_rows(read_rows(folder / "runs")):
                row["sweep"] = name
                rows.append(row)
            continue
        folder.mkdir(parents=True, exist_ok=True)
        scenario = _load(source, folder, name)
        if edit is not None:
            scenario = edit(scenario)
        scenario = _apply_settings(VARIANTS[variant](scenario), settings)
        save_scenario(scenario, folder / "base.yaml")
        count = max(1, int(round(share * trials)))
        lines = ["scenario: base.yaml", f"trials: {count}", f"seed: {seed + k}",
                 "controllers: [dac, dac-nominal]", "distributions:"]
        lines += [f"  {key}: {value}" for key, value in distributions.items()]
        (folder / "sweep.yaml").write_text("\n".join(lines) + "\n")
        definition = load_sweep(folder / "sweep.yaml")
        for row in run_sweep(definition, folder / "runs", slots=workers, progress=True):
            row["sweep"] = name
            row["n"] = len(definition.scenario.q0)
            rows.append(row)
    return rows


def _actuator_gains(row: Dict) -> np.ndarray:
    """The actuators' gains over the prior's (before any fault)."""
    return 10.0 ** np.asarray(row["sampled"].get("actuator_gain_log10", [0.0]), float)


def family_table(rows: List[Dict]) -> Dict:
    """The learning targets over a family's rows (the issue's list):

    - runaways: trials where DAC did not finish while dac-nominal did;
    - B and D no worse than the prior against the truth: the share of finished
      trial-phases with phaseK.X_error_ratio <= 1, and the worst ratio;
    - interval coverage: the pooled share of (sample, entry) pairs inside the
      reported intervals, and the share of trial-phases whose coverage is at least
      0.85;
    - informative intervals: the share of trial-phases with X_interval_ratio < 1;
    - DAC against dac-nominal where an actuator is off by more than x2: the share
      of trials with a lower phases 2-3 tracking error, and the same where some
      actuator is below x0.5 (weak) and where all are within x0.5 and some above
      x2 (strong);
    - an actuator fault: the share of trials whose tracking error over the 2 s
      after it is within 2x of the 2 s before (fault1.tracking_error_ratio);
    - the identified total mass: the share within 10 % of the truth, and the
      share of trials whose kinematic mismatch was reported.

    Args:
        rows: The family's rows.

    Returns:
        The table's numbers."""
    out = {"trials": len(rows)}
    finished = [r for r in rows if r["runs"].get("dac-nominal", {}).get("status") == "ok"]
    dac_ok = [r for r in finished if r["runs"].get("dac", {}).get("status") == "ok"]
    out["nominal_finished"] = len(finished)
    out["runaways"] = len(finished) - len(dac_ok)
    out["runaway_reasons"] = [f"{r['sweep']} trial {r['trial']}: "
                              f"{r['runs']['dac']['reason']}"
                              for r in finished if r not in dac_ok][:10]
    for X in ("B", "D"):
        ratios, coverage, informative = [], [], []
        for row in dac_ok:
            m = row["runs"]["dac"]["metrics"]
            for phase in PHASES:
                ratio = m.get(f"{phase}.{X}_error_ratio", float("nan"))
                if np.isfinite(ratio):
                    ratios.append(ratio)
                c = m.get(f"{phase}.{X}_coverage", float("nan"))
                if np.isfinite(c):
                    coverage.append(c)
                i = m.get(f"{phase}.{X}_interval_ratio", float("nan"))
                if np.isfinite(i):
                    informative.append(i < 1.0)
        ratios = np.array(ratios)
        out[f"{X}_no_worse_share"] = float(np.mean(ratios <= 1.0)) if len(ratios) else None
        out[f"{X}_worst_ratio"] = float(np.max(ratios)) if len(ratios) else None
        out[f"{X}_median_ratio"] = float(np.median(ratios)) if len(ratios) else None
        out[f"{X}_coverage_pooled"] = float(np.mean(coverage)) if coverage else None
        out[f"{X}_coverage_share_085"] = (float(np.mean(np.array(coverage) >= 0.85))
                                          if coverage else None)
        out[f"{X}_informative_share"] = (float(np.mean(informative))
                                         if informative else None)
        # Phases 2-3 whose prior is off by 20 % or more: the claims' share that halves
        # the prior's error there.
        off = [m[f"{phase}.{X}_error_ratio"] for row in dac_ok
               for m in [row["runs"]["dac"]["metrics"]] for phase in ("phase2", "phase3")
               if m.get(f"{phase}.{X}_error_nominal", 0.0) >= 0.2
               and np.isfinite(m.get(f"{phase}.{X}_error_ratio", np.nan))]
        out[f"{X}_off20_estimates"] = len(off)
        out[f"{X}_halved_off20_share"] = (float(np.mean(np.array(off) <= 0.5))
                                          if off else None)
    def better_share(trials):
        key = "tracking_error_rms_phases_2_3"
        better = [r for r in trials if r["runs"]["dac"]["metrics"][key]
                  < r["runs"]["dac-nominal"]["metrics"][key]]
        return len(better) / len(trials) if trials else None

    weak = [r for r in dac_ok if np.min(_actuator_gains(r)) < 0.5]
    strong = [r for r in dac_ok if np.max(_actuator_gains(r)) > 2.0 and r not in weak]
    out["actuator_off_trials"] = len(weak) + len(strong)
    out["dac_better_when_off_share"] = better_share(weak + strong)
    out["dac_better_weak_share"] = better_share(weak)
    out["dac_better_strong_share"] = better_share(strong)
    faults = [r["runs"]["dac"]["metrics"].get("fault1.tracking_error_ratio")
              for r in dac_ok]
    faults = np.array([f for f in faults if f is not None and np.isfinite(f)])
    out["fault_trials"] = len(faults)
    out["fault_recovered_share"] = float(np.mean(faults <= 2.0)) if len(faults) else None
    out["fault_ratio_median"] = float(np.median(faults)) if len(faults) else None
    mass = np.array([r["runs"]["dac"]["metrics"].get("identified_mass_error", np.nan)
                     for r in dac_ok], float)
    out["mass_within_10_share"] = (float(np.mean(np.abs(mass[np.isfinite(mass)]) <= 0.1))
                                   if np.isfinite(mass).any() else None)
    out["mismatch_reported_share"] = float(np.mean([
        r["runs"]["dac"]["metrics"].get("kinematic_mismatch", 0.0) > 0.5 for r in dac_ok]))
    for name in ("model_error_coverage", "model_error_sd", "model_error_realized"):
        values = [r["runs"]["dac"]["metrics"].get(f"{phase}.{name}", np.nan)
                  for r in dac_ok for phase in PHASES]
        values = np.array([v for v in values if v is not None and np.isfinite(v)])
        out[name] = float(np.median(values)) if len(values) else None
    tracking = [r["runs"]["dac"]["metrics"]["tracking_error_rms_phases_2_3"]
                / r["runs"]["dac-nominal"]["metrics"]["tracking_error_rms_phases_2_3"]
                for r in dac_ok]
    out["tracking_ratio_median"] = float(np.median(tracking)) if tracking else None
    return out


def _cell(value, digits=3):
    if value is None:
        return "-"
    if isinstance(value, float):
        return f"{value:.{digits}g}"
    return str(value)


LEARNING_COLUMNS = [
    ("trials", "trials"), ("B_no_worse_share", "B <= prior"), ("B_worst_ratio", "B worst"),
    ("B_median_ratio", "B median"), ("D_no_worse_share", "D <= prior"),
    ("D_worst_ratio", "D worst"), ("B_coverage_pooled", "B coverage"),
    ("D_coverage_pooled", "D coverage"), ("B_coverage_share_085", "B covered >= 0.85"),
    ("D_coverage_share_085", "D covered >= 0.85"), ("B_informative_share", "B informative"),
    ("D_informative_share", "D informative"),
    ("B_halved_off20_share", "B <= 0.5x where prior off >= 20 %"),
    ("B_off20_estimates", "(B estimates)"),
    ("D_halved_off20_share", "D <= 0.5x where prior off >= 20 %"),
    ("D_off20_estimates", "(D estimates)"),
    ("model_error_coverage", "E within its interval (median)"),
    ("model_error_sd", "E sd measured (median)"),
    ("model_error_realized", "true max |E| (median)")]
LOOP_COLUMNS = [
    ("nominal_finished", "dac-nominal finished"),
    ("runaways", "DAC runaways there"),
    ("dac_better_when_off_share", "DAC better, an actuator off > x2"),
    ("dac_better_weak_share", "... one < x0.5"), ("dac_better_strong_share", "... > x2 only"),
    ("fault_recovered_share", "fault: within 2x in 2 s"),
    ("mass_within_10_share", "mass within 10 %"),
    ("mismatch_reported_share", "mismatch reported"),
    ("tracking_ratio_median", "tracking DAC / dac-nominal (median)")]


def markdown(tables: Dict[str, Dict]) -> str:
    """The per-family tables as Markdown: the learning targets, then the loop's."""
    out = []
    for columns in (LEARNING_COLUMNS, LOOP_COLUMNS):
        lines = ["| family | " + " | ".join(label for _, label in columns) + " |",
                 "|---" * (len(columns) + 1) + "|"]
        for family, table in tables.items():
            lines.append(f"| {family} | " + " | ".join(_cell(table.get(key))
                                                        for key, _ in columns) + " |")
        out.append("\n".join(lines) + "\n")
    return "\n".join(out)


ABLATION_COLUMNS = [
    ("runaways", "runaways"), ("B_no_worse_share", "B <= prior"),
    ("B_worst_ratio", "B worst"), ("D_no_worse_share", "D <= prior"),
    ("D_worst_ratio", "D worst"), ("B_coverage_pooled", "B coverage"),
    ("D_coverage_pooled", "D coverage"), ("B_informative_share", "B informative"),
    ("D_informative_share", "D informative"),
    ("dac_better_when_off_share", "DAC better, actuator off > x2"),
    ("fault_recovered_share", "fault within 2x"),
    ("tracking_ratio_median", "tracking / dac-nominal")]


def ablation_markdown(out: Path, labels: List[str]) -> str:
    """One table of the saved summaries of several variants (OUT/LABEL/summary.json),
    a row per family and variant."""
    summaries = {label: json.loads((out / label / "summary.json").read_text())
                 for label in labels}
    families = [f for f in FAMILIES if any(f in s for s in summaries.values())]
    lines = ["| family | variant | " + " | ".join(l for _, l in ABLATION_COLUMNS) + " |",
             "|---" * (len(ABLATION_COLUMNS) + 2) + "|"]
    for family in families:
        for label, summary in summaries.items():
            if family in summary:
                lines.append(f"| {family} | {label} | " + " | ".join(
                    _cell(summary[family].get(key)) for key, _ in ABLATION_COLUMNS) + " |")
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--families", nargs="+", default=list(FAMILIES))
    parser.add_argument("--variant", default="default", choices=list(VARIANTS))
    parser.add_argument("--trials", type=int, default=64)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--seed", type=int, default=3700)
    parser.add_argument("--out", default=str(ROOT / "runs" / "learning_families"))
    parser.add_argument("--set", nargs="*", default=[], metavar="KEY=VALUE",
                        help="settings of every base scenario (a dotted path, a YAML "
                             "value), e.g. learner.bayes.min_dof=4")
    parser.add_argument("--label", default="", help="the results' folder name "
                        "(default: the variant's)")
    parser.add_argument("--tables-only", action="store_true",
                        help="the tables of the rows already saved, without running")
    parser.add_argument("--compare", nargs="+", metavar="LABEL",
                        help="print one table of these saved variants and stop")
    args = parser.parse_args()
    out = Path(args.out)
    if args.compare:
        print(ablation_markdown(out, args.compare))
        return
    tables = {}
    for family in args.families:
        rows = run_family(family, args.variant, args.trials, out, args.workers, args.seed,
                          args.set, args.label, saved=args.tables_only)
        tables[family] = family_table(rows)
        print(f"\n{family}: {json.dumps(tables[family], indent=1)}", flush=True)
    summary = out / (args.label or args.variant)
    summary.mkdir(parents=True, exist_ok=True)
    previous = (json.loads((summary / "summary.json").read_text())
                if (summary / "summary.json").exists() else {})
    previous.update(tables)
    (summary / "summary.json").write_text(json.dumps(previous, indent=1))
    (summary / "summary.md").write_text(markdown(previous))
    print(markdown(previous))


if __name__ == "__main__":
    sys.exit(main())
