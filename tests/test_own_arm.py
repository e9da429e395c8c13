"""An arm from its own description, as users have it (issue 24): a scenario file
naming only the robot, its base, its end effector and q0 gets every other setting
sized to the arm (robots.sizing); descriptions named by package:// URIs found the
ROS 2 way (the ament index of AMENT_PREFIX_PATH and of pip's cmeel prefix); a
fixed-base file's weld to the world dropped when it is mounted; and the shipped
Panda and UR5 scenarios (example-robot-data, the [robots] extra) run."""
import re
import sysconfig
from pathlib import Path

import numpy as np
import pytest

from dacph_drake.robots.described import arm_scenario
from dacph_drake.robots.sizing import DAMPING_RATE
from dacph_drake.robots.start_pose import rehearse
from dacph_drake.dynamics.floating_model import FloatingBaseModel
from dacph_drake.scenario.errors import ConfigError
from dacph_drake.robots.description import MODELS, MakeRobotPlant
from dacph_drake.scenario import ArmBase, DescribedArm
from dacph_drake.assembly.scenario_files import load_scenario

MOUNT = ArmBase(mass=250.0, size=[1.0, 1.0, 1.0], mount=[0.0, 0.0, 0.5, 0.0, 0.0, 0.0])
ROOT = Path(__file__).resolve().parents[1]
EXAMPLE_ROBOT_DATA = (Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix" / "share"
                      / "example-robot-data")
needs_example_robot_data = pytest.mark.skipif(
    not EXAMPLE_ROBOT_DATA.is_dir(),
    reason="example-robot-data is not installed (pip install 'dacph-drake[robots]')")


@pytest.fixture
def arm_alone(tmp_path):
    """satellite_3dof's arm without its base, welded to the world by a fixed joint
    as a fixed-base arm's file is (a UR5's world_joint), in an ament prefix:
    share/my_arm/arm.urdf, indexed as share/ament_index/resource_index/packages/
    my_arm."""
    text = (MODELS / "satellite_3dof.urdf").read_text()
    text = re.sub(r'<link name="base">.*?</link>', '<link name="arm_root"/>', text,
                  flags=re.S)
    text = text.replace('<parent link="base"/>', '<parent link="arm_root"/>')
    text = text.replace('<origin xyz="0 0 0.5" rpy="0 0 0"/>',
                        '<origin xyz="0 0 0" rpy="0 0 0"/>', 1)
    text = text.replace("</robot>", '<link name="world"/><joint name="world_joint" '
                        'type="fixed"><parent link="world"/><child link="arm_root"/>'
                        '</joint></robot>')
    prefix = tmp_path / "prefix"
    (prefix / "share" / "my_arm").mkdir(parents=True)
    (prefix / "share" / "my_arm" / "arm.urdf").write_text(text)
    index = prefix / "share" / "ament_index" / "resource_index" / "packages"
    index.mkdir(parents=True)
    (index / "my_arm").write_text("")
    return prefix


