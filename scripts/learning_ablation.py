"""Which part of the network learner earns what (learner.model: network): the DAC
loop on the short scenario (and a second, harder variant of it) with the paper's
plain learner and with the regularized network learner minus one component at a
time, over several learner seeds. (The local Bayesian learner's ablation is
scripts/learning_families.py's variants.)

    .venv/bin/python scripts/learning_ablation.py --out runs/learning_ablation

Writes ablation.md (the table quoted in docs/concepts/identifiability.md) and ablation.json (every run's
metrics). Each row is the median over scenarios x seeds of the per-phase
learned / nominal error ratios of B and D (below 1: learning beats the prior B0,
D0), with the largest share of rejected B_hat, the RMS e_tau of phases 1-2 and the
RMS alpha~ over phases 1-3.
"""
import argparse
import copy
import json
import multiprocessing
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from dacph_drake.loop.metrics import PHASES, run_metrics
from dacph_drake.loop.simulate import simulate
from dacph_drake.scenario import Scenario
from dacph_drake.scenario.built_in import short_scenario


def harder_short_scenario() -> Scenario:
    """The short scenario from another configuration, with 1.5 times the linear and
    0.7 times the nonlinear uncertainty and 1.5 times the disturbance."""
    scenario = short_scenario()
    scenario.q0 = [0.5, 1.3]
    scenario.uncertainty.linear_scale = 1.5
    scenario.uncertainty.nonlinear_scale = 0.7
    scenario.disturbance.scale = 1.5
    return scenario


SCENARIOS = {"short": short_scenario, "short, harder": harder_short_scenario}


def _plain(s: Scenario) -> None:
    s.learner.mode = "plain"
    s.learner.learning_rate = 3e-3            # the learner's rate before regularization
    s.excitation.amplitude = 0.0


def _plain_excited(s: Scenario) -> None:
    s.learner.mode = "plain"
    s.learner.learning_rate = 3e-3


VARIANTS = {
    "paper's plain learner (no excitation)": _plain,
    "plain learner + excitation": _plain_excited,
    "regularized, no excitation": lambda s: setattr(s.excitation, "amplitude", 0.0),
    "regularized, no prior (rho = 0)": lambda s: setattr(s.learner, "prior_weight", 0.0),
    "regularized, no change detection": lambda s: setattr(s.learner, "change_ratio", 1e6),
    "regularized + excitation (default)": lambda s: None,
}


def run_one(task):
    scenario_name, variant, seed = task
    import torch
    torch.set_num_threads(1)
    scenario = copy.deepcopy(SCENARIOS[scenario_name]())
    scenario.learner.model = "network"
    scenario.rhs.adoption = "trust_band"
    VARIANTS[variant](scenario)
    scenario.seed = seed
    result = simulate(scenario, "dac")
    metrics = run_metrics(result.logs, scenario) if result.status == "ok" else None
    return {"scenario": scenario_name, "variant": variant, "seed": seed,
            "status": result.status, "reason": result.reason, "metrics": metrics}


def table(rows) -> str:
    lines = ["| learner | " + " | ".join(f"B ratio {k + 1}" for k in range(3)) + " | "
             + " | ".join(f"D ratio {k + 1}" for k in range(3))
             + " | max rejected | RMS e_tau 1-2 [N m] | RMS alpha~ [rad] | runs |",
             "|---|" + "---|" * 10]
    for variant in VARIANTS:
        ok = [r["metrics"] for r in rows if r["variant"] == variant and r["metrics"]]
        total = sum(r["variant"] == variant for r in rows)
        if not ok:
            lines.append(f"| {variant} | " + "- | " * 10 + f"0 of {total} finished |")
            continue
        median = lambda key: float(np.median([m[key] for m in ok]))  # noqa: E731
        cells = [f"{median(f'{p}.{x}_error_ratio'):.2f}" for x in "BD" for p in PHASES]
        rejected = max(m[f"{p}.rejected_share"] for m in ok for p in PHASES)
        e_tau = float(np.median([np.sqrt((m["phase1.e_tau_rms"]**2
                                          + m["phase2.e_tau_rms"]**2) / 2) for m in ok]))
        lines.append(f"| {variant} | " + " | ".join(cells)
                     + f" | {100 * rejected:.1f} % | {e_tau:.3g} | "
                       f"{median('tracking_error_rms'):.3g} | {len(ok)} of {total} |")
    return "\n".join(lines) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True)
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    tasks = [(s, v, seed) for s in SCENARIOS for v in VARIANTS for seed in args.seeds]
    with ProcessPoolExecutor(args.workers,
                             mp_context=multiprocessing.get_context("spawn")) as pool:
        rows = list(pool.map(run_one, tasks))
    (out / "ablation.json").write_text(json.dumps(rows, indent=1))
    text = (f"Median over scenarios {list(SCENARIOS)} x seeds {args.seeds} "
            "(learned / nominal error ratio per phase):\n\n" + table(rows))
    (out / "ablation.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
