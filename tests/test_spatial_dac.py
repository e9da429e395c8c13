"""The DAC-pH loop on spatial robots: the spatial ground truth's RHS, the shared RHS
chain, tracking under the uncertainty phases, and `dacph verify` on a spatial run."""
import json

import numpy as np
import pytest

from dacph_drake.controllers import build_closed_loop
from dacph_drake.controllers.dac import build_dac_diagram
from dacph_drake.scenario.errors import ConfigError
from dacph_drake.loop.metrics import nominal_estimates, run_metrics
from dacph_drake.log_layout import LearnerLog
from dacph_drake.loop.simulate import simulate
from dacph_drake.scenario import AttitudeGains, Phases
from dacph_drake.assembly.scenario_files import load_scenario, save_scenario


def _short_3dof():
    """satellite_3dof with its phases compressed to 0.5 + 1 + 1 + 1 s."""
    scenario = load_scenario("satellite_3dof")
    scenario.phases = Phases(warmup=0.5, linear=1.0, nonlinear=1.0, disturbance=1.0)
    return scenario


def test_spatial_true_rhs_is_the_port_model_at_the_plant_state(rng):
    """tau = B~(q, p) u - D~(p) qdot + d(t) with p = M(q) qdot at a random state of
    zero momentum in every phase, B~, D~ from uncertainty.TrueRhsModel."""
    from dacph_drake.dynamics.uncertainty import TrueRhsModel
    scenario = _short_3dof()
    loop = build_closed_loop("dac", scenario)
    truth, model = loop.systems["true_rhs"], loop.model
    disturbance = loop.systems["disturbance"]
    context = truth.CreateDefaultContext()
    n = model.num_joints
    q, qdot, u = rng.uniform(-1, 1, n), rng.uniform(-0.5, 0.5, n), rng.uniform(-1, 1, n)
    plant_context = loop.plant.CreateDefaultContext()
    loop.plant.SetPositions(plant_context, model.FullPositions(q))
    velocities = np.zeros(loop.plant.num_velocities())
    velocities[model.coordinates.base_v] = model.BaseVelocity(q, qdot)
    velocities[model.coordinates.joint_v] = qdot
    loop.plant.SetVelocities(plant_context, velocities)
    truth.GetInputPort("state").FixValue(
        context, loop.plant.GetPositionsAndVelocities(plant_context))
    truth.GetInputPort("u").FixValue(context, u)
    truth.GetInputPort("disturbance_model").FixValue(
        context, disturbance.GetOutputPort("disturbance_model").Eval(
            disturbance.CreateDefaultContext()))
    reference = TrueRhsModel(scenario.uncertainty, scenario.phases)
    for t in (0.2, 1.0, 2.0, 3.0):
        context.SetTime(t)
        B, D = reference.Matrices(t, q, model.Momentum(q, qdot))
        expected = B @ u - D * qdot + disturbance.Evaluate(t)
        np.testing.assert_allclose(truth.GetOutputPort("tau").Eval(context), expected,
                                   rtol=1e-9, atol=1e-12)
    assert t >= scenario.disturbance_start and np.any(disturbance.Evaluate(t) != 0)


def test_model_based_loop_on_the_nominal_truth_applies_the_request():
    """On the nominal ground truth (the warm-up) the baseline's inversion is exact:
    the plant's torque is the attitude controller's request."""
    loop = build_closed_loop("model-based", _short_3dof())
    simulator = loop.CreateSimulator()
    simulator.AdvanceTo(0.05)
    context = simulator.get_context()
    tau = loop.systems["true_rhs"].GetOutputPort("tau").Eval(
        loop.systems["true_rhs"].GetMyContextFromRoot(context))
    controller = loop.systems["attitude_controller"]
    request = controller.GetOutputPort("tau_request").Eval(
        controller.GetMyContextFromRoot(context))
    np.testing.assert_allclose(tau, request, rtol=1e-12, atol=1e-15)


