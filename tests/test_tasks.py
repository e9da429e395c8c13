"""Tasks as their own axis (tasks.task.Task): the pose task's compiled kinematics
against Drake's plant and against differences of themselves, a pose run on a
described arm, and a task of the user's own registered once and taken by simulate,
reproduce, report and verify."""
import json
from dataclasses import dataclass, field

import numpy as np
import pytest

from dacph_drake.app.cli import main
from dacph_drake.dynamics.floating_model import FloatingBaseModel
from dacph_drake.scenario.errors import ConfigError
from dacph_drake.kernels.attitude import position_rows, turned
from dacph_drake.robots.description import SPATIAL_ROBOTS, MakeRobotPlant
from dacph_drake.robots.serial_arm import SerialLink
from dacph_drake.scenario import LhsGains, Phases, Reference
from dacph_drake.tasks.end_effector_angle import EndEffectorAngleTask


def _random_base(rng):
    quaternion = rng.normal(size=4)
    return np.concatenate([quaternion / np.linalg.norm(quaternion), rng.normal(size=3)])


@pytest.mark.parametrize("robot", SPATIAL_ROBOTS)
def test_the_pose_rows_are_the_plants_kinematics(robot, rng):
    """position_rows' p_E is Drake's end-effector position for any base pose; its
    D is the GJM's linear rows (FloatingBaseModel.GeneralizedJacobian, from Drake's
    Jacobians); v_E = D qdot at zero momentum; and D_dot is the central difference
    of D along the motion (joints at qdot, the base turning at omega_b)."""
    plant = MakeRobotPlant(robot)
    model = FloatingBaseModel(plant)
    n, tree = model.num_joints, model.kernel_tree
    frame = plant.GetFrameByName("end_effector")
    node, X_CE = model.FrameNode(frame)
    p_CE = np.ascontiguousarray(X_CE[:3, 3])
    context = plant.CreateDefaultContext()
    for _ in range(3):
        q, qdot, base = rng.uniform(-2, 2, n), rng.normal(size=n), _random_base(rng)
        omega = rng.normal(size=3)
        velocity = np.concatenate([omega, rng.normal(size=3)])
        p_E, v_E, D, D_dot = position_rows(tree[0], tree[1], tree[2], tree[7],
                                           model.Evaluate(q), qdot, base[:4], base[4:],
                                           velocity, node, p_CE)
        positions = plant.GetPositions(context)
        positions[:7] = base
        positions[model.coordinates.joint_q] = q
        plant.SetPositions(context, positions)
        expected = frame.CalcPoseInWorld(context).translation()
        np.testing.assert_allclose(p_E, expected, rtol=0, atol=1e-12)
        J = model.GeneralizedJacobian(q, frame, base_positions=base)
        np.testing.assert_allclose(D, J[3:], rtol=0, atol=1e-12)
        zero_momentum = model.BaseVelocity(q, qdot, base)
        _, v_free, _, _ = position_rows(tree[0], tree[1], tree[2], tree[7],
                                        model.Evaluate(q), qdot, base[:4], base[4:],
                                        zero_momentum, node, p_CE)
        np.testing.assert_allclose(v_free, D @ qdot, rtol=0,
                                   atol=1e-12 * np.abs(D @ qdot).max())

        def rows(h):
            moved = np.concatenate([turned(base[:4], h * omega), base[4:]])
            return position_rows(tree[0], tree[1], tree[2], tree[7],
                                 model.Evaluate(q + h * qdot), qdot, moved[:4],
                                 moved[4:], velocity, node, p_CE)[2]
        np.testing.assert_allclose(D_dot, (rows(1e-5) - rows(-1e-5)) / 2e-5, rtol=0,
                                   atol=1e-7 * np.abs(D_dot).max())
        assert np.abs(D_dot).max() > 1e-3          # the rows do move


def _pose_scenario(phase: float):
    from dacph_drake.assembly.scenario_files import load_scenario
    from dacph_drake.scenario import EndEffectorPose
    scenario = load_scenario("satellite_6dof")
    scenario.task = EndEffectorPose(reference=scenario.task.reference,
                                    gains=scenario.task.gains)
    scenario.phases = Phases(warmup=phase, linear=phase, nonlinear=phase,
                             disturbance=phase)
    return scenario


