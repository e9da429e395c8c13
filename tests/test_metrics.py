"""Metrics of SPEC section 9 on synthetic signals with known answers."""
import numpy as np
import pytest

from dacph_drake.log_layout import LearnerLog, RhsLog
from dacph_drake.loop.metrics import comparison, relative_error_rms, rms, run_metrics
from dacph_drake.app.reproduce import metrics_table
from dacph_drake.scenario.built_in import short_scenario


def test_rms_of_known_signals():
    t = np.linspace(0, 10, 100001)
    assert rms(0.3 * np.sin(2 * np.pi * t)) == pytest.approx(0.3 / np.sqrt(2), rel=1e-4)
    vector = np.stack([3 * np.ones_like(t), 4 * np.ones_like(t)], axis=1)
    assert rms(vector) == pytest.approx(5.0)
    assert np.isnan(rms(np.array([])))


def test_relative_error_rms():
    truth = np.tile([3.0, 4.0], (10, 1))
    assert relative_error_rms(1.1 * truth, truth) == pytest.approx(0.1)
    assert relative_error_rms(truth, truth) == 0.0


def _synthetic_logs(scenario, error_amplitude, effort, B_error):
    """Logs of a made-up run: alpha~ = A sin, ||u|| = effort, B_hat = (1 + B_error) B~."""
    n = scenario.robot.truth.num_links
    t = np.arange(0, scenario.duration, 0.01)
    T = len(t)
    lhs = np.zeros((T, n + 5))
    lhs[:, n] = error_amplitude * np.sin(2 * np.pi * t)
    state = np.zeros((T, 2 * (3 + n)))
    state[:, 3:3 + n] = scenario.q0
    truth = np.tile(np.concatenate([np.eye(n).reshape(-1), [0.1] * n]), (T, 1))
    estimates = truth.copy()
    estimates[:, :n * n] *= 1 + B_error
    rhs = np.zeros((T, 2 * n + 6))
    R = RhsLog(n)
    rhs[:, R.c] = 900.0
    rhs[:, R.c_min] = 800.0
    rhs[:, [R.dic_ok, R.trusted]] = 1.0
    u = np.zeros((T, n))
    u[:, 0] = effort
    learner = np.zeros((T, LearnerLog().size))
    learner[:, LearnerLog().beta_hat] = np.where(t >= scenario.disturbance_start, 3.0, 1.0)
    learner[:, LearnerLog().physical] = 1.0         # no kinematic mismatch reported
    return {"time": t, "lhs_log": lhs, "state": state, "u": u, "rhs_log": rhs,
            "learner_log": learner, "true_matrices": truth, "estimates": estimates,
            "tau_request": np.zeros((T, n)), "tau": np.zeros((T, n))}


def test_run_metrics_and_table_on_synthetic_runs():
    scenario = short_scenario()
    dac = run_metrics(_synthetic_logs(scenario, 0.001, 0.0116, 0.5), scenario)
    mb = run_metrics(_synthetic_logs(scenario, 0.004, 0.0100, 0.0), scenario)
    assert dac["tracking_error_rms"] == pytest.approx(0.001 / np.sqrt(2), rel=1e-3)
    assert dac["estimation_error_B"] == pytest.approx(0.5)
    assert dac["estimation_error_D"] == pytest.approx(0.0)
    assert dac["c_min_over_bound"] == pytest.approx(900 / 800)
    assert dac["dic_violations"] == 0 and dac["rejected_estimates"] == 0
    assert dac["min_clearance"] > 0
    assert dac["phase2.beta_clipped_share"] == 0.0      # beta_hat = 1 <= rhs.beta_max = 2
    assert dac["phase3.beta_clipped_share"] == 1.0      # beta_hat = 3
    c = comparison(dac, mb)
    assert c["tracking_error_reduction"] == pytest.approx(0.75, rel=1e-3)
    assert c["control_effort_increase"] == pytest.approx(0.16)
    rows = {r["key"]: r for r in metrics_table({"dac": dac, "model-based": mb})}
    assert rows["tracking_error_reduction"]["paper"] == 0.775
    assert rows["control_effort_increase"]["this_project"] == pytest.approx(0.16)
