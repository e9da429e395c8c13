"""Control under model error, each part of it against the run without it (docs/results/model-error.md): actuators off the prior (x0.4, x3, one of each), a fault, the
controller's inertias off the robot's (20 % in opposite directions, and each body
on its own), and the nominal robot; two seeds each (the learner's seed and the
start configuration). Every DAC run is also verified (dacph verify's checks), and
dac-nominal, the same loop without learning, runs once per scenario and seed.

    .venv/bin/python scripts/model_error_ablation.py --out results/model_error
    .venv/bin/python scripts/model_error_ablation.py --quick     (2 scenarios, 1 seed)

Writes OUT/runs.jsonl (one line a run: its settings and metrics) and OUT/table.md."""
import argparse
import copy
import json
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from dacph_drake.loop.verify import verify_logs
from dacph_drake.log_layout import RhsLog
from dacph_drake.loop.metrics import run_metrics
from dacph_drake.loop.simulate import simulate
from dacph_drake.scenario import ActuatorFault
from dacph_drake.scenario.built_in import short_scenario

START = [[0.3, 1.0], [0.45, 0.85]]          # q0 of seed 0, 1
KEPT_METRICS = ("tracking_error", "phase", "fault", "control_effort")   # in runs.jsonl
PHASES = ("phase1", "phase2", "phase3")


SPATIAL = {   # name -> (robot, the controller's factors per body, warm-up [s])
    "satellite_3dof inertia +-20 %": ("satellite_3dof", [1.2, 1.2, 0.8, 0.8], 2.0),
    "satellite_6dof inertia +-20 %": ("satellite_6dof",
                                      [1.2, 1.2, 1.2, 0.8, 0.8, 0.8, 0.8], 4.0),
}


def scenario_of(name: str, seed: int):
    if name in SPATIAL:
        from dacph_drake.assembly.scenario_files import load_scenario
        robot, factors, warmup = SPATIAL[name]
        s = load_scenario(robot)
        s.seed, s.robot.nominal_inertia_scale = seed, factors
        end = s.duration                    # the run keeps its length: phase 3 shorter
        s.phases.warmup = warmup
        s.phases.disturbance = end - s.phases.disturbance_start
        return s
    s = short_scenario()
    s.seed, s.q0 = seed, START[seed]
    robot = s.robot.nominal
    bodies = [robot.base] + robot.links
    if name == "x0.4":
        s.uncertainty.B_scale = [0.4, 0.4]
    elif name == "x3":
        s.uncertainty.B_scale = [3.0, 3.0]
    elif name == "x0.5,x2.5":
        s.uncertainty.B_scale = [0.5, 2.5]
    elif name == "fault":
        s.uncertainty.faults = [ActuatorFault(time=14.0, joint=2, gain=0.5)]
    elif name == "inertia +-20 %":          # the controller's base, link 1 heavy, link 2 light
        for body, f in zip(bodies, [1.2, 1.2, 0.8]):
            body.mass *= f
            body.inertia *= f
    elif name == "inertia -+20 %":
        for body, f in zip(bodies, [0.8, 0.8, 1.2]):
            body.mass *= f
            body.inertia *= f
        s.periods.rhs = 2.2e-4              # its lighter model asks for a faster RHS loop
    elif name == "inertia each +-20 %":     # mass and inertia each their own factor
        factors = np.random.default_rng(seed + 1).uniform(0.8, 1.2, (3, 2))
        for body, (fm, fi) in zip(bodies, factors.tolist()):
            body.mass *= fm
            body.inertia *= fi
        s.periods.rhs = 2.0e-4
    elif name != "nominal":
        raise ValueError(name)
    return s


# name -> the settings that remove (or add) one part; "every part off" switches
# every new part back.
CONFIGURATIONS = {
    "shipped defaults": {},
    "trust band around B0": {"rhs.trust_anchor": "prior"},
    "no acceptance on evidence": {"rhs.evidence_ratio": 0.0},
    "no start hold": {"learner.start_hold": 0.0},
    "no minimum window": {"learner.min_window": 0.0},
    "no warm start": {"learner.warm_start": False},
    "no hold on a new model": {"learner.model_change": False},
    "no step guard": {"learner.step_guard": 0.0},
    "no inertial identification": {"inertia.identify": False},
    "+ well-damped gain rule": {"rhs.gain_rule": "well_damped"},
    "+ boundary layer (rate 400)": {"lhs.boundary_rate": 400.0},
    "exact model": {},                      # the controller's model is the robot
    "every part off": {"rhs.trust_anchor": "prior", "rhs.evidence_ratio": 0.0,
                        "learner.start_hold": 0.0, "learner.min_window": 0.0,
                        "learner.warm_start": False, "learner.model_change": False,
                        "learner.step_guard": 0.0, "inertia.identify": False},
}


def _apply(scenario, settings):
    scenario = copy.deepcopy(scenario)
    for key, value in settings.items():
        section, name = key.split(".")
        setattr(getattr(scenario, section), name, value)
    return scenario


def settled_rejections(logs, scenario) -> float:
    """Refused B_hat share outside the 2 s after the start, each phase's start and
    each fault (a change of the port relation)."""
    t = logs["time"]
    p = scenario.phases
    changes = [0.0, p.linear_start, p.nonlinear_start, p.disturbance_start,
               *(f.time for f in scenario.uncertainty.faults)]
    settled = np.ones(len(t), bool)
    for change in changes:
        settled &= ~((t >= change) & (t < change + 2.0))
    return float(np.mean(logs["rhs_log"][settled, RhsLog(len(scenario.q0)).trusted] < 0.5))