def test_the_pose_task_tracks_position_and_attitude_and_reports_both(tmp_path):
    """task: !EndEffectorPose on the 6-DOF satellite (phases of 1 s): the scenario
    round-trips through YAML, DAC runs every phase, the position error falls from
    its 2 cm start below 1 mm in phase 3 and is reported per phase in metres, and
    the task's panel draws it beside the attitude error."""
    from dacph_drake.loop.metrics import run_metrics
    from dacph_drake.loop.simulate import simulate
    from dacph_drake.log_layout import PoseLog
    from dacph_drake.assembly.scenario_files import load_scenario, save_scenario
    scenario = _pose_scenario(1.0)
    save_scenario(scenario, tmp_path / "pose.yaml")
    assert "!EndEffectorPose" in (tmp_path / "pose.yaml").read_text()
    assert load_scenario(tmp_path / "pose.yaml") == scenario
    run = simulate(scenario, "dac")
    assert run.status == "ok"
    metrics = run_metrics(run.logs, scenario)
    L = PoseLog()
    assert run.logs["pose_log"][0, L.e_position_norm] == pytest.approx(0.02, rel=1e-6)
    assert metrics["phase3.position_error_rms"] < 1e-3
    assert metrics["phase3.tracking_error_rms"] < 1e-2
    from dacph_drake.app.figures import make_panels
    baseline = simulate(scenario, "model-based")
    panels = make_panels({"dac": run.logs, "model-based": baseline.logs}, scenario)
    axes = panels["e_pose_dac_vs_model_based"].axes
    assert "position error" in axes[1].get_ylabel() and len(axes) == 5
    from dacph_drake.assembly.registry import robot_of
    html = robot_of(scenario).WriteAnimation(run.logs, tmp_path / "pose.html")
    assert html.stat().st_size > 10_000
    import matplotlib.pyplot as plt
    plt.close("all")


def test_a_pose_task_needs_six_joints_and_a_regular_start():
    """On a 3-joint arm the pose task is refused naming the joint count."""
    from dacph_drake.assembly.registry import robot_of
    from dacph_drake.assembly.scenario_files import load_scenario
    from dacph_drake.scenario import EndEffectorPose
    scenario = load_scenario("satellite_3dof")
    scenario.task = EndEffectorPose()
    with pytest.raises(ConfigError, match="at least 6 joints"):
        robot_of(scenario).RequireRunnableStart()


@dataclass
class HoldAngle:
    """A task of the user's own: hold the planar end effector's angle at its start.

    Attributes:
        reference: alpha_d(t), still by default.
        gains: The LHS gains."""
    reference: Reference = field(
        default_factory=lambda: Reference(amplitudes=[0.0], periods=[1.0]))
    gains: LhsGains = field(default_factory=LhsGains)


class HoldAngleTask(EndEffectorAngleTask):
    """A new task as a researcher writes one, in its own module: a section and a
    Task (here the angle task's controller under its own name)."""
    section = HoldAngle
    lhs_name = "hold_controller"
    panels = ()


def test_a_new_task_is_one_module_and_one_registration(tmp_path, monkeypatch):
    """tasks.registry.register(task) and nothing else: a scenario file with
    ``task: !HoldAngle`` loads, `dacph simulate`, `dacph verify`, `dacph reproduce`,
    `dacph report` and a 2-trial sweep take it, and its LHS system is in the diagram
    by its name."""
    from dacph_drake.controllers.dac import build_dac_diagram
    from dacph_drake.scenario import Scenario
    from dacph_drake.assembly.scenario_files import load_scenario
    from dacph_drake.tasks import registry
    field_ = Scenario.__dataclass_fields__["task"]
    monkeypatch.setattr(field_, "type", field_.type)         # undone after the test
    monkeypatch.setitem(registry.TASKS, HoldAngle, None)     # undone after the test
    registry.register(HoldAngleTask())
    (tmp_path / "hold.yaml").write_text(
        "task: !HoldAngle\n  reference: {amplitudes: [0.0], periods: [1.0]}\n"
        "phases: {warmup: 0.2, linear: 0.3, nonlinear: 0.3, disturbance: 0.3}\n")
    scenario = load_scenario(tmp_path / "hold.yaml")
    assert isinstance(scenario.task, HoldAngle)
    assert isinstance(scenario.task.gains, LhsGains)
    assert isinstance(scenario.task.reference, Reference)
    assert "hold_controller" in build_dac_diagram(scenario).systems
    single = tmp_path / "single"
    assert main(["simulate", str(tmp_path / "hold.yaml"), "--out", str(single)]) == 0
    assert json.loads((single / "run_dac.json").read_text())["status"] == "ok"
    assert main(["verify", str(single)]) in (0, 1)
    assert (single / "verification.json").is_file()
    out = tmp_path / "reproduced"
    assert main(["reproduce", str(tmp_path / "hold.yaml"), "--out", str(out)]) == 0
    assert main(["report", str(out)]) == 0
    alpha = np.load(out / "logs_dac.npz")["lhs_log"][:, 2 + 1]      # alpha_d, n = 2
    assert np.ptp(alpha) == 0.0                                      # held still
    from dacph_drake.montecarlo.definition import load_sweep
    from dacph_drake.montecarlo.executors import InProcessExecutor
    from dacph_drake.montecarlo.runner import run_sweep
    (tmp_path / "sweep.yaml").write_text(
        "scenario: hold.yaml\ntrials: 2\ncontrollers: [dac]\ndistributions:\n"
        "  delta_D_scale: !Uniform {min: 0.5, max: 1.5}\n")
    rows = run_sweep(load_sweep(tmp_path / "sweep.yaml"), tmp_path / "sweep",
                     InProcessExecutor(), 1)
    assert [row["runs"]["dac"]["status"] for row in rows] == ["ok", "ok"]