def test_spatial_dac_tracks_through_the_phases_and_verifies(tmp_path):
    """The 3-DOF arm with DAC through warm-up, linear and nonlinear uncertainty and
    the disturbance (0.5 + 1 + 1 + 1 s): the attitude error follows the LHS's
    exp(-Lambda t) from 0.3 rad through every phase change, within 1e-3 rad, and is
    below 1e-3 rad from 3 s on (the disturbance phase); the momentum stays zero, the arm keeps > 0.1 m from the
    base, the model-based baseline on the same run is worse in the disturbance
    phase, and `dacph verify` passes on the saved run."""
    from dacph_drake.app.cli import main
    scenario = _short_3dof()
    dac = simulate(scenario, "dac", out_dir=tmp_path / "dac")
    baseline = simulate(scenario, "model-based")
    assert dac.status == "ok" and baseline.status == "ok"
    t = dac.logs["time"]
    error = dac.logs["attitude_log"][:, 3]
    bound = 1.1 * error[0] * np.exp(-scenario.task.gains.Lambda * (t - 0.1)) + 1e-3
    assert np.all(error <= bound), t[np.argmax(error > bound)]
    assert np.max(error[t >= 3.0]) < 1e-3
    metrics, baseline_metrics = (run_metrics(r.logs, scenario) for r in (dac, baseline))
    assert metrics["max_momentum"] < 1e-8
    assert metrics["min_clearance"] > 0.1
    assert (metrics["phase3.tracking_error_rms"]
            < baseline_metrics["phase3.tracking_error_rms"])
    assert json.loads((tmp_path / "dac" / "run_dac.json").read_text())["controller"] \
        == "dac"
    assert main(["verify", str(tmp_path / "dac")]) == 0
    report = json.loads((tmp_path / "dac" / "verification.json").read_text())
    assert report["ok"] and report["checks"]["rhs_loop_truth"]["evaluated"] > 0
    assert report["settings"]["lambda_lhs"] == pytest.approx(
        2 * scenario.task.gains.damping_rate)


def test_verify_refuses_a_spatial_baseline_run(tmp_path, capsys):
    from dacph_drake.app.cli import main
    simulate(_short_3dof(), "model-based", duration=0.1, out_dir=tmp_path)
    assert main(["verify", str(tmp_path)]) == 2
    assert "logs_dac.npz is missing" in capsys.readouterr().err


@pytest.mark.parametrize("change, message", [
    (dict(rhs=2e-3), r"periods.rhs = 0.002 s must not exceed periods.lhs = 0.001 s"),
    (dict(rhs=1e-3), r"periods.rhs = 0.001 s must be shorter than periods.lhs"),
    (dict(learner_sample=1e-1, learner=1e-2),
     r"periods.learner_sample = 0.1 s must not exceed periods.learner = 0.01 s"),
])
def test_bad_spatial_periods_are_named(change, message):
    scenario = _short_3dof()
    for name, value in change.items():
        setattr(scenario.periods, name, value)
    with pytest.raises(ConfigError, match=message):
        build_dac_diagram(scenario)


def test_bad_spatial_port_settings_are_named():
    scenario = _short_3dof()
    scenario.uncertainty.D0 = [0.1, 0.1]
    with pytest.raises(ConfigError, match=r"uncertainty.D0 has 2 entries; allowed: 3"):
        build_dac_diagram(scenario)
    scenario = _short_3dof()
    scenario.task.gains = AttitudeGains(boundary_rate=500.0)
    with pytest.raises(ConfigError, match=r"task.gains.damping_rate \+ "
                                          r"task.gains.boundary_rate = 520 1/s with "
                                          r"periods.lhs = 0.001 s"):
        build_dac_diagram(scenario)
    scenario = _short_3dof()
    scenario.task.gains = AttitudeGains(damping_rate=200.0, boundary_rate=1.0)
    scenario.periods.lhs = 2e-3
    with pytest.raises(ConfigError, match=r"periods.rhs = 0.0005 s cannot realize"):
        build_dac_diagram(scenario)


