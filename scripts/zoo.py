"""The zoo: arms as their makers ship them, each from a scenario file of at most six
lines (run: .venv/bin/python scripts/zoo.py --out results/zoo).

Every manipulator of example-robot-data (Panda, UR3/5/10, Kinova j2s6s200, xArm7,
Unitree Z1, SO-100, SO-101), every arm of robosuite 1.5.2 (its MJCF robot.xml files:
Panda, Sawyer, iiwa, Jaco, Kinova3, xArm7, UR5e), dm_control's Jaco, and arms of our
own with extreme properties (heavy
joint damping, a tiny wrist, a chain of 9 joints, a heavy tool, a light base:
URDFs written by this script), each from a file naming only the description, the
base's mass, the end-effector frame and the locked gripper joints. For each arm,
in a fresh process each: DAC, dac-nominal (the learning ablation) and the
model-based baseline through every phase, then `verify` on the DAC run: status,
RMS attitude error per phase, DAC / baseline in phases 2-3, verify's verdict and
time, wall time, the derived integration step, and the warning lines the run
printed. Rows go to OUT/rows.jsonl as they finish (a re-run skips the arms done);
OUT/table.md is the docs' results page table.

--files runs scenario files of your own instead. --quick runs the arms named by --arms (default: the CI short version's three) for
--duration seconds without verify. --family N runs N random arms of our own
(family: 3-9 joints, masses, lengths, damping, tools and bases drawn with --seed)
instead.
"""
import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

from dacph_drake.robots.serial_arm import (AXES, SerialLink, serial_arm_mjcf,
                                           serial_arm_urdf)

EXAMPLE = "package://example-robot-data/robots"
# name -> (description, end-effector frame, locked joints)
SHIPPED = {
    "panda": (f"{EXAMPLE}/panda_description/urdf/panda.urdf", "panda_link8", ""),
    "ur3": (f"{EXAMPLE}/ur_description/urdf/ur3_robot.urdf", "tool0", ""),
    "ur5": (f"{EXAMPLE}/ur_description/urdf/ur5_robot.urdf", "tool0", ""),
    "ur10": (f"{EXAMPLE}/ur_description/urdf/ur10_robot.urdf", "tool0", ""),
    "kinova_j2s6s200": (f"{EXAMPLE}/kinova_description/robots/kinova.urdf",
                        "j2s6s200_end_effector", ""),
    "xarm7": (f"{EXAMPLE}/xarm_description/urdf/xarm7.urdf", "link7", ""),
    "z1": (f"{EXAMPLE}/z1_description/urdf/z1.urdf", "link06", "jointGripper: 0.0"),
    "so100": (f"{EXAMPLE}/so_arm_description/urdf/so100.urdf", "gripper",
              "gripper: 0.0"),
    "so101": (f"{EXAMPLE}/so_arm_description/urdf/so101.urdf", "gripper_link",
              "gripper: 0.0"),
}
# robosuite's arms, each from its own robot.xml as robosuite 1.5.2 ships it (MJCF: STL
# meshes, massless mount bodies; pip install --no-deps robosuite==1.5.2).
ROBOSUITE = "package://robosuite/models/assets/robots"
SHIPPED.update({f"robosuite_{arm}": (f"{ROBOSUITE}/{arm}/robot.xml", "right_hand", "")
                for arm in ("panda", "sawyer", "iiwa", "jaco", "kinova3", "xarm7",
                            "ur5e")})
# dm_control's Jaco (MJCF: mesh inertias in MuJoCo's legacy mode, armature 2-4 and
# frictionloss 1-2 on every joint; pip install --no-deps dm_control).
SHIPPED["dm_control_jaco"] = ("package://dm_control/third_party/kinova/jaco_arm.xml",
                              "b_6", "")
# Arms of our own (robots.serial_arm): (links as (mass [kg], length [m], damping
# [N m s/rad]), tool mass [kg], base mass [kg]).
OWN = {
    "heavy_damping": ([(4.0, 0.4, 20.0), (3.0, 0.35, 20.0), (2.0, 0.3, 10.0),
                       (1.0, 0.2, 5.0), (0.5, 0.1, 5.0), (0.3, 0.08, 5.0)], 0.0, 200.0),
    "tiny_wrist": ([(4.0, 0.4, 0.0), (3.0, 0.35, 0.0), (2.0, 0.3, 0.0),
                    (0.05, 0.03, 0.0), (0.02, 0.02, 0.0), (0.01, 0.02, 0.0)], 0.0, 200.0),
    "chain9": ([(2.0 * 0.85**k, 0.3 * 0.9**k, 0.0) for k in range(9)], 0.0, 200.0),
    "heavy_tool": ([(4.0, 0.4, 0.0), (3.0, 0.35, 0.0), (2.0, 0.3, 0.0),
                    (1.0, 0.2, 0.0), (0.5, 0.1, 0.0), (0.3, 0.08, 0.0)], 5.0, 200.0),
    "light_base": ([(4.0, 0.4, 0.0), (3.0, 0.35, 0.0), (2.0, 0.3, 0.0),
                    (1.0, 0.2, 0.0), (0.5, 0.1, 0.0), (0.3, 0.08, 0.0)], 0.0, 20.0),
}
QUICK = ("xarm7", "heavy_damping", "z1")


