"""End to end on the short scenario (CI): DAC tracks alpha_d, learns, keeps the arm
off the base, and beats the model-based baseline once the disturbance is on."""
from pathlib import Path

import numpy as np
import pytest

from dacph_drake.metrics import comparison, run_metrics
from dacph_drake.run import simulate
from dacph_drake.scenario import load_scenario

SHORT = Path(__file__).resolve().parents[1] / "diagrams" / "short.yaml"


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    scenario = load_scenario(SHORT)
    out = tmp_path_factory.mktemp("short")
    results = {c: simulate(scenario, c, out_dir=out) for c in ("dac", "model-based")}
    return scenario, out, results


def test_runs_finish_and_save(runs):
    scenario, out, results = runs
    for controller, result in results.items():
        assert result.status == "ok", result.reason
        assert result.final_time == pytest.approx(scenario.duration)
        assert (out / f"logs_{controller}.npz").exists()
        assert (out / f"run_{controller}.json").exists()
    assert load_scenario(out / "scenario.yaml") == scenario


def test_dac_tracks_learns_and_stays_clear(runs):
    scenario, _, results = runs
    logs = results["dac"].logs
    m = run_metrics(logs, scenario)
    # Tracking bound over phases 1-3 (alpha_d swings by +-0.4 rad).
    assert m["tracking_error_rms"] < 5e-4
    assert m["tracking_error_max"] < 3e-3
    # The arm never touches the base (clearance of the link outline, metres).
    assert m["min_clearance"] > 0.0
    # c always satisfies the gain rule (eq. 48).
    assert m["c_min_over_bound"] >= 1.0
    # The learner's loss, relative to the nominal RHS's loss on the same window,
    # falls within phases 1 and 2 and ends each well below the prior.
    t = logs["time"]
    relative = logs["learner_log"][:, 0] / logs["learner_log"][:, 2]
    phases = scenario.phases
    for start, end in [(phases.linear_start, phases.nonlinear_start),
                       (phases.nonlinear_start, phases.disturbance_start)]:
        early = np.median(relative[(t > start + 0.1) & (t < start + 1.0)])
        late = np.median(relative[(t > end - 1.0) & (t < end)])
        assert late < 0.5 * early and late < 0.01, (start, early, late)
    # Estimates at the end of phase 2 within the paper's errors (63 %, 30 %).
    assert m["estimation_error_B"] < 0.63 and m["estimation_error_D"] < 0.30
    # Every estimate used before d(t) switches on passed the DIC and trust checks.
    before = t < phases.disturbance_start
    assert np.all(logs["rhs_log"][before, -1] == 1.0)


def test_dac_beats_model_based_once_the_disturbance_is_on(runs):
    scenario, _, results = runs
    assert all(r.status == "ok" for r in results.values())   # whole phase 3 compared
    dac = run_metrics(results["dac"].logs, scenario)
    model_based = run_metrics(results["model-based"].logs, scenario)
    assert dac["tracking_error_rms_phase3"] < model_based["tracking_error_rms_phase3"]
    assert comparison(dac, model_based)["tracking_error_reduction"] > 0.5