def test_spatial_panels_show_dac_against_the_baseline(tmp_path, capsys):
    """`dacph reproduce` on a described arm's scenario writes (a)-(d) and the
    attitude panel (e), whose first axis holds every controller's |e|; the former
    `dacph spatial --panels` points there."""
    import matplotlib.image
    from dacph_drake.app.cli import main
    from dacph_drake.app.figures import DAC_PANELS
    from dacph_drake.tasks.end_effector_attitude import END_EFFECTOR_ATTITUDE
    scenario = _short_3dof()
    scenario.phases = Phases(warmup=0.2, linear=0.3, nonlinear=0.3, disturbance=0.3)
    save_scenario(scenario, tmp_path / "s.yaml")
    assert main(["reproduce", str(tmp_path / "s.yaml"), "--out", str(tmp_path / "run")]) == 0
    for name in DAC_PANELS + END_EFFECTOR_ATTITUDE.panels:
        image = matplotlib.image.imread(tmp_path / "run" / "figures" / f"{name}.png")
        assert image.shape[0] > 500 and (tmp_path / "run" / "figures" / f"{name}.pdf").is_file()
    assert main(["spatial", str(tmp_path / "s.yaml"), "--out", str(tmp_path / "mb"),
                 "--controller", "model-based", "--panels"]) == 2
    assert "allowed: dacph reproduce" in capsys.readouterr().err


def test_a_sweep_over_a_spatial_scenario(tmp_path):
    """A sweep file naming a spatial scenario samples the RHS and disturbance settings
    (the planar runs' metrics, so the summary reads them alike); the robot's own
    distributions are refused with the reason."""
    from dacph_drake.montecarlo.definition import load_sweep
    from dacph_drake.montecarlo.executors import InProcessExecutor
    from dacph_drake.montecarlo.runner import run_sweep
    from dacph_drake.montecarlo.summary import write_summary
    scenario = _short_3dof()
    scenario.phases = Phases(warmup=0.2, linear=0.3, nonlinear=0.3, disturbance=0.3)
    save_scenario(scenario, tmp_path / "s.yaml")
    (tmp_path / "sweep.yaml").write_text(
        "scenario: s.yaml\ntrials: 2\ncontrollers: [dac]\ndistributions:\n"
        "  delta_D_scale: !Uniform {min: 0.5, max: 1.5}\n")
    definition = load_sweep(tmp_path / "sweep.yaml")
    rows = run_sweep(definition, tmp_path / "out", InProcessExecutor(), 1)
    assert [row["status"] for row in rows] == ["ok", "ok"]
    summary = write_summary(tmp_path / "out", definition)
    assert summary["succeeded"] == 2
    assert summary["controllers"]["dac"]["metrics"]["phase3.B_error_ratio"]["n"] == 2
    assert summary["controllers"]["dac"]["metrics"]["max_momentum"]["q95"] < 1e-8
    (tmp_path / "bad.yaml").write_text(
        "scenario: satellite_3dof\ntrials: 1\ndistributions:\n  link_mass_scale: 1.1\n")
    with pytest.raises(ConfigError, match=r"distributions.link_mass_scale with the "
                                          r"scenario 'satellite_3dof', whose robot is a "
                                          r"DescribedArm"):
        load_sweep(tmp_path / "bad.yaml")


@pytest.mark.long
def test_six_dof_dac_meets_the_stated_bounds_and_verifies(tmp_path):
    """The shipped 6-DOF example (14 s, about 40 s of simulation and 2 min of the
    region-of-attraction SOS): |e| below 1e-3 rad from 4 s on through every phase,
    at least 0.15 m between the arm and the base, momentum below 1e-7, and
    `dacph verify` passes."""
    from dacph_drake.loop.verify import verify_run
    scenario = load_scenario("satellite_6dof")
    result = simulate(scenario, "dac", out_dir=tmp_path)
    t, error = result.logs["time"], result.logs["attitude_log"][:, 3]
    metrics = run_metrics(result.logs, scenario)
    assert result.status == "ok" and np.max(error[t >= 4.0]) < 1e-3
    assert metrics["min_clearance"] > 0.15
    assert metrics["max_momentum"] < 1e-7
    assert verify_run(tmp_path)["ok"]