def family(count: int, seed: int, joints=(3, 9)) -> dict:
    """``count`` random serial arms (robots.serial_arm), as OWN's entries: ``joints``
    (3 to 9) joints; link masses log-uniform in [0.02, 5] kg and lengths uniform in [0.03,
    0.45] m, both tapering on average; half the arms with joint damping
    log-uniform in [0.01, 20] N m s/rad; a third with a tool of 0.5-5 kg; the base
    log-uniform in [15, 500] kg; the axes' cycle (z, y, x) started anywhere."""
    import numpy as np
    rng = np.random.default_rng(seed)
    arms = {}
    for k in range(count):
        n = int(rng.integers(joints[0], joints[1] + 1))
        taper = np.linspace(1.0, 0.3, n)
        mass = np.exp(rng.uniform(np.log(0.02), np.log(5.0), n)) * taper
        length = rng.uniform(0.03, 0.45, n) * taper
        damped = rng.random() < 0.5
        damping = (np.exp(rng.uniform(np.log(0.01), np.log(20.0), n)) if damped
                   else np.zeros(n))
        tool = float(rng.uniform(0.5, 5.0)) if rng.random() < 1 / 3 else 0.0
        base = float(np.exp(rng.uniform(np.log(15.0), np.log(500.0))))
        offset = int(rng.integers(3))
        arms[f"family_{seed}_{k:03d}"] = (
            [(float(m), float(max(l, 0.01)), float(d))
             for m, l, d in zip(mass, length, damping)], tool, base, offset)
    return arms


def mjcf_extras(name: str, links) -> dict:
    """What an MJCF of a family arm adds (its own draws, seeded by the arm's name, so
    the arm is the URDF family's): each joint's armature uniform in [0.5, 3] times its
    link's own inertia about its joint (geared motors: a reflected rotor inertia of the
    order of the link's), every joint's frictionloss log-uniform in
    [0.01, 0.1] N m (ignored by default: robot.joint_friction), each link's inertia from
    its geom with probability 1/2."""
    import zlib
    import numpy as np
    rng = np.random.default_rng(zlib.crc32(name.encode()))
    lateral = np.array([m * l * l / 3 for m, l, _ in links])
    return {"armature": (rng.uniform(0.5, 3.0, len(links)) * lateral).tolist(),
            "frictionloss": float(np.exp(rng.uniform(np.log(0.01), np.log(0.1)))),
            "from_geoms": (rng.random(len(links)) < 0.5).tolist()}
CONTROLLERS = ("dac", "dac-nominal", "model-based")

CHILD = r"""
import json, sys, time, io, logging
stream = io.StringIO()
handler = logging.StreamHandler(stream)
logging.getLogger().addHandler(handler)
from dacph_drake.loop.metrics import run_metrics
from dacph_drake.loop.verify import verify_logs
from dacph_drake.loop.simulate import simulate
from dacph_drake.assembly.scenario_files import load_scenario
path, duration, with_verify = sys.argv[1], float(sys.argv[2]), sys.argv[3] == "1"
row = {}
start = time.perf_counter()
try:
    scenario = load_scenario(path)
except Exception as e:
    print(json.dumps({"error": f"{type(e).__name__}: {e}",
                      "warnings": stream.getvalue().splitlines()}))
    sys.exit(0)
row["load_s"] = time.perf_counter() - start
row["step"] = scenario.simulator.max_step_size
row["num_joints"] = len(scenario.q0)
row["q0"] = [round(x, 3) for x in scenario.q0]
for controller in ("dac", "dac-nominal", "model-based"):
    try:
        result = simulate(scenario, controller,
                          duration=None if duration <= 0 else duration)
    except Exception as e:
        row[controller] = {"error": f"{type(e).__name__}: {e}"}
        continue
    metrics = run_metrics(result.logs, scenario)
    row[controller] = {"status": result.status, "reason": result.reason,
                       "wall_s": result.wall_time,
                       "rms": [metrics.get(f"phase{k}.tracking_error_rms")
                               for k in (1, 2, 3)]}
    if controller == "dac" and with_verify and result.status == "ok":
        start = time.perf_counter()
        report = verify_logs(result.logs, scenario, {"status": result.status,
                                                    "final_time": result.final_time})
        region = report["checks"]["region_of_attraction"]
        row["verify"] = {"ok": report["ok"], "seconds": time.perf_counter() - start,
                         "failed": [k for k, c in report["checks"].items()
                                    if not c["ok"]],
                         "s0_norm": region["s0_norm"],
                         "frozen_radius": region.get("frozen_radius")}
row["warnings"] = [line for line in stream.getvalue().splitlines() if line.strip()]
print(json.dumps(row, default=float))
"""


