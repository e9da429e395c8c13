"""The model-based LHS loop on the spatial 6-DOF robot: the ground truth (free
quaternion base) tracks a turning 3D end-effector attitude reference."""
import numpy as np
import pytest
from pydrake.systems.analysis import SimulatorConfig

from dacph_drake.controllers.model_based import build_model_based_diagram
from dacph_drake.scenario.errors import ConfigError
from dacph_drake.log_layout import AttitudeLog
from dacph_drake.loop.simulate import collect_logs
from dacph_drake.scenario import AttitudeGains, ClearancePotential, Phases
from dacph_drake.scenario.built_in import satellite_6dof_scenario


def _nominal_6dof(duration: float):
    """satellite_6dof on the nominal ground truth (uncertainty and disturbance
    off) for ``duration`` seconds."""
    scenario = satellite_6dof_scenario()
    scenario.uncertainty.linear_scale = scenario.uncertainty.nonlinear_scale = 0.0
    scenario.disturbance.scale = 0.0
    scenario.phases = Phases(warmup=duration, linear=0.0, nonlinear=0.0, disturbance=0.0)
    return scenario


def test_six_dof_arm_tracks_a_3d_attitude_reference():
    """From rest with a 0.3 rad error, |e| decays as exp(-Lambda t) once s (zero
    only when qdot = nu, so not at rest) has settled at damping_rate = 20 1/s: below
    1.1 |e0| exp(-Lambda (t - 0.1 s)) + 1e-4 rad throughout, and below 2e-4 rad
    after 4 s while R_d(t) turns by up to 0.4 rad; ||s|| < 1e-3 after 0.5 s; the
    momentum stays zero."""
    scenario = _nominal_6dof(4.0)
    loop = build_model_based_diagram(scenario)
    simulator = loop.CreateSimulator()
    simulator.AdvanceTo(scenario.duration)
    log = loop.loggers["attitude_log"].FindLog(simulator.get_context())
    t, data = log.sample_times(), log.data().T
    error, s_norm = data[:, AttitudeLog().e_norm], data[:, AttitudeLog().s_norm]
    assert error[0] == pytest.approx(2 * np.sin(scenario.task.reference.initial_error / 2))
    bound = 1.1 * error[0] * np.exp(-scenario.task.gains.Lambda * (t - 0.1)) + 1e-4
    assert np.all(error <= bound), t[np.argmax(error > bound)]
    assert error[-1] < 2e-4
    assert np.max(s_norm[t > 0.5]) < 1e-3
    context = loop.plant.GetMyContextFromRoot(simulator.get_context())
    momentum = loop.plant.CalcSpatialMomentumInWorldAboutPoint(context, np.zeros(3))
    assert np.max(np.abs(momentum.get_coeffs())) < 1e-8


@pytest.mark.parametrize("change, message", [
    ("q0", r"q0 has 2 entries; allowed: 6"),
    ("lhs_period", r"task.gains.damping_rate = 20 1/s with periods.lhs = 0.05 s"),
    ("robot", r"no such .urdf or .sdf file"),
    ("log_period", r"periods.log = 100 s is longer than the run \(8 s\)"),
    ("task_damping", r"task.gains.task_damping = -1.0"),
    ("margin", r"robot.potential.margin = 0.0"),
    ("simulator", r"simulator.integration_scheme = 'radau3'; allowed: runge_kutta2"),
])
def test_bad_spatial_settings_are_named(change, message):
    scenario = _nominal_6dof(8.0)
    {"q0": lambda: setattr(scenario, "q0", [0.1, 0.2]),
     "lhs_period": lambda: setattr(scenario.periods, "lhs", 0.05),
     "robot": lambda: setattr(scenario.robot, "description", "satellite_9dof"),
     "log_period": lambda: setattr(scenario.periods, "log", 100.0),
     "task_damping": lambda: setattr(scenario.task, "gains",
                                     AttitudeGains(task_damping=-1.0)),
     "margin": lambda: setattr(scenario.robot, "potential",
                               ClearancePotential(margin=0.0)),
     "simulator": lambda: setattr(scenario, "simulator",
                                  SimulatorConfig(integration_scheme="radau3")),
     }[change]()
    with pytest.raises(ConfigError, match=message):
        build_model_based_diagram(scenario)


