"""The end-effector pose task (task: !EndEffectorPose) against the model-based
baseline: each scenario under DAC, dac-nominal and the baseline through every phase,
RMS position error [m] and attitude error [rad] per phase, DAC / baseline in phases
2-3, then `dacph verify` on the DAC run (run: .venv/bin/python scripts/pose_task.py
--out results/pose_task [SCENARIO.yaml ...]; default: the shipped pose scenarios;
--family N: N starts and references of our own on them; --zoo: the zoo's arms of at
least 6 joints, --zoo --family N: its random arms).

Rows go to OUT/rows.jsonl as they finish (a re-run skips the ones done); OUT/table.md
is the docs' results table."""
import argparse
import copy
import json
import time
from pathlib import Path

import numpy as np

from dacph_drake.loop.threads import single_threaded

SHIPPED = ("scenarios/satellite_6dof_pose.yaml", "scenarios/panda_pose.yaml")
CONTROLLERS = ("dac", "dac-nominal", "model-based")


def family(count: int, seed: int, bases=None):
    """Pose scenarios of our own: the bases (default: the two shipped pose scenarios)
    in turn with random starts near their q0 (+-0.3 rad), position references along
    random axes of 1-5 cm and periods of 5-12 s, initial offsets up to 3 cm and
    attitude amplitudes 0.1-0.5 rad."""
    from dacph_drake.assembly.scenario_files import load_scenario
    rng = np.random.default_rng(seed)
    bases = bases or [(Path(path).stem, load_scenario(path)) for path in SHIPPED]
    for k in range(count):
        stem, base = bases[k % len(bases)]
        scenario = copy.deepcopy(base)
        scenario.q0 = [float(x) for x in np.asarray(scenario.q0) + rng.uniform(
            -0.3, 0.3, len(scenario.q0))]
        p = scenario.task.position
        axis = rng.normal(size=3)
        p.axis = list(axis / np.linalg.norm(axis))
        p.amplitude = float(rng.uniform(0.01, 0.05))
        p.period = float(rng.uniform(5.0, 12.0))
        offset = rng.normal(size=3)
        p.initial_offset = list(offset / np.linalg.norm(offset) * rng.uniform(0.0, 0.03))
        scenario.task.reference.amplitude = float(rng.uniform(0.1, 0.5))
        scenario.seed = int(seed * 1000 + k)
        yield f"{stem}_family_{seed}_{k:02d}", scenario


def zoo_arms(folder: Path, family_count: int, seed: int):
    """The zoo's arms (scripts/zoo.py: example-robot-data's and our own extreme
    ones) and ``family_count`` of its random serial arms, each from its zoo file with
    ``task: !EndEffectorPose {}`` added (every other setting sized to the arm); arms
    of fewer than 6 joints are left out (the pose needs 6)."""
    import zoo
    from dacph_drake.assembly.scenario_files import load_scenario
    folder.mkdir(parents=True, exist_ok=True)
    names = list(zoo.SHIPPED) + list(zoo.OWN)
    if family_count:
        zoo.OWN.update(zoo.family(family_count, seed))
        names = [name for name in zoo.OWN if name.startswith("family_")]
    for name in names:
        path = zoo.scenario_file(folder, name)
        path.write_text(path.read_text() + "task: !EndEffectorPose {}\n")
        try:
            scenario = load_scenario(path)
        except Exception as e:                              # noqa: BLE001
            yield f"{name}_pose", e
            continue
        if len(scenario.q0) >= 6:
            yield f"{name}_pose", scenario


def evaluate(name: str, scenario, out: Path) -> dict:
    """One scenario's row."""
    from dacph_drake.loop.metrics import RunMetrics
    from dacph_drake.loop.verify import verify_logs
    from dacph_drake.assembly.registry import robot_of
    from dacph_drake.loop.simulate import simulate
    from dacph_drake.assembly.scenario_files import save_scenario
    row = {"name": name, "runs": {}}
    if isinstance(scenario, Exception):
        row["refused"] = str(scenario)
        return row
    out.mkdir(parents=True, exist_ok=True)
    save_scenario(scenario, out / f"{name}.yaml")
    try:
        robot_of(scenario).RequireRunnableStart()
    except Exception as e:                                  # noqa: BLE001
        row["refused"] = str(e)
        return row
    for controller in CONTROLLERS:
        start = time.perf_counter()
        run = simulate(scenario, controller)
        metrics = RunMetrics.Of(run.logs, scenario) if run.status == "ok" else None
        row["runs"][controller] = {
            "status": run.status, "reason": run.reason, "final_time": run.final_time,
            "wall_time": time.perf_counter() - start,
            "position": {phase: values.get("position_error_rms")
                         for phase, values in metrics.phases.items()} if metrics else {},
            "attitude": {phase: values.get("tracking_error_rms")
                         for phase, values in metrics.phases.items()} if metrics else {}}
        if controller == "dac" and run.status == "ok":
            start = time.perf_counter()
            report = verify_logs(run.logs, scenario, {"status": run.status})
            row["verify"] = {"ok": bool(report["ok"]),
                             "failed": [k for k, v in report["checks"].items()
                                        if isinstance(v, dict) and not v.get("ok", True)],
                             "wall_time": time.perf_counter() - start}
    return row