def scenario_file(folder: Path, name: str, task: str = "attitude",
                  form: str = "urdf") -> Path:
    """The arm's scenario file (at most six lines; with ``task`` "position", a line
    more: task: !EndEffectorPosition {}); an arm of our own as ``form`` "urdf" or
    "mjcf" (robots.serial_arm.serial_arm_mjcf with mjcf_extras)."""
    if name in SHIPPED:
        description, frame, locked = SHIPPED[name]
        base = 250.0
    else:
        links, tool, base, *offset = OWN[name]
        axes = AXES[offset[0]:] + AXES[:offset[0]] if offset else AXES
        if form == "mjcf":
            for file, text in serial_arm_mjcf(name, [SerialLink(*link) for link in links],
                                              tool, axes, **mjcf_extras(name, links)
                                              ).items():
                (folder / file).write_text(text)
            description = f"{name}.xml"
        else:
            urdf = folder / f"{name}.urdf"
            urdf.write_text(serial_arm_urdf(name, [SerialLink(*link) for link in links],
                                            tool, axes))
            description = urdf.name
        frame, locked = "tool", ""
    lines = ["robot: !DescribedArm", f"  description: {description}",
             f"  base: {{mass: {base:g}}}", f"  end_effector: {{frame: {frame}}}"]
    if locked:
        lines.append(f"  locked_joints: {{{locked}}}")
    if task == "position":
        lines.append("task: !EndEffectorPosition {}")
    path = folder / f"{name}.yaml"
    path.write_text("\n".join(lines) + "\n")
    return path


def _cell(value, form="{:.2e}") -> str:
    return "-" if value is None or value != value else form.format(value)


