"""The result of a run by name (loop.signals.Signals, RunResult.signals, to_pandas,
plot, metrics): every named signal is the indexed column it names, on a planar and
a described arm alike, a batch's trials are traces, and the typed metrics are
run_metrics' numbers under the scenario's phase names."""
import numpy as np
import pytest

from dacph_drake.log_layout import AttitudeLog, LearnerLog, LhsLog, RhsLog


def _short(robot: str):
    from dacph_drake.scenario import Phases
    from dacph_drake.assembly.scenario_files import load_scenario
    scenario = load_scenario({"planar": "short", "described": "satellite_3dof"}[robot])
    scenario.phases = Phases(warmup=0.1, linear=0.1, nonlinear=0.1, disturbance=0.1)
    return scenario


@pytest.fixture(scope="module", params=["planar", "described"])
def run(request):
    from dacph_drake.loop.simulate import simulate
    return simulate(_short(request.param), "dac")


def test_named_signals_are_the_indexed_columns(run):
    n = len(run.scenario.q0)
    signals, logs = run.signals, run.logs
    R, L = RhsLog(n), LearnerLog()
    pairs = [("e_tau", "rhs_log", R.e_tau), ("chi", "rhs_log", R.chi),
             ("K", "rhs_log", R.K), ("c_min", "rhs_log", R.c_min),
             ("rhs_log.e_norm", "rhs_log", R.e_norm),
             ("beta_hat", "learner_log", L.beta_hat), ("loss", "learner_log", L.loss)]
    if "lhs_log" in logs:
        H = LhsLog(n)
        pairs += [("alpha_error", "lhs_log", H.alpha_error), ("s", "lhs_log", H.s),
                  ("alpha_desired", "lhs_log", H.alpha_desired),
                  ("V", "lhs_log", H.lyapunov_V)]
    else:
        A = AttitudeLog()
        pairs += [("attitude_error", "attitude_log", A.e),
                  ("attitude_error_norm", "attitude_log", A.e_norm),
                  ("V", "attitude_log", A.lyapunov_V),
                  ("clearance", "attitude_log", A.clearance)]
    for name, log, column in pairs:
        np.testing.assert_array_equal(signals[name], logs[log][:, column], err_msg=name)
    np.testing.assert_array_equal(signals["u"], logs["u"])
    np.testing.assert_array_equal(signals["time"], logs["time"])
    with pytest.raises(KeyError, match="did you mean"):
        signals["e_ta"]


def test_to_pandas_and_plot_name_their_columns(run):
    frame = run.to_pandas(["chi", "u", "V"])
    n = len(run.scenario.q0)
    assert list(frame.columns) == ["chi"] + [f"u[{i}]" for i in range(n)] + ["V"]
    np.testing.assert_array_equal(frame.index.values, run.logs["time"])
    np.testing.assert_array_equal(frame["chi"].values, run.signals["chi"])
    ax = run.plot("chi", "e_tau", logy=True)
    assert len(ax.get_lines()) == 1 + n
    assert [t.get_text() for t in ax.get_legend().get_texts()][0] == "chi"
    import matplotlib.pyplot as plt
    plt.close(ax.figure)


def test_metrics_are_typed_per_phase_with_units(run):
    from dacph_drake.loop.metrics import run_metrics
    flat = run_metrics(run.logs, run.scenario)
    record = run.metrics
    assert record.flat.keys() == flat.keys()
    np.testing.assert_equal(list(record.flat.values()), [flat[k] for k in record.flat])
    assert set(record.phases) == {"linear", "nonlinear", "disturbance"}
    assert record.phases["nonlinear"]["tracking_error_rms"] == flat[
        "phase2.tracking_error_rms"]
    assert record.units["tracking_error_rms"] == "rad"
    assert record.units["e_tau_rms"] == "N m"


def test_a_batchs_trials_are_traces():
    from dacph_drake.loop.signals import Signals
    from dacph_drake.loop.simulate import simulate_batch
    scenarios = [_short("planar") for _ in range(2)]
    scenarios[1].q0 = [0.35, 1.0]
    trials = simulate_batch(scenarios, "model-based", duration=0.2)
    traces = Signals.Of(trials)["alpha_error"]
    assert traces.shape == (2, len(trials[0].logs["time"]))
    for k, trial in enumerate(trials):
        np.testing.assert_array_equal(traces[k], trial.signals["alpha_error"])
    frame = Signals.Of(trials).to_pandas(["alpha_error"])
    assert frame.index.names == ["trial", "time"] and len(frame) == 2 * traces.shape[1]