def test_spatial_run_replays_in_3d_offline(tmp_path):
    """The 6-DOF run as a self-contained HTML file: the robot (coloured links), both
    attitude triads and the overlay with the simulated time, in headless Chromium
    with the network blocked."""
    import re
    import matplotlib.image
    from headless_chromium import run_chromium
    from dacph_drake.robots.viewers import write_spatial_animation
    scenario = _nominal_6dof(1.0)
    loop = build_model_based_diagram(scenario)
    simulator = loop.CreateSimulator()
    simulator.AdvanceTo(scenario.duration)
    logs = collect_logs(loop, simulator.get_context())
    page = write_spatial_animation(scenario.robot.description, logs, tmp_path / "a.html")
    dom = run_chromium(page.resolve().as_uri(), "--dump-dom", virtual_time_ms=8000)
    assert 0.0 < float(re.search(r'id="dacph-time">t = ([0-9.]+) s<', dom).group(1)) <= 1.0
    assert "desired attitude" in dom and "measured end-effector attitude" in dom
    shot = tmp_path / "shot.png"
    run_chromium(page.resolve().as_uri(), f"--screenshot={shot}", virtual_time_ms=8000)
    image = matplotlib.image.imread(shot)[..., :3]
    orange = (image[..., 0] > 0.7) & (image[..., 1] > 0.3) & (image[..., 1] < 0.6) & \
        (image[..., 2] < 0.3)
    assert orange.sum() > 200, "no links in the screenshot"


def test_the_clearance_potential_keeps_the_arm_off_the_base():
    """Ablation: from a start 4.4 cm from the base, the same reference drives the
    forearm into the base (signed distance below 0) without the null-space
    potential; with it the clearance never drops below its start, reaches the
    0.1 m margin, and the attitude error is the same (the potential acts in the
    task's null space)."""
    from dacph_drake.robots.clearance_potential import BaseClearancePotential
    from dacph_drake.robots.description import ParsedDescription
    runs = {}
    for gain in (1.0, 0.0):
        scenario = _nominal_6dof(3.0)
        scenario.q0 = [0.3, -0.8, 2.1, 0.2, 0.6, -0.3]
        scenario.robot.potential = ClearancePotential(gain=gain)
        loop = build_model_based_diagram(scenario)
        simulator = loop.CreateSimulator()
        simulator.AdvanceTo(scenario.duration)
        context = simulator.get_context()
        states = loop.loggers["state"].FindLog(context).data().T
        measure = BaseClearancePotential(parsed=ParsedDescription(scenario.robot),
                                         model=loop.model, gain=1.0, margin=0.1)
        joints, base = loop.model.coordinates.joint_q, loop.model.coordinates.base_q
        clearance = np.array([measure.Evaluate(x[joints], x[base]).min_distance
                              for x in states])
        error = loop.loggers["attitude_log"].FindLog(context).data().T[
            :, AttitudeLog().e_norm]
        runs[gain] = clearance, error
    (with_potential, error_with), (without, error_without) = runs[1.0], runs[0.0]
    assert with_potential[0] == pytest.approx(0.0439, abs=1e-3)
    assert without.min() < 0.0                          # the forearm hits the base
    assert with_potential.min() >= with_potential[0] - 1e-3
    assert with_potential.max() > 0.1
    np.testing.assert_allclose(error_with, error_without, atol=2e-3 * error_with[0])


