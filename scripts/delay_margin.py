"""The largest command delay `dacph verify` says the RHS loop tolerates, against the
first delay at which a simulated run diverges or fails verify (run:
.venv/bin/python scripts/delay_margin.py --out results/delay_margin).

For each robot: a run without delay gives verify's predictions (delay_tolerance: the
largest delay keeping the loop stable at the truth's least-margin sample, so the
first unstable delay is one more; and the largest keeping it decaying at lambda_LHS,
the first delay past it the first unseparated one); then runs with sensing.unmodelled_delay = 1, 2, ...
(a delay the controller does not know of, so its gains stay those it designed without
one) until one diverges or its Lyapunov envelope fails. Under DAC (learning) and
dac-nominal (the learner off: the gains do not follow what the delayed run's data
teach). Phases 0.25 + 3 x 1 s."""
import argparse
import json
from pathlib import Path

from dacph_drake.assembly.scenario_files import load_scenario
from dacph_drake.loop.simulate import simulate
from dacph_drake.loop.verify import verify_logs
from dacph_drake.scenario import Phases, Sensing

ROBOTS = ("short", "satellite_3dof", "satellite_6dof", "scenarios/ur5.yaml")


def scenario_of(name: str, delay: int, lag: float):
    scenario = load_scenario(name)
    scenario.phases = Phases(warmup=0.25, linear=1.0, nonlinear=1.0, disturbance=1.0)
    scenario.sensing = Sensing(enabled=True, unmodelled_delay=delay, actuator_lag=lag)
    return scenario


def fails(name: str, delay: int, lag: float, controller: str) -> str:
    """Why the run with this delay fails: it diverges or its Lyapunov envelope fails
    ("" when neither)."""
    scenario = scenario_of(name, delay, lag)
    run = simulate(scenario, controller)
    if run.status != "ok":
        return f"{run.status}: {run.reason}"
    report = verify_logs(run.logs, scenario, {"status": run.status}, region_budget=0.0)
    envelope = report["checks"]["lhs_envelope"]
    return "" if envelope["ok"] else f"envelope: {envelope.get('reason', 'failed')}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--robots", nargs="*", default=list(ROBOTS))
    parser.add_argument("--lag", type=float, default=0.0, help="actuator lag [s]")
    parser.add_argument("--controllers", nargs="*", default=["dac", "dac-nominal"])
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    rows = []
    for name in args.robots:
        for controller in args.controllers:
            scenario = scenario_of(name, 0, args.lag)
            run = simulate(scenario, controller)
            tolerance = verify_logs(run.logs, scenario, {"status": run.status},
                                    region_budget=0.0)["delay_tolerance"]
            predicted = tolerance["stable_samples"] + 1    # the first unstable delay
            # The first delay at which the RHS loop decays slower than lambda_LHS.
            unseparated = tolerance["separated_samples"] + 1
            first, why = None, ""
            for delay in range(1, 3 * predicted + 4):
                why = fails(name, delay, args.lag, controller)
                print(f"{name} {controller}: delay {delay}: {why or 'ok'}", flush=True)
                if why:
                    first = delay
                    break
            row = {"robot": name, "controller": controller, "lag": args.lag,
                   "predicted_first_unstable": predicted,
                   "predicted_first_unseparated": unseparated,
                   "simulated_first_failure": first, "why": why,
                   "relative_difference": (abs(first - predicted) / first
                                           if first else None),
                   "relative_difference_unseparated": (abs(first - unseparated) / first
                                                       if first else None),
                   "tolerance": tolerance}
            rows.append(row)
            print(json.dumps(row), flush=True)
    (args.out / f"rows_lag_{args.lag:g}.json").write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