def run(task):
    name, seed, configuration, controller = task
    scenario = _apply(scenario_of(name, seed), CONFIGURATIONS[configuration])
    if configuration == "exact model":          # the controller knows the robot
        if name in SPATIAL:
            scenario.robot.nominal_inertia_scale = []
        else:
            scenario.robot.nominal = copy.deepcopy(scenario.robot.truth)
    start = time.perf_counter()
    result = simulate(scenario, controller)
    row = {"scenario": name, "seed": seed, "configuration": configuration,
           "controller": controller, "status": result.status, "reason": result.reason,
           "final_time": result.final_time, "wall_time": time.perf_counter() - start}
    if result.status == "ok":
        row["metrics"] = {k: v for k, v in run_metrics(result.logs, scenario).items()
                          if k.startswith(KEPT_METRICS)}
        # The 6-DOF arm's region-of-attraction search takes minutes: verified by
        # its own long test (tests/test_spatial_dac.py), not here.
        if controller == "dac":
            row["settled_rejections"] = settled_rejections(result.logs, scenario)
        if controller == "dac" and "6dof" not in name:
            report = verify_logs(result.logs, scenario, {"status": result.status,
                                                         "final_time": result.final_time})
            row["verify"] = {k: c["ok"] for k, c in report["checks"].items()}
            row["verify_first_failure"] = next(
                (c.get("reason") or c.get("first_failure", "") for c in
                 report["checks"].values() if not c["ok"]), "")
    return row


def table(rows) -> str:
    """One line per scenario and configuration: medians over the seeds."""
    nominal = {(r["scenario"], r["seed"]): r for r in rows
               if r["controller"] == "dac-nominal"}
    lines = ["| scenario | DAC configuration | runs ok | RMS alpha~ per phase [rad] | "
             "/ dac-nominal (phases 2, 3) | B ratio, scaled | D ratio, scaled | "
             "rejected (settled) | verify |", "|---|---|---|---|---|---|---|---|---|"]
    keys = list(dict.fromkeys((r["scenario"], r["configuration"]) for r in rows
                              if r["controller"] == "dac"))
    for scenario, configuration in keys:
        group = [r for r in rows if r["controller"] == "dac" and r["scenario"] == scenario
                 and r["configuration"] == configuration]
        ok = [r for r in group if r["status"] == "ok"]
        cells = [scenario, configuration, f"{len(ok)} of {len(group)}"]
        if ok:
            def median(key, runs=ok):
                return float(np.median([r["metrics"][key] for r in runs]))
            cells.append(" / ".join(f"{median(f'{p}.tracking_error_rms'):.2e}"
                                    for p in PHASES))
            ratios = []
            for p in ("phase2", "phase3"):
                pairs = [r["metrics"][f"{p}.tracking_error_rms"]
                         / nominal[(r["scenario"], r["seed"])]["metrics"][
                             f"{p}.tracking_error_rms"] for r in ok
                         if nominal.get((r["scenario"], r["seed"]), {}).get("status") == "ok"]
                ratios.append(f"{np.median(pairs):.2f}" if pairs else "nominal diverged")
            cells.append(" / ".join(ratios))
            for name in ("B", "D"):
                key = f"{name}_error_ratio_scaled" if "phase1.B_error_ratio_scaled" in \
                    ok[0]["metrics"] else f"{name}_error_ratio"
                cells.append(" / ".join(f"{median(f'{p}.{key}'):.2f}" for p in PHASES))
            verified = [r for r in ok if "verify" in r]
            cells.append(f"{100 * max(r['settled_rejections'] for r in verified):.1f} %"
                         if verified else "-")
            passed = sum(all(r["verify"].values()) for r in verified)
            cells.append(f"{passed} of {len(verified)}" if verified else "not run")
        else:
            cells += ["diverged: " + group[0]["reason"][:40]] + [""] * 5
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", default="results/model_error")
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--spatial", action="store_true",
                        help="also the spatial arms with their inertias 20 %% off")
    args = parser.parse_args()
    scenarios = (["x0.4", "inertia +-20 %"] if args.quick else
                 ["nominal", "x0.4", "x3", "x0.5,x2.5", "fault", "inertia +-20 %",
                  "inertia -+20 %", "inertia each +-20 %"])
    seeds = [0] if args.quick else [0, 1]
    tasks = [(s, k, "shipped defaults", "dac-nominal") for s in scenarios for k in seeds]
    tasks += [(s, k, c, "dac") for s in scenarios for c in CONFIGURATIONS for k in seeds
              if c != "exact model" or s.startswith("inertia")]
    if args.spatial:
        for name in SPATIAL:
            tasks += [(name, 0, "shipped defaults", "dac-nominal")]
            tasks += [(name, 0, c, "dac") for c in ("shipped defaults", "exact model",
                                                    "no inertial identification",
                                                    "no hold on a new model",
                                                    "no step guard")]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    with ProcessPoolExecutor(args.workers) as pool, open(out / "runs.jsonl", "w") as f:
        rows = []
        for row in pool.map(run, tasks):
            rows.append(row)
            f.write(json.dumps(row) + "\n")
            f.flush()
    (out / "table.md").write_text(table(rows))
    print(table(rows))


if __name__ == "__main__":
    main()
