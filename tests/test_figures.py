"""The panels show what a reader relies on: log axes where the controllers differ by
orders of magnitude, one unit per axis, legends outside the data, fast ripple as an
honest min/max envelope, one small axis per matrix entry for any number of links.
Checked on synthetic runs of the paper's length (1500 s logged at 100 Hz)."""
import re

import matplotlib.pyplot as plt
import numpy as np
import pytest

from conftest import three_link_robot
from dacph_drake.app.figures import COLUMNS, DAC_PANELS, envelope, make_panels
from dacph_drake.log_layout import LhsLog, RhsLog
from dacph_drake.tasks.end_effector_angle import END_EFFECTOR_ANGLE
from dacph_drake.scenario import PlanarArm, Scenario, Uncertainty
from dacph_drake.scenario.built_in import paper_scenario

PANELS = DAC_PANELS + END_EFFECTOR_ANGLE.panels


def _synthetic_run(scenario: Scenario, tracking_error: float, seed: int):
    """Logs laid out as a run's, with a 20 Hz ripple in phase 3 (as d_HF makes)."""
    rng = np.random.default_rng(seed)
    n = scenario.robot.truth.num_links
    t = np.arange(0.0, scenario.phases.end, scenario.periods.log)
    phase3 = t >= scenario.disturbance_start
    ripple = np.where(phase3, np.sin(2 * np.pi * 20.0 * t), 0.0)
    slow = np.sin(2 * np.pi * t / 300.0)
    truth = np.tile(np.concatenate([np.eye(n).reshape(-1), np.full(n, 0.12)]),
                    (len(t), 1)) + 0.02 * slow[:, None]
    lhs = np.zeros((len(t), LhsLog(n).size))
    lhs[:, LhsLog(n).s] = tracking_error * (1 + ripple[:, None]) * rng.uniform(
        0.5, 1.5, (len(t), n))
    lhs[:, LhsLog(n).alpha_error] = tracking_error * slow * (1 + 0.5 * ripple)
    lhs[:, LhsLog(n).alpha_desired] = 1.3 + 0.2 * slow
    rhs = np.zeros((len(t), RhsLog(n).size))
    R = RhsLog(n)
    rhs[:, R.e_norm] = 1e-6 + 1e-3 * phase3 * (1 + ripple)
    rhs[:, R.chi] = 1e-3 + 0.1 * np.exp(-t / 10)
    rhs[:, R.K] = 800 + 50 * slow[:, None]
    rhs[:, R.c], rhs[:, R.c_min] = 870 + 50 * slow, 790.0
    state = np.zeros((len(t), 2 * (3 + n)))
    state[:, 3:3 + n] = 0.5 + 0.3 * slow[:, None]
    return {"time": t, "true_matrices": truth,
            "estimates": truth + 1e-3 * rng.standard_normal(truth.shape),
            "rhs_log": rhs, "lhs_log": lhs, "state": state,
            "disturbance": 0.02 * (ripple[:, None] + phase3[:, None]) * np.ones(n),
            "u": 0.05 * slow[:, None] + 0.01 * ripple[:, None] + np.zeros(n)}


def _three_link_scenario() -> Scenario:
    robot = three_link_robot()
    return Scenario(robot=PlanarArm(truth=robot, nominal=robot), q0=[0.3, 0.6, 0.6],
                    uncertainty=Uncertainty(B0=[1.0] * 3, D0=[0.1] * 3))


@pytest.fixture(scope="module", params=["paper_2link", "3link"])
def panels(request):
    scenario = paper_scenario() if request.param == "paper_2link" else _three_link_scenario()
    scenario.phases = paper_scenario().phases
    dac = _synthetic_run(scenario, 1e-5, seed=1)
    model_based = _synthetic_run(scenario, 1e-2, seed=2)
    figures = make_panels({"dac": dac, "model-based": model_based}, scenario)
    for fig in figures.values():
        fig.canvas.draw()
    yield scenario, dac, figures
    for fig in figures.values():
        plt.close(fig)


def _data_axes(fig):
    return [ax for ax in fig.axes if ax.lines]


def test_log_axes_where_the_controllers_differ_by_orders_of_magnitude(panels):
    _, _, figures = panels
    a, d, e = (figures[name] for name in (PANELS[0], PANELS[3], PANELS[4]))
    assert [ax.get_yscale() for ax in _data_axes(a)] == ["log"] * 3
    assert [ax.get_yscale() for ax in _data_axes(e)] == ["log", "log", "linear"]
    assert _data_axes(d)[2].get_yscale() == "log"
    for ax in _data_axes(a) + _data_axes(e)[:2]:      # fitted to the data
        low, high = ax.get_ylim()
        assert np.log10(high / low) <= 8


