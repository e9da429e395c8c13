"""Command line: ``dacph <command> ...`` (``dacph --help`` lists the commands)."""
import argparse
import sys

import numpy as np

from dacph_drake.errors import ConfigError


def _free_flight(args) -> int:
    from dacph_drake.free_flight import run_free_flight
    from dacph_drake.robot import RobotParams, load_robot
    robot = load_robot(args.robot) if args.robot else RobotParams()
    n = robot.num_links
    result = run_free_flight(robot, args.duration, amplitudes=np.full(n, 0.006),
                             frequencies=3.0 + np.arange(n), q0=np.full(n, 0.3))
    drift = abs(result.kinetic_energy - result.work) / max(result.kinetic_energy, 1e-300)
    print(f"free flight, {args.duration:g} s, {n} links")
    print(f"  max |momentum|            {result.max_momentum:.3e}  (zero at start)")
    print(f"  kinetic energy            {result.kinetic_energy:.9e} J")
    print(f"  work done by torques      {result.work:.9e} J")
    print(f"  relative energy mismatch  {drift:.3e}")
    print(f"  min arm-base clearance    {result.min_clearance:.4f} m")
    return 0


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="dacph", description=__doc__)
    commands = parser.add_subparsers(dest="command", required=True)
    free = commands.add_parser(
        "free-flight", help="passive simulation of the ground truth: momentum and "
                            "energy bookkeeping")
    free.add_argument("--robot", help="robot YAML (default: the paper's robot)")
    free.add_argument("--duration", type=float, default=10.0, help="[s]")
    free.set_defaults(run=_free_flight)
    args = parser.parse_args(argv)
    try:
        return args.run(args)
    except ConfigError as e:
        print(f"dacph: error: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
