"""The armature ablation (run: .venv/bin/python scripts/armature_ablation.py --arms 8
--out results/armature_ablation): MJCF arms of the zoo's family with armature
(scripts/zoo.py mjcf_extras: each joint's reflected rotor inertia 0.5-3 times its
link's own inertia about the joint), run by DAC and the model-based baseline twice each: with
the LHS model carrying the armature, as the library builds it, and with the LHS model
without it (the controller's FloatingBaseModel's reflected inertias zeroed; the ground
truth, Drake's plant, keeps them). Each run in a fresh process. Rows go to
OUT/rows.jsonl, the table to OUT/table.md.
"""
import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "scripts"))

CHILD = r"""
import json, sys
import numpy as np
path, model_armature, controller = sys.argv[1], sys.argv[2] == "1", sys.argv[3]
from dacph_drake.dynamics import floating_model
if not model_armature:
    original = floating_model.FloatingBaseModel.kernel_tree
    def without_armature(self):
        tree = original.fget(self)
        return tree[:-1] + (np.zeros_like(tree[-1]),)
    floating_model.FloatingBaseModel.kernel_tree = property(without_armature)
from dacph_drake.loop.metrics import run_metrics
from dacph_drake.loop.simulate import simulate
from dacph_drake.assembly.scenario_files import load_scenario
scenario = load_scenario(path)
result = simulate(scenario, controller)
metrics = run_metrics(result.logs, scenario) if result.status == "ok" else {}
print(json.dumps({"status": result.status, "reason": result.reason,
                  "rms": [metrics.get(f"phase{k}.tracking_error_rms") for k in (1, 2, 3)]},
                 default=float))
"""


def run(path: Path, model_armature: bool, controller: str) -> dict:
    env = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}
    done = subprocess.run([sys.executable, "-c", CHILD, str(path),
                           "1" if model_armature else "0", controller],
                          capture_output=True, text=True, cwd=path.parent, env=env)
    try:
        return json.loads(done.stdout.strip().splitlines()[-1])
    except (IndexError, json.JSONDecodeError):
        return {"status": "error", "reason": done.stderr.strip()[-300:], "rms": []}


def main() -> None:
    from zoo import OWN, family, scenario_file
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--arms", type=int, default=8)
    parser.add_argument("--seed", type=int, default=21)
    parser.add_argument("--joints", type=int, nargs=2, default=(3, 7))
    parser.add_argument("--out", default="results/armature_ablation")
    args = parser.parse_args()
    out = Path(args.out)
    (out / "files").mkdir(parents=True, exist_ok=True)
    arms = family(args.arms, args.seed, tuple(args.joints))
    OWN.update(arms)
    rows_path = out / "rows.jsonl"
    done = {json.loads(line)["arm"] for line in rows_path.read_text().splitlines()} \
        if rows_path.exists() else set()
    for name in arms:
        if name in done:
            continue
        path = scenario_file((out / "files").resolve(), name, "attitude", "mjcf")
        row = {"arm": name, "n": len(arms[name][0])}
        for label, model_armature in (("with", True), ("without", False)):
            for controller in ("dac", "model-based"):
                row[f"{controller} {label}"] = run(path, model_armature, controller)
        with rows_path.open("a") as f:
            f.write(json.dumps(row, default=float) + "\n")
        print(json.dumps(row, default=float)[:300], flush=True)
    rows = [json.loads(line) for line in rows_path.read_text().splitlines()]
    (out / "table.md").write_text(table(rows))
    print(table(rows))


def _worst(run: dict) -> float:
    """The worst of phases 2 and 3's RMS error (nan unless the run finished)."""
    if run.get("status") != "ok" or len(run.get("rms", [])) < 3:
        return float("nan")
    return max(run["rms"][1], run["rms"][2])


def table(rows) -> str:
    """The ablation's table: each arm's worst phase-2/3 RMS attitude error [rad] of
    DAC and the baseline with and without the armature in the LHS model."""
    lines = ["| arm | n | DAC, model with armature | DAC, without | baseline, with | "
             "baseline, without |", "|---|---|---|---|---|---|"]
    ratios = {"dac": [], "model-based": []}
    for row in rows:
        cells = []
        for controller in ("dac", "model-based"):
            with_, without = (_worst(row[f"{controller} {label}"])
                              for label in ("with", "without"))
            ratios[controller].append(without / with_)
            cells += [f"{with_:.2e}", f"{without:.2e}" if np.isfinite(without) else
                      row[f"{controller} without"].get("status", "-")]
        lines.append(f"| {row['arm']} | {row['n']} | " + " | ".join(
            [cells[0], cells[1], cells[2], cells[3]]) + " |")
    summary = []
    for controller, values in ratios.items():
        values = np.array(values, float)
        finite = values[np.isfinite(values)]
        summary.append(f"- {controller}: without / with the armature in the LHS model, "
                       f"median {np.median(finite):.2f}, range {finite.min():.2f}-"
                       f"{finite.max():.2f} over {len(finite)} arms; "
                       f"{len(values) - len(finite)} runs without it did not finish"
                       if len(finite) else f"- {controller}: no finished pair")
    return "\n".join(lines) + "\n\n" + "\n".join(summary) + "\n"


if __name__ == "__main__":
    main()