def test_inertia_scaled_damping_sets_the_lhs_rate_the_gain_rule_uses():
    """With K_d = damping_rate M, V = s^T M s / 2 decays at 2 damping_rate on the
    true 6-DOF dynamics (within 3 %, the 1 kHz hold), the rate
    gain_rule.inertia_scaled_c_lower_bound puts in eq. (48) in place of
    2 lambda_max(K_d) / inf lambda_min(M): the RHS loop it asks for is the same for
    every arm (1.25 ms at the defaults, against 18 us with a constant K_d on this
    arm's 3.8e-4 kg m^2 wrist)."""
    from dacph_drake.gain_rule import WELL_DAMPED_LOOP_GAIN, inertia_scaled_c_lower_bound
    from dacph_drake.scenario import Rhs
    scenario = _nominal_6dof(0.2)
    scenario.periods.log = 1e-3
    loop = build_model_based_diagram(scenario)
    simulator = loop.CreateSimulator()
    simulator.AdvanceTo(scenario.duration)
    log = loop.loggers["attitude_log"].FindLog(simulator.get_context())
    t, V = log.sample_times(), log.data()[AttitudeLog().lyapunov_V]
    rate = -np.polyfit(t, np.log(V), 1)[0]
    assert rate == pytest.approx(2 * scenario.task.gains.damping_rate, rel=0.03)
    rhs = Rhs()
    c_largest = (1 + rhs.c_margin) * inertia_scaled_c_lower_bound(
        rhs.Td, scenario.task.gains.damping_rate, rhs.beta_max)
    assert WELL_DAMPED_LOOP_GAIN / c_largest == pytest.approx(1.25e-3, rel=0.01)


def test_dacph_spatial_runs_saves_and_replays(tmp_path, capsys):
    """`dacph spatial satellite_3dof` (now `dacph simulate`, with a note) end to end:
    metrics printed, the run saved, its scenario file loads back to the same
    settings; a bad name is named."""
    from dacph_drake.app.cli import main
    from dacph_drake.loop.metrics import run_metrics
    from dacph_drake.loop.run_store import load_run
    from dacph_drake.scenario.built_in import BUILT_IN_SCENARIOS
    out = tmp_path / "run"
    assert main(["spatial", "satellite_3dof", "--out", str(out), "--duration", "2",
                 "--animate"]) == 0
    printed = capsys.readouterr()
    assert "dac: ok (2.00 s simulated" in printed.out
    assert "dacph spatial is dacph simulate now" in printed.err
    logs, scenario, run = load_run(out, "dac")
    metrics = run_metrics(logs, scenario)
    assert run["status"] == "ok" and metrics["max_momentum"] < 1e-8
    assert metrics["attitude_error_final"] < 0.2 * 2 * np.sin(0.15)
    assert (out / "animation_dac.html").stat().st_size > 100_000
    assert scenario == BUILT_IN_SCENARIOS["satellite_3dof"]()
    assert main(["spatial", "satellite_9dof", "--out", str(out)]) == 2
    assert ("allowed: a scenario YAML file or a built-in name (paper, short, "
            "satellite_6dof, satellite_3dof)") in capsys.readouterr().err


@pytest.mark.parametrize("name", ["satellite_6dof", "satellite_3dof"])
def test_shipped_spatial_scenario_files_are_the_built_ins(name):
    from pathlib import Path
    from pydrake.common.yaml import yaml_dump_typed
    from dacph_drake.scenario.built_in import BUILT_IN_SCENARIOS
    from dacph_drake.assembly.scenario_files import load_scenario
    path = Path(__file__).resolve().parents[1] / "scenarios" / f"{name}.yaml"
    assert yaml_dump_typed(load_scenario(path)) == yaml_dump_typed(
        BUILT_IN_SCENARIOS[name]())


def test_live_meshcat_shows_a_spatial_run_without_changing_it():
    from dacph_drake.robots.viewers import DESIRED_TRIAD, MEASURED_TRIAD, QuietMeshcat
    from dacph_drake.loop.simulate import simulate
    from dacph_drake.assembly.scenario_files import load_scenario
    meshcat = QuietMeshcat()
    scenario = load_scenario("satellite_3dof")
    watched = simulate(scenario, "model-based", duration=0.3, meshcat=meshcat)
    for path in ("/drake/visualizer", DESIRED_TRIAD, MEASURED_TRIAD):
        assert meshcat.HasPath(path), path
    plain = simulate(scenario, "model-based", duration=0.3)
    for name, log in plain.logs.items():
        assert np.array_equal(log, watched.logs[name]), name


def test_dacph_spatial_checks_out_before_simulating(tmp_path, capsys):
    from dacph_drake.app.cli import main
    taken = tmp_path / "file"
    taken.write_text("")
    assert main(["spatial", "satellite_3dof", "--out", str(taken)]) == 2
    assert "is an existing file; allowed: a directory" in capsys.readouterr().err