@pytest.mark.parametrize("setting, value, message", [
    ("period", 0.0, r"task.position.period"),
    ("amplitude", -0.01, r"task.position.amplitude = -0.01 m; allowed: >= 0"),
    ("axis", [0.0, 0.0, 0.0], r"task.position.axis = \[0.0, 0.0, 0.0\]; allowed: a "
                              r"non-zero 3-vector"),
    ("initial_offset", [0.01, 0.0], r"task.position.initial_offset = \[0.01, 0.0\]; "
                                    r"allowed: a 3-vector"),
    ("axis", [float("nan"), 0.0, 1.0], r"task.position.axis"),
])
def test_a_bad_position_reference_is_named(setting, value, message):
    """Each of the pose task's own settings, out of range, ends in one ConfigError
    naming it and what is allowed."""
    from dacph_drake.assembly.registry import robot_of
    scenario = _pose_scenario(1.0)
    setattr(scenario.task.position, setting, value)
    with pytest.raises(ConfigError, match=message):
        robot_of(scenario)


def _position_scenario(tmp_path, links, phase: float, extra: str = ""):
    """A serial arm of ``links`` from a file naming the description, the base, the end
    effector and task: !EndEffectorPosition (its start chosen for the linear rows)."""
    from dacph_drake.robots.serial_arm import serial_arm_urdf
    from dacph_drake.assembly.scenario_files import load_scenario
    (tmp_path / "arm.urdf").write_text(serial_arm_urdf("arm", links))
    (tmp_path / "arm.yaml").write_text(
        "robot: !DescribedArm\n  description: arm.urdf\n  base: {mass: 200.0}\n"
        "  end_effector: {frame: tool}\ntask: !EndEffectorPosition {}\n"
        f"phases: {{warmup: {phase}, linear: {phase}, nonlinear: {phase}, "
        f"disturbance: {phase}}}\n{extra}")
    return load_scenario(tmp_path / "arm.yaml")


FOUR = [SerialLink(4.0, 0.4), SerialLink(3.0, 0.35), SerialLink(2.0, 0.3),
        SerialLink(1.0, 0.2)]