def test_every_axis_carries_one_unit(panels):
    _, _, figures = panels
    for name, fig in figures.items():
        axes = _data_axes(fig)
        for ax in axes:
            units = re.findall(r"\[[^\]]*\]", ax.get_ylabel())
            assert len(units) == 1, (name, ax.get_ylabel())
        assert any(ax.get_xlabel() == "time t [s]" for ax in axes), name


def test_legends_sit_outside_the_data(panels):
    _, _, figures = panels
    for name, fig in figures.items():
        renderer = fig.canvas.get_renderer()
        legends = fig.legends + [ax.get_legend() for ax in fig.axes if ax.get_legend()]
        assert legends, name
        for legend in legends:
            box = legend.get_window_extent(renderer)
            for ax in _data_axes(fig):
                area = ax.get_window_extent(renderer)
                overlap_x = min(box.x1, area.x1) - max(box.x0, area.x0)
                overlap_y = min(box.y1, area.y1) - max(box.y0, area.y0)
                assert overlap_x <= 1 or overlap_y <= 1, (name, ax.get_ylabel())


def test_fast_ripple_is_drawn_as_its_envelope(panels):
    """150 000 samples become at most 2 COLUMNS points per line, and the band still
    reaches the data's extremes."""
    _, dac, figures = panels
    disturbance_axis = _data_axes(figures[PANELS[4]])[2]
    for line in disturbance_axis.lines:
        assert len(line.get_xdata()) <= COLUMNS + 1
    drawn = np.concatenate([line.get_ydata() for line in disturbance_axis.lines])
    assert drawn.max() == dac["disturbance"].max()
    assert drawn.min() == dac["disturbance"].min()


def test_envelope_keeps_every_extreme():
    t = np.linspace(0, 10, 100_001)
    y = np.sin(2 * np.pi * 20 * t) + 1e-3 * t
    tc, low, high = envelope(t, y, (0, 10), columns=500)
    assert len(tc) == 500 and np.all(low <= high)
    assert high.max() == y.max() and low.min() == y.min()
    tc, low, high = envelope(t[:900], y[:900], (0, 10), columns=500)
    assert low is high and len(tc) == 900               # few samples: drawn as they are


def test_one_axis_per_matrix_entry_for_any_number_of_links(panels):
    scenario, _, figures = panels
    n = scenario.robot.truth.num_links
    for name in (PANELS[1], PANELS[2]):
        labels = [ax.get_ylabel() for ax in _data_axes(figures[name])]
        assert len(labels) == n * n + n and len(set(labels)) == len(labels)


def test_warm_up_is_labelled_and_the_controllers_are_distinguishable(panels):
    _, _, figures = panels
    top = _data_axes(figures[PANELS[0]])[0]
    assert any(text.get_text().startswith("Warm-up") for text in top.texts)
    alpha_axis = _data_axes(figures[PANELS[4]])[0]
    styles = {line.get_label(): (line.get_color(), line.get_linestyle())
              for line in alpha_axis.lines if not line.get_label().startswith("_")}
    assert set(styles) == {"DAC-pH", "model-based"}
    dac, model_based = styles["DAC-pH"], styles["model-based"]
    assert dac[0] != model_based[0] and dac[1] != model_based[1]


def test_the_entries_panel_draws_the_claims_the_metrics_report():
    """Panel b draws what the metrics table reports (loop.metrics.physical_view):
    the claimed entries, their 90 % interval as a band; panel g the port model the
    loop closes on against its own truth (I + E) B~, for a run that measured E."""
    from dacph_drake.loop.metrics import physical_view
    from dacph_drake.app.figures import PORT_PANEL
    from dacph_drake.loop.simulate import simulate
    from dacph_drake.scenario.built_in import short_scenario
    scenario = short_scenario()
    run = simulate(scenario, "dac", duration=3.0)
    figures = make_panels({"dac": run.logs}, scenario)
    try:
        claims, lower, upper = physical_view(run.logs, scenario)
        n = len(scenario.q0)
        axes = [ax for ax in figures[PANELS[1]].axes if ax.lines]
        assert len(axes) == n * n + n
        for column, ax in enumerate(axes):
            drawn = {line.get_label(): line.get_ydata() for line in ax.lines}
            np.testing.assert_array_equal(drawn["claimed (learned or prior)"],
                                          claims[:, column])
            band = ax.collections[-1].get_paths()[0].vertices[:, 1]
            assert band.min() == pytest.approx(lower[:, column].min())
            assert band.max() == pytest.approx(upper[:, column].max())
        port = [ax for ax in figures[PORT_PANEL].axes if ax.lines]
        drawn = {line.get_label(): line.get_ydata() for line in port[0].lines}
        np.testing.assert_array_equal(drawn["port model (the loop's)"],
                                      run.logs["estimates"][:, 0])
    finally:
        for fig in figures.values():
            plt.close(fig)
