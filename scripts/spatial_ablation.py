"""The spatial robots' ablation (docs/results/spatial.md): DAC, its learner-off
ablation (dac-nominal) and the model-based baseline on the shipped spatial scenarios,
DAC and dac-nominal with two seeds. Prints the Markdown table, writes it to --table
(the site includes results/spatial/table.md) and every run's metrics to --out
(JSON). About 1 minute on one core.

    .venv/bin/python scripts/spatial_ablation.py --table results/spatial/table.md \
        --out results/spatial/runs.json
"""
import argparse
import json
from pathlib import Path

from dacph_drake.loop.metrics import run_metrics
from dacph_drake.loop.simulate import simulate
from dacph_drake.assembly.scenario_files import load_scenario

RUNS = [("dac", 0), ("dac", 1), ("dac-nominal", 0), ("dac-nominal", 1),
        ("model-based", 0)]


def _phases(metrics, name, digits):
    return " / ".join(f"{metrics[f'phase{k}.{name}']:.{digits}}" for k in (1, 2, 3))


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--out", default=None, help="JSON file for every run's metrics")
    parser.add_argument("--table", default=None, help="Markdown file for the table")
    parser.add_argument("--robots", nargs="+", default=["satellite_6dof", "satellite_3dof"])
    args = parser.parse_args()
    rows, table = [], []

    def line(text):
        print(text, flush=True)
        table.append(text)
    line("| robot, controller, seed | \\|e\\| RMS phase 1 / 2 / 3 [rad] | "
         "B learned / nominal | D learned / nominal | min clearance [m] |")
    line("| --- | --- | --- | --- | --- |")
    for robot in args.robots:
        for controller, seed in RUNS:
            scenario = load_scenario(robot)
            scenario.seed = seed
            result = simulate(scenario, controller)
            m = run_metrics(result.logs, scenario)
            rows.append({"robot": robot, "controller": controller, "seed": seed,
                         "status": result.status, "metrics": m})
            learned = (f"{_phases(m, 'B_error_ratio', '2f')} | "
                       f"{_phases(m, 'D_error_ratio', '2f')}"
                       if "phase1.B_error_ratio" in m else "- | -")
            line(f"| {robot}, {controller}, {seed} | "
                 f"{_phases(m, 'tracking_error_rms', '2e')} | {learned} | "
                 f"{m['min_clearance']:.3f} |")
    if args.table:
        Path(args.table).parent.mkdir(parents=True, exist_ok=True)
        Path(args.table).write_text("\n".join(table) + "\n")
    if args.out:
        with open(args.out, "w") as f:
            json.dump(rows, f, indent=1)


if __name__ == "__main__":
    main()