def test_the_position_rates_track_the_position_rows_exactly():
    """position_rates: with no task damping D_p nu = v_d - Lambda e_p (an arm of 4
    joints has a null space: xi passes through it), and nu_dot is the rate of nu
    along the motion (central differences of q, the base and t)."""
    from dacph_drake.kernels.attitude import position_rates, position_rows, turned
    from dacph_drake.dynamics.floating_model import FloatingBaseModel
    from dacph_drake.robots.description import MakeRobotPlant
    from dacph_drake.robots.serial_arm import serial_arm_urdf
    import tempfile
    from pathlib import Path
    rng = np.random.default_rng(48)
    folder = Path(tempfile.mkdtemp())
    (folder / "arm.urdf").write_text(serial_arm_urdf("arm", FOUR))
    from dacph_drake.scenario import ArmBase, DescribedArm, EndEffectorFrame
    arm = DescribedArm(description=str(folder / "arm.urdf"), base=ArmBase(mass=200.0),
                       end_effector=EndEffectorFrame(frame="tool"))
    model = FloatingBaseModel(MakeRobotPlant(arm))
    tree = model.kernel_tree
    node, X_CE = model.FrameNode(model.plant.GetFrameByName("end_effector"))
    end_effector = (node, np.ascontiguousarray(X_CE[:3, :3]))
    position = np.concatenate([X_CE[:3, 3], [0.3, 0.1, 0.5], [0.0, 0.6, 0.8],
                               [0.03, 2 * np.pi / 8.0, 1.0]])
    q, qdot = rng.uniform(-1, 1, 4), rng.normal(size=4)
    base = np.concatenate([[1.0, 0.0, 0.0, 0.0], [0.1, -0.2, 0.05]])
    omega = rng.normal(size=3)
    velocity = np.concatenate([omega, rng.normal(size=3)])
    xi = 0.1 * rng.normal(size=4)
    t, Lambda = 1.3, 2.0

    def rates(h):
        moved = np.concatenate([turned(base[:4], h * omega), base[4:] + h * velocity[3:]])
        return position_rates(tree[0], tree[1], tree[2], tree[7],
                              model.Evaluate(q + h * qdot), qdot, moved, velocity,
                              t + h, end_effector, position, xi, np.zeros(4), Lambda,
                              0.0)
    nu, nu_dot, e_p, p_d = rates(0.0)
    p_E, v_E, D_p, _ = position_rows(tree[0], tree[1], tree[2], tree[7],
                                     model.Evaluate(q), qdot, base[:4], base[4:],
                                     velocity, node, position[:3])
    v_d = position[6:9] * 0.03 * position[10] * np.cos(position[10] * t)
    np.testing.assert_allclose(e_p, p_E - p_d, atol=1e-15)
    np.testing.assert_allclose(D_p @ nu, v_d - Lambda * e_p, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(nu_dot, (rates(1e-6)[0] - rates(-1e-6)[0]) / 2e-6,
                               rtol=0, atol=1e-6 * np.abs(nu_dot).max())


def test_the_position_task_tracks_a_four_joint_arms_end_effector(tmp_path):
    """task: !EndEffectorPosition on a 4-joint arm (which cannot turn its end effector
    about every axis): the file loads with a start chosen for the linear rows, DAC and
    the baseline run every phase (1.5 s each), the tracking error is |e_p| [m] (from
    the 2 cm initial offset), DAC's phase-3 error is below 1e-4 m and below the
    baseline's, the attitude is not reported, and the task's panel draws |e_p|."""
    from dacph_drake.loop.metrics import run_metrics
    from dacph_drake.app.figures import make_panels
    from dacph_drake.log_layout import PoseLog
    from dacph_drake.loop.simulate import simulate
    scenario = _position_scenario(tmp_path, FOUR, 1.5)
    assert type(scenario.task).__name__ == "EndEffectorPosition"
    runs = {name: simulate(scenario, name) for name in ("dac", "model-based")}
    assert all(run.status == "ok" for run in runs.values())
    log = runs["dac"].logs["position_log"]
    assert log[0, PoseLog().e_position_norm] == pytest.approx(0.02, rel=1e-6)
    metrics = {name: run_metrics(run.logs, scenario) for name, run in runs.items()}
    dac, base = metrics["dac"], metrics["model-based"]
    assert dac["phase3.tracking_error_rms"] == dac["phase3.position_error_rms"]
    assert dac["phase3.position_error_rms"] < 1e-4
    assert dac["phase3.position_error_rms"] < base["phase3.position_error_rms"]
    assert not any(key.startswith("attitude_error") for key in dac)
    panel = make_panels({n: r.logs for n, r in runs.items()}, scenario)[
        "e_position_dac_vs_model_based"]
    assert "position error" in panel.axes[0].get_ylabel() and len(panel.axes) == 4
    import matplotlib.pyplot as plt
    plt.close("all")


def test_a_position_task_needs_three_joints(tmp_path):
    """On a 2-joint arm the position task is refused naming the joint count."""
    from dacph_drake.assembly.registry import robot_of
    scenario = _position_scenario(tmp_path, FOUR[:2], 1.0, "q0: [0.3, 0.8]\n")
    with pytest.raises(ConfigError, match="at least 3 joints"):
        robot_of(scenario).RequireRunnableStart()