def ratios(row: dict) -> dict:
    """DAC / baseline of the worst of phases 2-3, for position and attitude."""
    dac, base = row["runs"].get("dac", {}), row["runs"].get("model-based", {})
    out = {}
    for key in ("position", "attitude"):
        try:
            worst = max(dac[key][p] for p in ("nonlinear", "disturbance"))
            baseline = min(base[key][p] for p in ("nonlinear", "disturbance"))
            out[key] = max(dac[key][p] / base[key][p] for p in ("nonlinear",
                                                                 "disturbance"))
            out[f"dac_{key}_worst"] = worst
            out[f"baseline_{key}_best"] = baseline
        except (KeyError, TypeError, ZeroDivisionError):
            out[key] = float("nan")
    return out


def table(rows) -> str:
    lines = ["| scenario | DAC position RMS, phases 2 / 3 [m] | baseline [m] | "
             "DAC / baseline (position) | DAC attitude RMS, phases 2 / 3 [rad] | "
             "baseline [rad] | DAC / baseline (attitude) | verify |",
             "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    for row in rows:
        if "refused" in row:
            lines.append(f"| {row['name']} | refused: {row['refused'][:80]} |||||||")
            continue
        r = ratios(row)
        cells = [row["name"]]
        for key in ("position", "attitude"):
            for controller in ("dac", "model-based"):
                run = row["runs"][controller]
                cells.append(" / ".join(f"{run[key].get(p, float('nan')):.2e}"
                                        if run["status"] == "ok" else run["status"]
                                        for p in ("nonlinear", "disturbance")))
            cells.append(f"{r[key]:.3f}")
        cells.append("pass" if row.get("verify", {}).get("ok") else
                     "FAIL " + ",".join(row.get("verify", {}).get("failed", [])))
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def summary(rows) -> str:
    """The family's counts against the targets, and its worst cases."""
    built = [row for row in rows if "refused" not in row]
    ran = [row for row in built if all(run["status"] == "ok"
                                       for run in row["runs"].values())]
    ratio = {row["name"]: ratios(row) for row in ran}
    lines = [f"- scenarios: {len(rows)}; built and started: {len(built)} "
             f"(refused: {len(rows) - len(built)})",
             f"- every controller ran every phase: {len(ran)} of {len(built)}"]
    for key, unit in (("position", "m"), ("attitude", "rad")):
        values = sorted((r[key], name) for name, r in ratio.items())
        met = sum(value <= 0.1 for value, _ in values)
        worst = values[-1] if values else (float("nan"), "-")
        dac = max((r.get(f"dac_{key}_worst", float("nan")) for r in ratio.values()),
                  default=float("nan"))
        lines.append(f"- {key}: DAC <= 0.1x the baseline in phases 2-3 on {met} of "
                     f"{len(values)} (worst {worst[0]:.3f}, {worst[1]}); DAC's largest "
                     f"phase-2/3 RMS {dac:.2e} {unit}")
    verified = [row for row in ran if row.get("verify", {}).get("ok")]
    lines.append(f"- dacph verify passes: {len(verified)} of {len(ran)}")
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scenarios", nargs="*")
    parser.add_argument("--out", default="results/pose_task")
    parser.add_argument("--family", type=int, default=0)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--variations", type=int, default=0,
                        help="with --zoo: this many random references per zoo arm")
    parser.add_argument("--zoo", action="store_true",
                        help="the zoo's arms (with --family N: N of its random arms)")
    args = parser.parse_args()
    from dacph_drake.assembly.scenario_files import load_scenario
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    rows_file = out / "rows.jsonl"
    done = {json.loads(line)["name"]: json.loads(line)
            for line in rows_file.read_text().splitlines()} if rows_file.exists() else {}
    if args.zoo and args.variations:
        arms = [(name, scenario) for name, scenario in zoo_arms(out / "arms", 0, 0)
                if not isinstance(scenario, Exception)]
        cases = family(args.variations * len(arms), args.seed, arms)
    elif args.zoo:
        cases = zoo_arms(out / "arms", args.family, args.seed)
    elif args.family:
        cases = family(args.family, args.seed)
    else:
        cases = ((Path(p).stem, load_scenario(p)) for p in (args.scenarios or SHIPPED))
    rows = []
    with single_threaded():
        for name, scenario in cases:
            if name not in done:
                done[name] = evaluate(name, copy.deepcopy(scenario), out / "scenarios")
                with rows_file.open("a") as f:
                    f.write(json.dumps(done[name]) + "\n")
                print(json.dumps({"name": name, **ratios(done[name])}), flush=True)
            rows.append(done[name])
    ordered = sorted(done.values(), key=lambda r: r["name"])
    (out / "table.md").write_text(table(ordered))
    (out / "summary.md").write_text(summary(ordered))


if __name__ == "__main__":
    main()