def table(rows, unit: str = "rad") -> str:
    """The results page's table of the rows (one line per arm; the task's error in
    ``unit``)."""
    lines = [f"| arm | n | step [s] | DAC RMS phases 1 / 2 / 3 [{unit}] | dac-nominal 2 / 3 "
             "| model-based 2 / 3 | DAC / baseline (2, 3) | verify | warning lines | "
             "wall DAC [s] |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for row in rows:
        if "error" in row:
            lines.append(f"| {row['arm']} | | | refused: {row['error'][:120]} "
                         "| | | | | | |")
            continue
        dac, nominal, base = (row.get(c, {}) for c in CONTROLLERS)

        def rms(run, phases):
            if "error" in run:
                return "error"
            if run.get("status") != "ok":
                return f"{run.get('status')}: {run.get('reason', '')[:60]}"
            return " / ".join(_cell(run["rms"][k - 1]) for k in phases)
        ratio = "-"
        if dac.get("status") == "ok" and base.get("status") == "ok":
            ratio = " / ".join(f"{dac['rms'][k] / base['rms'][k]:.3f}" for k in (1, 2))
        check = row.get("verify")
        verdict = ("-" if check is None else
                   f"{'PASS' if check['ok'] else 'FAIL ' + ','.join(check['failed'])} "
                   f"({check['seconds']:.0f} s)")
        lines.append(f"| {row['arm']} | {row['num_joints']} | {row['step']:.3g} | "
                     f"{rms(dac, (1, 2, 3))} | {rms(nominal, (2, 3))} | "
                     f"{rms(base, (2, 3))} | {ratio} | {verdict} | "
                     f"{len(row['warnings'])} | {_cell(dac.get('wall_s'), '{:.1f}')} |")
    return "\n".join(lines) + "\n"


def run_arm(folder: Path, name: str, duration: float, with_verify: bool,
            task: str = "attitude", form: str = "urdf") -> dict:
    """One arm of the zoo in a fresh process (run_file)."""
    return run_file(scenario_file(folder, name, task, form), name, duration, with_verify)


def run_file(path: Path, name: str, duration: float, with_verify: bool) -> dict:
    """The arm of a scenario file in a fresh process (one thread for the numerical
    libraries), in the file's folder."""
    env = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
           "MKL_NUM_THREADS": "1"}
    done = subprocess.run([sys.executable, "-c", CHILD, str(path), str(duration),
                           "1" if with_verify else "0"], capture_output=True, text=True,
                          cwd=path.parent, env=env)
    lines = done.stdout.strip().splitlines()
    try:
        row = json.loads(lines[-1])
    except (IndexError, json.JSONDecodeError):
        row = {"error": f"exit {done.returncode}: {done.stderr.strip()[-300:]}"}
    return {"arm": name, "file_lines": len(path.read_text().splitlines()), **row}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--arms", nargs="+", default=None,
                        help=f"default: all ({', '.join([*SHIPPED, *OWN])}); with "
                             f"--quick: {', '.join(QUICK)}")
    parser.add_argument("--out", default="results/zoo", help="folder of rows and table")
    parser.add_argument("--quick", action="store_true",
                        help="short runs (--duration), no verify")
    parser.add_argument("--duration", type=float, default=3.0,
                        help="[s] of each --quick run")
    parser.add_argument("--family", type=int, default=0,
                        help="run this many random arms of our own instead (family)")
    parser.add_argument("--seed", type=int, default=0, help="the family's seed")
    parser.add_argument("--joints", type=int, nargs=2, default=(3, 9),
                        metavar=("FEWEST", "MOST"), help="the family's joint counts")
    parser.add_argument("--task", choices=("attitude", "position"), default="attitude",
                        help="the task every arm tracks (position: task: "
                             "!EndEffectorPosition; its error in m)")
    parser.add_argument("--files", nargs="+", type=Path, default=None,
                        help="run these scenario files instead (arms of your own; each "
                             "named by its file's stem)")
    parser.add_argument("--format", choices=("urdf", "mjcf"), default="urdf",
                        help="the arms of our own as URDF or as MJCF (an include, a "
                             "default class, armature, frictionloss, inertia from "
                             "geoms: mjcf_extras)")
    args = parser.parse_args()
    if args.family:
        generated = family(args.family, args.seed, tuple(args.joints))
        OWN.update(generated)
        args.arms = list(generated)
    files = {path.stem: path.resolve() for path in args.files or []}
    arms = list(files) or args.arms or (list(QUICK) if args.quick else [*SHIPPED, *OWN])
    unknown = [a for a in arms if a not in SHIPPED and a not in OWN and a not in files]
    if unknown:
        parser.error(f"--arms: unknown {unknown}; allowed: {[*SHIPPED, *OWN]}")
    out = Path(args.out)
    unit = "m" if args.task == "position" else "rad"
    out.mkdir(parents=True, exist_ok=True)
    (out / "files").mkdir(exist_ok=True)
    rows_path = out / "rows.jsonl"
    done = {json.loads(line)["arm"]: json.loads(line)
            for line in rows_path.read_text().splitlines()} if rows_path.exists() else {}
    for name in arms:
        if name in done:
            continue
        start = time.perf_counter()
        duration = args.duration if args.quick else 0.0
        row = (run_file(files[name], name, duration, not args.quick) if name in files
               else run_arm((out / "files").resolve(), name, duration, not args.quick,
                            args.task, args.format))
        row["total_s"] = time.perf_counter() - start
        done[name] = row
        with rows_path.open("a") as f:
            f.write(json.dumps(row, default=float) + "\n")
        print(table([row], unit).splitlines()[-1], flush=True)
    rows = [done[name] for name in [*SHIPPED, *OWN, *files] if name in done]
    (out / "table.md").write_text(table(rows, unit) + "\n" + summary(rows, unit))
    print(table(rows, unit) + "\n" + summary(rows, unit))


def summary(rows, unit: str = "rad") -> str:
    """The targets over the rows: how many arms meet each (the error in ``unit``)."""
    ran = [r for r in rows if "error" not in r
           and not any("error" in r.get(c, {}) for c in CONTROLLERS)]
    every = [r for r in ran if all(r.get(c, {}).get("status") == "ok"
                                   for c in CONTROLLERS)]
    dac = [r for r in ran if r.get("dac", {}).get("status") == "ok"]
    worst = [max(r["dac"]["rms"][1:]) for r in dac]
    ratio = [max(r["dac"]["rms"][k] / r["model-based"]["rms"][k] for k in (1, 2))
             for r in every]
    checked = [r for r in ran if "verify" in r]
    return (f"| target ({len(rows)} arms) | met by |\n|---|---|\n"
            f"| loaded and built (no refusal, no traceback) | {len(ran)} |\n"
            f"| every controller runs every phase | {len(every)} |\n"
            f"| DAC RMS phases 2-3 <= 1e-4 {unit} | {sum(w <= 1e-4 for w in worst)} "
            f"(worst {max(worst, default=float('nan')):.2e}) |\n"
            f"| DAC <= 0.1x the baseline (phases 2-3) | {sum(x <= 0.1 for x in ratio)} "
            f"of {len(ratio)} (worst {max(ratio, default=float('nan')):.3f}) |\n"
            f"| verify passes | {sum(r['verify']['ok'] for r in checked)} of "
            f"{len(checked)} (longest {max((r['verify']['seconds'] for r in checked), default=0):.0f} s) |\n")


if __name__ == "__main__":
    main()
