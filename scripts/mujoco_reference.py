"""MJCF arms read by the library against MuJoCo's own model of each file (run:
.venv/bin/python scripts/mujoco_reference.py [--family N --seed S] [--out DIR]).

Every robosuite arm as robosuite ships it (where robosuite is installed: pip install
--no-deps robosuite==1.5.2) and N random MJCF arms of the zoo's family
(scripts/zoo.py --format mjcf: an include, a default class, armature, frictionloss,
inertia from geoms): robots.mujoco_reference.compare_with_mujoco at 5 random joint
angles each (within the joints' limits). Writes DIR/table.md."""
import argparse
import importlib.util
import logging
import tempfile
from pathlib import Path

from zoo import OWN, SHIPPED, family, scenario_file
from dacph_drake.robots.mujoco_reference import compare_with_mujoco


def _robosuite_arms():
    """(name, robot.xml, end-effector frame) of robosuite's arms, where it is installed."""
    spec = importlib.util.find_spec("robosuite")
    if spec is None:
        return []
    root = Path(spec.submodule_search_locations[0])
    prefix = "package://robosuite/"
    return [(name, root / description[len(prefix):], frame)
            for name, (description, frame, _) in SHIPPED.items()
            if description.startswith(prefix)]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--family", type=int, default=32, help="random MJCF arms")
    parser.add_argument("--seed", type=int, default=0, help="the family's seed")
    parser.add_argument("--out", default="results/mujoco_reference")
    args = parser.parse_args()
    logging.disable(logging.WARNING)        # Drake's notes on the files' unused tags
    folder = Path(tempfile.mkdtemp())
    arms = _robosuite_arms()
    generated = family(args.family, args.seed)
    OWN.update(generated)
    for name in generated:
        scenario_file(folder, name, form="mjcf")
        arms.append((name, folder / f"{name}.xml", "tool"))
    lines = ["| arm | joints | max abs(H_mm - M_mujoco) / max abs(M) | damping | "
             "frictionloss | limits [rad] |", "|---|---|---|---|---|---|"]
    worst = 0.0
    for name, path, frame in arms:
        d = compare_with_mujoco(path, frame, seed=args.seed)
        worst = max(worst, d.mass_matrix)
        lines.append(f"| {name} | {d.joints} (MuJoCo: {d.dofs}) | {d.mass_matrix:.1e} | "
                     f"{d.damping:.1e} | {d.frictionloss:.1e} | {d.limits:.1e} |")
        print(lines[-1], flush=True)
    lines.append(f"\n{len(arms)} arms; the largest mass-matrix difference {worst:.1e}.")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "table.md").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
