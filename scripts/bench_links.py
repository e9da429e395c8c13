"""Planar arms of n links (run: .venv/bin/python scripts/bench_links.py).

For each n (--links, default 2 3 4 5 6 8), an arm of n equal links (1 kg, 0.5 m,
0.02 kg m^2) and one of n tapering links (each link 0.8 times the mass and 0.85
times the length of the one before), from a scenario naming only robot.truth and
the short scenario's phases (assembly.registry.sized_defaults sizes the rest), in a
fresh process each: the build time of the DAC diagram (its inertia bounds, the grid
for two links and the search beyond, included), then the DAC run through all
phases: its status, wall time per simulated second, and per phase the tracking
error and the learned B's error against the prior's (B_error_ratio).

--out FILE also writes the table there (results/performance/links.txt).
"""
import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

CHILD = r"""
import json, sys, time
from dacph_drake.controllers import build_closed_loop
from dacph_drake.loop.simulate import simulate
from dacph_drake.assembly.scenario_files import load_scenario
start = time.perf_counter()
scenario = load_scenario(sys.argv[1])
loaded = time.perf_counter() - start
start = time.perf_counter()
build_closed_loop("dac", scenario)
built = time.perf_counter() - start
result = simulate(scenario, "dac")
from dacph_drake.loop.metrics import run_metrics
metrics = run_metrics(result.logs, scenario)
print(json.dumps({"load": loaded, "build": built, "status": result.status,
                  "reason": result.reason,
                  "per_second": result.wall_time / max(result.final_time, 1e-9),
                  "tracking": [metrics.get(f"phase{k}.tracking_error_rms", float("nan"))
                               for k in (1, 2, 3)],
                  "B_ratio": [metrics.get(f"phase{k}.B_error_ratio", float("nan"))
                              for k in (1, 2, 3)]}))
"""


def _arm_file(folder: Path, n: int, taper: float) -> Path:
    links = "\n".join(
        f"      - {{mass: {taper**k:.6g}, length: {0.5 * (0.85 if taper < 1 else 1)**k:.6g}, "
        f"inertia: {0.02 * taper**k * (0.85 if taper < 1 else 1)**(2 * k):.6g}, "
        f"com: {0.25 * (0.85 if taper < 1 else 1)**k:.6g}}}" for k in range(n))
    path = folder / f"arm{n}_{taper:g}.yaml"
    path.write_text("robot: !PlanarArm\n  truth:\n    links:\n" + links + "\n"
                    "phases: {warmup: 2.0, linear: 8.0, nonlinear: 8.0, "
                    "disturbance: 8.0}\n")
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--links", type=int, nargs="+", default=[2, 3, 4, 5, 6, 8])
    parser.add_argument("--out", default=None)
    args = parser.parse_args()
    lines = ["| links | arm | build [s] | status | wall s per simulated s | tracking "
             "rms, phases 1/2/3 [rad] | B_error_ratio, phases 1/2/3 |",
             "| --- | --- | --- | --- | --- | --- | --- |"]
    print("\n".join(lines), flush=True)
    with tempfile.TemporaryDirectory() as folder:
        for n in args.links:
            for taper, name in ((1.0, "equal"), (0.8, "tapering")):
                path = _arm_file(Path(folder), n, taper)
                child = subprocess.run([sys.executable, "-c", CHILD, str(path)],
                                       capture_output=True, text=True)
                if child.returncode != 0:
                    line = (f"| {n} | {name} | - | failed: "
                            f"{(child.stderr.strip().splitlines() or ['?'])[-1]} | | | |")
                else:
                    r = json.loads(child.stdout.strip().splitlines()[-1])
                    status = r["status"] + (f" ({r['reason']})" if r["reason"] else "")
                    line = (f"| {n} | {name} | {r['build']:.1f} | {status} | "
                            f"{r['per_second']:.2f} | "
                            + " / ".join(f"{v:.2g}" for v in r["tracking"]) + " | "
                            + " / ".join(f"{v:.2f}" for v in r["B_ratio"]) + " |")
                lines.append(line)
                print(line, flush=True)
    if args.out:
        Path(args.out).write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
