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


KNOWN_DIVERGENCE = pytest.mark.xfail(
    strict=True, reason="issue 3 open: the DAC loop runs away (a joint rate > 50 rad/s) "
                        "at t = 18.4 s, 0.4 s after d(t) switches on; cause not found yet")


@KNOWN_DIVERGENCE
def test_runs_finish_and_save(runs):
    scenario, out, results = runs
    for controller, result in results.items():
        assert result.status == "ok", result.reason
        assert result.final_time == pytest.approx(scenario.duration)
        assert (out / f"logs_{controller}.npz").exists()
        assert (out / f"run_{controller}.json").exists()
    assert load_scenario(out / "scenario.yaml") == scenario


@KNOWN_DIVERGENCE
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
    # The learner's loss falls within each phase: the last learner update of
    # phase 2 against its first updates after the nonlinear terms switch on.
    t, loss = logs["time"], logs["learner_log"][:, 0]
    start = scenario.phases.nonlinear_start
    early = np.median(loss[(t > start + 0.1) & (t < start + 1.0)])
    late = np.median(loss[(t > scenario.phases.disturbance_start - 1.0)
                          & (t < scenario.phases.disturbance_start)])
    assert late < 0.5 * early
    # Estimates move from the nominal towards the truth.
    assert m["estimation_error_B"] < 0.63 and m["estimation_error_D"] < 0.30


@KNOWN_DIVERGENCE
def test_dac_beats_model_based_once_the_disturbance_is_on(runs):
    scenario, _, results = runs
    assert all(r.status == "ok" for r in results.values())   # whole phase 3 compared
    dac = run_metrics(results["dac"].logs, scenario)
    model_based = run_metrics(results["model-based"].logs, scenario)
    assert dac["tracking_error_rms_phase3"] < model_based["tracking_error_rms_phase3"]
    assert comparison(dac, model_based)["tracking_error_reduction"] > 0.5