def test_a_file_naming_only_the_arm_gets_settings_sized_to_it(arm_alone, tmp_path,
                                                               monkeypatch, caplog):
    """A scenario file of robot (a package:// description found through
    AMENT_PREFIX_PATH, its world weld dropped with a note; its own end_effector
    frame), base and q0 loads with every per-joint setting sized to the arm by
    robots.sizing's rule:
    D0 = DAMPING_RATE M_jj(q0), the linear group adding 0.5 D0 at the momentum
    p_j = max(M_jj w, the rehearsal's peak |p_j| past the warm-up) (the coupled
    inertia: never below the diagonal's scale), the disturbance's offsets 0.3
    max(M_jj w (2 pi / T), the rehearsal's peak |dp_j/dt| past the warm-up) with
    alternating signs; the same as arm_scenario
    from Python. A per-joint list of the wrong length given in the file is still
    named in one line."""
    monkeypatch.setenv("AMENT_PREFIX_PATH", str(arm_alone))
    body = ("robot: !DescribedArm\n"
            "  description: package://my_arm/arm.urdf\n"
            "  base: {mass: 250.0, size: [1.0, 1.0, 1.0], mount: [0, 0, 0.5, 0, 0, 0]}\n"
            "q0: [0.3, -0.8, 1.6]\n")
    path = tmp_path / "arm.yaml"
    path.write_text(body)
    scenario = load_scenario(path)
    assert "weld 'world_joint' to the world is dropped" in caplog.text
    model = FloatingBaseModel(MakeRobotPlant(scenario.robot))
    M = np.diag(model.MassMatrix(np.array([0.3, -0.8, 1.6])))
    reference = scenario.task.reference
    w = 2 * np.pi * reference.amplitude / reference.period
    u, d = scenario.uncertainty, scenario.disturbance
    rehearsal = rehearse(model, [0.3, -0.8, 1.6], scenario.task,
                         scenario.phases.warmup + reference.period)
    steady = rehearsal.time >= scenario.phases.warmup
    p = np.maximum(M * w, np.abs(rehearsal.p[steady]).max(axis=0))
    torque = np.maximum(M * w * 2 * np.pi / reference.period,
                        np.abs(rehearsal.p_rate[steady]).max(axis=0))
    assert np.any(p > M * w)            # the coupling moves a joint beyond M_jj w
    np.testing.assert_allclose(u.D0, DAMPING_RATE * M, rtol=1e-12)
    np.testing.assert_allclose(np.asarray(u.D_offset) + np.asarray(u.D_linear) * p,
                               0.5 * np.asarray(u.D0), rtol=1e-12)
    np.testing.assert_allclose(d.lf_offset, [0.3, -0.3, 0.3] * torque, rtol=1e-12)
    assert u.B0 == [1.0] * 3 and len(u.B_linear) == 3 and len(d.hf_direction) == 3
    assert scenario.phases.end == 14.0 and scenario.periods.rhs == 5e-4
    assert scenario == arm_scenario(scenario.robot, [0.3, -0.8, 1.6])
    path.write_text(body + "uncertainty: {D0: [0.1, 0.1]}\n")
    with pytest.raises(ConfigError, match=r"^uncertainty.D0 has 2 entries; allowed: 3 "):
        load_scenario(path)


def test_a_world_anchored_arm_without_a_base_is_named(arm_alone):
    """Without robot.base, a file welded to the world has no free body: named in
    one line (no Drake assertion)."""
    arm = DescribedArm(description=str(arm_alone / "share" / "my_arm" / "arm.urdf"))
    with pytest.raises(ConfigError, match=r"0 free bodies; allowed: .*robot.base"):
        MakeRobotPlant(arm)
    assert MakeRobotPlant(DescribedArm(description=arm.description, base=MOUNT)
                          ).num_velocities() == 6 + 3


def test_an_unknown_package_is_named(monkeypatch):
    monkeypatch.delenv("AMENT_PREFIX_PATH", raising=False)
    with pytest.raises(ConfigError, match=r"unknown package 'no_such_arm'; allowed: "):
        MakeRobotPlant(DescribedArm(description="package://no_such_arm/arm.urdf",
                                    base=MOUNT))


@needs_example_robot_data
def test_the_shipped_ur5_scenario_builds_as_shipped():
    """scenarios/ur5.yaml (14 lines) loads the UR5 file unmodified: 6 joints, its
    per-joint settings sized to it, its effort limits (150, 150, 150, 28, 28, 28
    N m) on the actuators."""
    scenario = load_scenario(ROOT / "scenarios" / "ur5.yaml")
    assert len((ROOT / "scenarios" / "ur5.yaml").read_text().splitlines()) <= 20
    plant = MakeRobotPlant(scenario.robot)
    assert plant.num_actuators() == 6 and len(scenario.uncertainty.D0) == 6
    np.testing.assert_allclose(plant.GetEffortUpperLimits(), [150] * 3 + [28] * 3)


@needs_example_robot_data
def test_the_shipped_panda_scenario_runs_dac(tmp_path):
    """scenarios/panda.yaml (the Panda file unmodified, its fingers locked) runs
    DAC through `dacph simulate` for 3 s: status ok, the attitude error falls
    below a tenth of its start (0.3 rad), the spatial momentum stays zero, no
    command saturates."""
    from dacph_drake.app.cli import main
    from dacph_drake.loop.metrics import run_metrics
    from dacph_drake.loop.run_store import load_run
    path = ROOT / "scenarios" / "panda.yaml"
    assert len(path.read_text().splitlines()) <= 20
    assert main(["simulate", str(path), "--out", str(tmp_path / "run"),
                 "--duration", "3"]) == 0
    logs, scenario, record = load_run(tmp_path / "run", "dac")
    assert record["status"] == "ok"
    metrics = run_metrics(logs, scenario)
    assert metrics["attitude_error_final"] < 0.03
    assert metrics["max_momentum"] < 1e-8
    assert metrics["effort_saturated_share"] == 0.0