def test_learning_beats_the_prior_on_the_3dof_arm_without_costing_tracking():
    """The shipped satellite_3dof scenario (14 s), DAC against its learner-off
    ablation (dac-nominal), same seed: the learned B is closer to the truth than B0
    in every uncertainty phase, D stays at D0 (its heavy joints' damping torque is
    under 1 % of their in-band inertial torque: not in the data), and the attitude
    error in phases 2 and 3 stays within 1.5x of the learner-off loop's (with the
    planar learner's settings on this arm: 8x). The network learner with the point
    rule and the model's inertial scale, as released before the local Bayesian
    learner, its estimates taken as the claims (model_error 0, and the model stated
    exact: no tolerance on its inertias or the anchor, so the measured E is 0)."""
    scenario = load_scenario("satellite_3dof")
    scenario.learner.model, scenario.rhs.adoption = "network", "trust_band"
    scenario.inertia.anchor, scenario.inertia.fit_tolerance = "model", 0.0
    scenario.learner.bayes.model_error = 0.0
    scenario.inertia.nominal_tolerance = scenario.inertia.anchor_tolerance = 0.0
    dac = simulate(scenario, "dac")
    nominal = simulate(scenario, "dac-nominal")
    assert dac.status == "ok" and nominal.status == "ok"
    dac_metrics, nominal_metrics = (run_metrics(r.logs, scenario) for r in (dac, nominal))
    for phase in ("phase1", "phase2", "phase3"):
        assert dac_metrics[f"{phase}.B_error_ratio"] < 0.95, phase
        assert dac_metrics[f"{phase}.D_error_ratio"] < 1.05, phase
    for phase in ("phase2", "phase3"):
        assert (dac_metrics[f"{phase}.tracking_error_rms"]
                < 1.5 * nominal_metrics[f"{phase}.tracking_error_rms"]), phase
    # The prior fallback (learner.prior_fallback, on here): the prior is published
    # while training holds and for part of the run besides, and what is published
    # then is (B0, D0) to round-off (the network evaluated at its prior weights).
    layout = LearnerLog()
    learner_log = dac.logs["learner_log"]
    published = learner_log[:, layout.network_published] > 0.5
    holding = learner_log[:, layout.holding] > 0.5
    assert scenario.learner.prior_fallback
    assert holding.any() and not np.any(published & holding)
    assert 0.2 < published.mean() < 0.9
    prior = nominal_estimates(scenario)
    np.testing.assert_allclose(dac.logs["estimates"][~published],
                               np.tile(prior, (np.count_nonzero(~published), 1)),
                               rtol=0, atol=1e-12)
    assert not np.allclose(dac.logs["estimates"][published], prior)


def test_the_default_learner_on_the_3dof_arm_claims_no_more_than_its_data_hold():
    """The shipped satellite_3dof scenario with the default local Bayesian learner:
    its port data (heavy joints, small in-band torques) determine almost nothing
    once the LHS model's inertia error is allowed for, and the learner says so: B
    is claimed at the prior (no worse than it), the claimed 90 % intervals hold
    the truth at least 85 % of the time in every phase, most quantities are
    reported undetermined, and the attitude error in phases 2 and 3 stays within
    1.5x of the learner-off loop's."""
    scenario = load_scenario("satellite_3dof")
    dac = simulate(scenario, "dac")
    nominal = simulate(scenario, "dac-nominal")
    assert dac.status == "ok" and nominal.status == "ok"
    dac_metrics, nominal_metrics = (run_metrics(r.logs, scenario) for r in (dac, nominal))
    for phase in ("phase1", "phase2", "phase3"):
        assert dac_metrics[f"{phase}.B_error_ratio"] <= 1.0 + 1e-9, phase
        assert dac_metrics[f"{phase}.B_coverage"] >= 0.85, phase
        assert dac_metrics[f"{phase}.D_coverage"] >= 0.85, phase
        assert dac_metrics[f"{phase}.undetermined_share"] > 0.5, phase
    for phase in ("phase2", "phase3"):
        assert (dac_metrics[f"{phase}.tracking_error_rms"]
                < 1.5 * nominal_metrics[f"{phase}.tracking_error_rms"]), phase
