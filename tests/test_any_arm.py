"""Any arm as its maker ships it (issue 38): a heavily damped arm integrated stably
through every phase, quirks of real descriptions tolerated with one line per
kind, SDF and MJCF through the URDF's path, xacro refused with its command, a
singular start refused by its joints' names, an automatic start within limits
and clear of the base, errors naming joints and frames, one thread for the
numerical libraries in a run, and the zoo's short version (scripts/zoo.py)."""
import json
import logging
import subprocess
import sys
import sysconfig
from pathlib import Path
from typing import Dict

import numpy as np
import pytest
from threadpoolctl import threadpool_info

from dacph_drake.robots.described import arm_scenario
from dacph_drake.robots.sizing import DEFAULT_STEP
from dacph_drake.dynamics.floating_model import FloatingBaseModel
from dacph_drake.scenario.errors import ConfigError
from dacph_drake.loop.simulate import simulate
from dacph_drake.loop.threads import single_threaded
from dacph_drake.assembly.registry import robot_of
from dacph_drake.montecarlo.definition import apply_model_error_sample
from dacph_drake.robots.described import link_base_clearance
from dacph_drake.robots.description import MakeRobotPlant, ParsedDescription
from dacph_drake.robots.serial_arm import SerialLink, serial_arm_urdf
from dacph_drake.robots.start_pose import (CLEARANCE_BOUND, SINGULAR_BOUND,
                                           rehearse, task_jacobian, within_limits)
from dacph_drake.scenario import ArmBase, DescribedArm, EndEffectorFrame
from dacph_drake.assembly.scenario_files import load_scenario

ROOT = Path(__file__).resolve().parents[1]
needs_example_robot_data = pytest.mark.skipif(
    not (Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix" / "share"
         / "example-robot-data").is_dir(),
    reason="example-robot-data is not installed (pip install 'dacph-drake[robots]')")
ARMS = Path(__file__).resolve().parent / "data" / "arms"
SIX = [SerialLink(4.0, 0.4), SerialLink(3.0, 0.35), SerialLink(2.0, 0.3),
       SerialLink(1.0, 0.2), SerialLink(0.5, 0.1), SerialLink(0.3, 0.08)]


def _arm_file(tmp_path: Path, name: str, urdf: str, extra: str = "") -> Path:
    """A scenario file of at most six lines naming the description, the base's
    mass and the end-effector frame."""
    (tmp_path / f"{name}.urdf").write_text(urdf)
    path = tmp_path / f"{name}.yaml"
    path.write_text(f"robot: !DescribedArm\n  description: {name}.urdf\n"
                    f"  base: {{mass: 200.0}}\n  end_effector: {{frame: tool}}\n{extra}")
    return path


def test_a_heavily_damped_arm_runs_every_phase_on_a_step_its_damping_allows(tmp_path):
    """Joint damping of 20 N m s/rad on a 1.6e-4 kg m^2 wrist decays at ~1e5 1/s,
    far beyond the default 0.25 ms RK2 step's stability (h lambda <= 2): the sized
    step keeps h lambda <= 1 for the fastest mode, and every controller runs every
    (shortened) phase with the momentum conserved."""
    links = [SerialLink(link.mass, link.length, damping) for link, damping
             in zip(SIX, (20.0, 20.0, 10.0, 5.0, 5.0, 5.0))]
    path = _arm_file(tmp_path, "damped", serial_arm_urdf("damped", links),
                     "phases: {warmup: 0.3, linear: 0.3, nonlinear: 0.3, "
                     "disturbance: 0.3}\n")
    scenario = load_scenario(path)
    assert scenario.simulator.max_step_size < DEFAULT_STEP / 2
    model = FloatingBaseModel(MakeRobotPlant(scenario.robot))
    M = model.MassMatrix(np.asarray(scenario.q0))
    L = np.linalg.inv(np.linalg.cholesky(M))
    damping = np.diag([20.0, 20.0, 10.0, 5.0, 5.0, 5.0])
    fastest = np.max(np.linalg.eigvalsh(L @ damping @ L.T))
    assert fastest * DEFAULT_STEP > 2                  # the default step would blow up
    assert fastest * scenario.simulator.max_step_size <= 1.0
    for controller in ("dac", "dac-nominal", "model-based"):
        result = simulate(scenario, controller)
        assert result.status == "ok", (controller, result.reason)
        assert result.final_time == pytest.approx(scenario.phases.end)


def test_duplicate_materials_load_with_one_line_per_kind(tmp_path, caplog):
    """A URDF defining one material in every link (as Kinova's does), with an
    unsupported tag on every joint: Drake alone refuses the file; here it loads,
    each quirk reported once, naming the user's file and its lines."""
    text = serial_arm_urdf("quirky", SIX)
    text = text.replace("<collision>", '<visual><geometry><box size="0.01 0.01 0.01"/>'
                        '</geometry><material name="carbon"><color rgba="0.3 0.3 0.3 1"/>'
                        '</material></visual><collision>')
    text = text.replace("<dynamics", '<safety_controller soft_lower_limit="-2"/><dynamics')
    text = text.replace("><", ">\n<")               # lines to name
    path = _arm_file(tmp_path, "quirky", text, "q0: [0.3, -0.8, 1.2, 0.2, 0.6, -0.3]\n")
    with caplog.at_level(logging.WARNING):
        scenario = load_scenario(path)
        robot_of(scenario)
    lines = [r.getMessage() for r in caplog.records]
    materials = [line for line in lines if "material 'carbon'" in line]
    tags = [line for line in lines if "safety_controller" in line]
    assert len(materials) == 1 and len(tags) == 1, lines
    assert "quirky.urdf" in materials[0] and "defined again on 6 lines" in materials[0]
    assert tags[0].startswith(str(tmp_path / "quirky.urdf") + ":")
    assert "6 lines of this kind" in tags[0]
    assert not any("<literal-string>" in line for line in lines)


def test_xacro_is_refused_with_the_command_that_expands_it(tmp_path):
    (tmp_path / "arm.urdf.xacro").write_text('<robot xmlns:xacro="http://www.ros.org/'
                                             'wiki/xacro"><xacro:property/></robot>')
    with pytest.raises(ConfigError, match=r"xacro macro file.*`xacro .*arm\.urdf\.xacro "
                                          r"-o .*arm\.urdf`"):
        MakeRobotPlant(DescribedArm(description=str(tmp_path / "arm.urdf.xacro"),
                                    base=ArmBase(mass=100.0)))


@pytest.mark.parametrize("suffix, edit, message", [
    (".urdf", lambda text: text.replace('<origin xyz="0 0 0.2"/>', '<origin xyz="0 0"/>', 1),
     r"a\.urdf: Expected 3 values for attribute xyz got 0 0"),
    (".urdf", lambda text: text.replace('ixx="0.01"', 'ixx="nan"', 1),
     r"a\.urdf:1: error: Expected single value for attribute 'ixx' got 'nan'"),
    (".sdf", lambda text: text.replace("<xyz>0 1 0</xyz>", "<xyz>0 1</xyz>", 1),
     r"a\.sdf:\d+: error: .*joint\[@name=\"joint2\"\]/axis/xyz: Error reading element"),
])
def test_a_malformed_vector_in_a_urdf_or_sdf_is_refused_in_one_line(tmp_path, suffix,
                                                                     edit, message):
    """A vector attribute of the wrong count or a non-number (Drake's parser raises a
    bare ValueError for some) ends in one ConfigError naming the file."""
    text = (serial_arm_urdf("a", SIX[:3]) if suffix == ".urdf"
            else (ARMS / "arm3.sdf").read_text())
    path = tmp_path / f"a{suffix}"
    path.write_text(edit(text))
    with pytest.raises(ConfigError, match=message) as error:
        MakeRobotPlant(DescribedArm(description=str(path), base=ArmBase(mass=100.0)))
    assert "\n" not in str(error.value)


def test_sdf_and_mjcf_go_through_the_same_path_as_urdf():
    """The same three-joint arm in MJCF (its root welded to the world: dropped) and
    SDFormat: the same joints, mass matrix and chosen start."""
    starts, matrices = [], []
    for name in ("arm3.xml", "arm3.sdf"):
        arm = DescribedArm(description=str(ARMS / name), base=ArmBase(mass=100.0),
                           end_effector=EndEffectorFrame(frame="link3"))
        scenario = arm_scenario(arm)
        model = FloatingBaseModel(MakeRobotPlant(arm))
        starts.append(scenario.q0)
        matrices.append(model.MassMatrix(np.asarray(scenario.q0)))
    np.testing.assert_allclose(starts[0], starts[1], rtol=1e-12)
    np.testing.assert_allclose(matrices[0], matrices[1], rtol=1e-9, atol=1e-12)


def test_a_start_at_a_task_singularity_is_refused_by_name(tmp_path):
    """Axes z, y, z with the middle joint at 0: joints 1 and 3 turn the end
    effector about the same axis (gimbal lock): refused, naming them."""
    urdf = serial_arm_urdf("gimbal", SIX[:3], axes=("0 0 1", "0 1 0", "0 0 1"))
    path = _arm_file(tmp_path, "gimbal", urdf, "q0: [0.4, 0.0, -0.2]\n")
    scenario = load_scenario(path)
    with pytest.raises(ConfigError, match=r"q0 = \[0.4, 0.0, -0.2\]: the end "
                                          r"effector's attitude is singular there .*"
                                          r"joints ('joint1', 'joint3'|'joint3', "
                                          r"'joint1') turn it"):
        robot_of(scenario).RequireRunnableStart()
    path.write_text(path.read_text().replace("q0: [0.4, 0.0, -0.2]",
                                             "q0: [0.4, 0.7, -0.2]"))
    robot_of(load_scenario(path)).RequireRunnableStart()


@pytest.mark.parametrize("name, links, tool", [
    ("tiny_wrist", SIX[:3] + [SerialLink(0.05, 0.03), SerialLink(0.02, 0.02),
                              SerialLink(0.01, 0.02)], 0.0),
    ("chain9", [SerialLink(2.0 * 0.85**k, 0.3 * 0.9**k) for k in range(9)], 0.0),
    ("heavy_tool", SIX, 5.0)])
def test_the_automatic_start_is_within_limits_clear_of_the_base_and_regular(
        tmp_path, name, links, tool):
    """Without q0 a start is chosen: its rehearsal of the task keeps every joint
    within 10 % of its range from its limits and D's smallest singular value above
    SINGULAR_BOUND; its links are CLEARANCE_BOUND clear of the base."""
    path = _arm_file(tmp_path, name, serial_arm_urdf(name, links, tool))
    scenario = load_scenario(path)
    parsed = ParsedDescription(scenario.robot)
    model = FloatingBaseModel(parsed.plant)
    q0 = np.asarray(scenario.q0)
    assert link_base_clearance(parsed, model)(q0) >= CLEARANCE_BOUND   # these arms
    #                                                    can reach that far
    rehearsal = rehearse(model, q0, scenario.task,
                         scenario.phases.warmup + scenario.task.reference.period)
    assert within_limits(model, rehearsal.q)
    assert np.min(rehearsal.singular_value) >= SINGULAR_BOUND
    assert np.linalg.svd(task_jacobian(model, q0), compute_uv=False)[-1] >= SINGULAR_BOUND
    robot_of(scenario).RequireRunnableStart()


def test_errors_name_the_joints_frames_and_bodies(tmp_path):
    path = _arm_file(tmp_path, "named", serial_arm_urdf("named", SIX[:3]),
                     "q0: [0.1, 0.2]\n")
    with pytest.raises(ConfigError, match=r"q0 has 2 entries; allowed: 3 \(one per "
                                          r"joint\); the joints in q0's order: joint1, "
                                          r"joint2, joint3$"):
        robot_of(load_scenario(path))
    arm = DescribedArm(description=str(tmp_path / "named.urdf"), base=ArmBase(mass=1.0),
                       end_effector=EndEffectorFrame(frame="tol"))
    with pytest.raises(ConfigError, match=r"frame = 'tol' is not a frame of .*named"
                                          r"\.urdf \(did you mean 'tool'\?\); allowed: "
                                          r"one of its link frames: root, link1, link2, "
                                          r"link3, tool"):
        MakeRobotPlant(arm)
    path.write_text(path.read_text().replace("q0: [0.1, 0.2]", "q0: [0.1, 0.2, 0.3]"))
    scenario = load_scenario(path)
    scenario.robot.nominal_inertia_scale = [1.0]
    with pytest.raises(ConfigError, match=r"nominal_inertia_scale has 1 entries; "
                                          r"allowed: 5, one per body with mass in this "
                                          r"order: root, link1, link2, link3, base"):
        robot_of(scenario)


def test_a_run_limits_blas_and_openmp_to_one_thread():
    """Inside a run (loop.threads.single_threaded) every BLAS and OpenMP pool has
    one thread, and the caller's settings come back afterwards."""
    before = {(i["internal_api"], i["prefix"]): i["num_threads"]
              for i in threadpool_info()}
    with single_threaded():
        assert all(i["num_threads"] == 1 for i in threadpool_info())
    assert {(i["internal_api"], i["prefix"]): i["num_threads"]
            for i in threadpool_info()} == before


@needs_example_robot_data
def test_the_zoo_short_version(tmp_path):
    """scripts/zoo.py --quick: the xArm7 (damping 2-10 N m s/rad on light wrists),
    an arm of our own with heavier damping and the Unitree Z1 (its gripper locked,
    its rest pose on a joint limit), each from its file of at most six lines, run
    the warm-up and the start of the first phase under all three controllers."""
    done = subprocess.run([sys.executable, str(ROOT / "scripts" / "zoo.py"), "--quick",
                           "--duration", "2.2", "--out", str(tmp_path)],
                          capture_output=True, text=True, cwd=ROOT)
    assert done.returncode == 0, done.stderr[-2000:]
    rows = [json.loads(line) for line in (tmp_path / "rows.jsonl").read_text()
            .splitlines()]
    assert [row["arm"] for row in rows] == ["xarm7", "heavy_damping", "z1"]
    for row in rows:
        assert row["file_lines"] <= 6
        for controller in ("dac", "dac-nominal", "model-based"):
            assert row[controller]["status"] == "ok", (row["arm"], row[controller])


def test_q0_by_joint_name(tmp_path):
    """q0 as a mapping joint name -> angle reads as the list in q's order; a name
    the arm does not have is named with the closest one, a joint left out too."""
    urdf = serial_arm_urdf("named", SIX[:3])
    path = _arm_file(tmp_path, "named", urdf,
                     "q0: {joint3: -0.2, joint1: 0.4, joint2: 0.7}\n")
    assert load_scenario(path).q0 == [0.4, 0.7, -0.2]
    path.write_text(path.read_text().replace("joint3: -0.2", "jiont3: -0.2"))
    with pytest.raises(ConfigError, match=r"^q0.jiont3 is not a joint of the arm \(did "
                                          r"you mean 'joint3'\?\); allowed: joint1, "
                                          r"joint2, joint3$"):
        load_scenario(path)
    path.write_text(path.read_text().replace("jiont3: -0.2, ", ""))
    with pytest.raises(ConfigError, match=r"^q0 leaves out the joints joint3; "):
        load_scenario(path)


def test_the_coupling_ratio_is_the_normalized_inverse_mass_matrix_largest_eigenvalue():
    """kernels.attitude.coupling_ratio against numpy on random positive definite M
    (one far from diagonal), and 1 for a diagonal M."""
    from dacph_drake.kernels.attitude import coupling_ratio
    rng = np.random.default_rng(3)
    for n in (3, 6, 9):
        A = rng.standard_normal((n, n))
        M = A @ A.T + 1e-3 * np.eye(n)
        root = np.sqrt(np.diag(M))
        expected = np.max(np.linalg.eigvalsh(np.outer(root, root) * np.linalg.inv(M)))
        assert coupling_ratio(M) == pytest.approx(expected, rel=1e-3)
    assert coupling_ratio(np.diag([3.0, 1e-4, 0.2])) == pytest.approx(1.0)


def test_a_strongly_coupled_arm_runs_its_start(tmp_path):
    """A 5-joint arm whose 4.2 kg tool makes one coupled motion 195 times lighter
    than the joints' own inertias say (family_1_012 of scripts/zoo.py --family 64
    --seed 1): its boundary layer thickens (AttitudeController) and DAC runs the
    warm-up, where it ran away at 22 ms."""
    links = [SerialLink(0.37, 0.279), SerialLink(0.208, 0.115), SerialLink(0.0183, 0.249),
             SerialLink(0.328, 0.116), SerialLink(0.665, 0.0734)]
    path = _arm_file(tmp_path, "coupled", serial_arm_urdf(
        "coupled", links, tool_mass=4.19), "phases: {warmup: 0.5, linear: 0.1, "
        "nonlinear: 0.1, disturbance: 0.1}\n")
    result = simulate(load_scenario(path), "dac")
    assert result.status == "ok", result.reason


def test_a_damping_too_stiff_to_integrate_is_refused_by_name(tmp_path):
    """18 N m s/rad on a 6 g, 3 cm link asks for a step of ~0.1 us: refused at the
    build, naming the step and the joint, instead of a run of hours."""
    links = [SerialLink(1.15, 0.40, 0.27), SerialLink(0.056, 0.28, 0.94),
             SerialLink(0.0064, 0.03, 18.4)]
    path = _arm_file(tmp_path, "stiff", serial_arm_urdf("stiff", links),
                     "q0: [0.3, 0.8, -0.4]\n")
    scenario = load_scenario(path)
    assert scenario.simulator.max_step_size < 1e-6
    with pytest.raises(ConfigError, match=r"^simulator.max_step_size = .* s, the step "
                                          r"the description's joint damping asks for "
                                          r"\(joint 'joint3': 18.4 N m s/rad on"):
        robot_of(scenario).RequireRunnableStart()


def test_a_sweeps_model_error_lands_on_the_bodies_it_names(tmp_path):
    """A sweep's nominal_link_mass_scale and nominal_base_mass_scale on a mounted arm
    (its description's root first, robot.base's box last): the base's factor on the
    free base's body, joint j's on the body joint j moves, 1 on the description's
    root; the controller's model then has those bodies' masses, the truth its own."""
    path = _arm_file(tmp_path, "swept", serial_arm_urdf("swept", SIX[:3]))
    scenario = load_scenario(path)
    apply_model_error_sample(scenario.robot, [2.0, 3.0, 4.0], 5.0)
    assert scenario.robot.nominal_inertia_scale == [1.0, 2.0, 3.0, 4.0, 5.0]
    robot = robot_of(scenario)
    mass = {body.name(): body.default_mass() for body in robot.model.parameters.bodies}
    nominal = robot.model.inertial_parameters.reshape(-1, 10)[:, 0]
    np.testing.assert_allclose(nominal, [mass["root"], 2 * mass["link1"],
                                         3 * mass["link2"], 4 * mass["link3"],
                                         5 * mass["base"]], rtol=1e-12)
    apply_model_error_sample(scenario.robot, None, 0.5)
    assert scenario.robot.nominal_inertia_scale == [1.0, 1.0, 1.0, 1.0, 0.5]


def test_a_heavy_joints_actuator_leaks_into_a_light_one_at_its_own_scale(tmp_path):
    """On an arm whose shoulder carries 60x the torque of the joint after it (a
    random arm's, tests/data/arms/coupled_light_joints.urdf, base 37 kg), the sized
    couplings of the true actuators put at most the paper's fractions of the
    receiving joint's own torque scale into it (|B_jk| tau_k <= 0.4 tau_j for the
    q1^2 coupling at |q1| = 1 rad, 0.05 tau_j for the linear block), and the
    model-based baseline runs through the start of the nonlinear phase, where with
    the paper's unscaled fractions every controller ran away (t = 6.03-6.05 s)."""
    urdf = (ARMS / "coupled_light_joints.urdf").read_text()
    path = tmp_path / "coupled.yaml"
    (tmp_path / "coupled.urdf").write_text(urdf)
    path.write_text("robot: !DescribedArm\n  description: coupled.urdf\n"
                    "  base: {mass: 37.0301}\n  end_effector: {frame: tool}\n")
    scenario = load_scenario(path)
    d = scenario.disturbance
    torque = np.abs(np.asarray(d.hf_direction)) * d.hf_amplitude / 0.05
    assert torque[0] > 20 * torque[1]
    u = scenario.uncertainty
    for matrix, fraction in ((u.B_q1_squared, 0.4), (u.B_linear, 0.05)):
        leak = np.abs(np.asarray(matrix)) * torque[None, :]
        np.fill_diagonal(leak, 0.0)
        assert np.all(leak <= fraction * torque[:, None] * (1 + 1e-12))
    result = simulate(scenario, "model-based", duration=6.5)
    assert result.status == "ok", result.reason


def _robosuite_style(tmp_path: Path) -> Path:
    """arm3.xml as robosuite ships its arms: the arm in an <include>d file, a massless
    mount body (mass="0" diaginertia="0 0 0") between the root and the arm, a binary
    STL collision mesh without a name in compiler meshdir, and a MuJoCo .msh one."""
    from test_arm_mount import _stl
    (tmp_path / "meshes").mkdir()
    half = np.array([0.03, 0.03, 0.1])
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * half
    faces = np.array([(0, 1, 3), (0, 3, 2), (4, 6, 7), (4, 7, 5), (0, 4, 5), (0, 5, 1),
                      (2, 3, 7), (2, 7, 6), (0, 2, 6), (0, 6, 4), (1, 5, 7), (1, 7, 3)])
    (tmp_path / "meshes" / "link1.stl").write_bytes(_stl(corners[faces], True))
    header = np.array([8, 0, 0, 12], "<i4").tobytes()
    (tmp_path / "meshes" / "link2.msh").write_bytes(
        header + corners.astype("<f4").tobytes() + faces.astype("<i4").tobytes())
    text = (ARMS / "arm3.xml").read_text()
    arm = text[text.index('<body name="link1"'):text.index("</body>\n    </body>")] \
        + "</body>"
    arm = arm.replace('<geom name="link1_geom" type="cylinder" pos="0 0 0.2" '
                      'size="0.04 0.2"/>', '<geom name="link1_geom" type="mesh" '
                      'mesh="link1" pos="0 0 0.2"/>')
    arm = arm.replace('<geom name="link2_geom" type="cylinder" pos="0 0 0.15" '
                      'size="0.03 0.15"/>', '<geom name="link2_geom" type="mesh" '
                      'mesh="shoulder" pos="0 0 0.15"/>')
    (tmp_path / "arm_body.xml").write_text(
        f'<mujoco><body name="mount" pos="0 0 0"><inertial pos="0 0 0" mass="0" '
        f'diaginertia="0 0 0"/>{arm}</body></mujoco>')
    main = text[:text.index('<body name="link1"')].replace(
        '<compiler angle="radian"/>', '<compiler angle="radian" meshdir="meshes"/>\n'
        '  <asset><mesh file="link1.stl"/><mesh name="shoulder" file="link2.msh"/>'
        '</asset>') + '<include file="arm_body.xml"/>\n    </body>\n  </worldbody>\n' \
        '</mujoco>\n'
    path = tmp_path / "robot.xml"
    path.write_text(main)
    return path


def test_an_mjcf_arm_as_robosuite_ships_it_loads_unchanged(tmp_path):
    """An MJCF with an include, meshdir, an STL and a .msh mesh (one without a name) and a
    massless mount body loads as MuJoCo reads it: the same joints and mass matrix as the
    plain arm3.xml (the massless body adds nothing), the meshes converted to OBJ in the
    cache (the user's folder untouched), the clearance potential measuring them."""
    from dacph_drake.robots.clearance_potential import BaseClearancePotential
    path = _robosuite_style(tmp_path)
    before = sorted(p.name for p in tmp_path.rglob("*"))
    matrices = []
    for description in (ARMS / "arm3.xml", path):
        arm = DescribedArm(description=str(description), base=ArmBase(mass=100.0),
                           end_effector=EndEffectorFrame(frame="link3"))
        model = FloatingBaseModel(MakeRobotPlant(arm))
        matrices.append(model.MassMatrix(np.array([0.3, 0.8, -0.4])))
    np.testing.assert_allclose(matrices[1], matrices[0], rtol=1e-12, atol=1e-14)
    assert sorted(p.name for p in tmp_path.rglob("*")) == before
    potential = BaseClearancePotential(parsed=ParsedDescription(arm), model=model,
                                       gain=1.0, margin=0.1)
    assert np.isfinite(potential.Evaluate(np.array([0.3, 2.2, 0.5]), None).min_distance)


@pytest.mark.parametrize("edit, message", [
    (lambda p: (p.parent / "meshes" / "link1.stl").unlink(),
     r"robot\.xml: mesh 'link1': no such file .*link1\.stl"),
    (lambda p: p.write_text(p.read_text().replace('file="link1.stl"',
                                                  'file="link1.ply"')),
     r"robot\.xml: mesh 'link1' file 'link1\.ply' is a \.ply file; allowed: "
     r"\.stl, \.obj, \.msh"),
    (lambda p: (p.parent / "meshes" / "link1.stl").write_bytes(b"solid x\nendsolid x\n"),
     r"mesh '.*link1\.stl' is not an STL file"),
    (lambda p: (p.parent / "meshes" / "link2.msh").write_bytes(b"\x01\x00\x00\x00" * 3),
     r"mesh '.*link2\.msh' is not a MuJoCo \.msh file"),
    (lambda p: (p.parent / "arm_body.xml").unlink(),
     r"robot\.xml: <include file='arm_body\.xml'>: no such file"),
    (lambda p: (p.parent / "arm_body.xml").write_text(
        '<mujoco><include file="arm_body.xml"/></mujoco>'),
     r"<include file='arm_body\.xml'> nests more than 16 deep"),
    (lambda p: (p.parent / "arm_body.xml").write_text("<mujoco><body"),
     r"arm_body\.xml:1: not an XML file"),
    (lambda p: (p.parent / "arm_body.xml").write_text("<robot/>"),
     r"arm_body\.xml: its root element is <robot>; allowed: an MJCF file"),
    (lambda p: p.parent.joinpath("arm_body.xml").write_text(
        p.parent.joinpath("arm_body.xml").read_text().replace('mass="0"', 'mass="x"')),
     r"body 'mount': <inertial mass='x'>; allowed: a number >= 0"),
    (lambda p: p.parent.joinpath("arm_body.xml").write_text(
        p.parent.joinpath("arm_body.xml").read_text().replace(
            '<body name="link1"', '<body name="link1" quat="1 0 0"', 1)),
     r"robot\.xml: <body name='link1'> quat='1 0 0'; allowed: 4 finite numbers"),
    (lambda p: p.write_text(p.read_text().replace(
        "<worldbody>", '<default><joint axis="0 0 nan"/></default><worldbody>', 1)),
     r"<joint> axis='0 0 nan'; allowed: 3 finite numbers"),
    (lambda p: (p.write_text(p.read_text().replace(
        "<worldbody>", '<default><geom shellinertia="true"/></default><worldbody>', 1)),
        p.parent.joinpath("arm_body.xml").write_text(
            p.parent.joinpath("arm_body.xml").read_text().replace(
                '<inertial pos="0 0 0.2" mass="3" diaginertia="0.04 0.04 0.002"/>', ""))),
     r"robot\.xml: geom 'link1_geom' of body 'link1': shellinertia='true' \(MuJoCo's "
     r"thin-shell inertia\) is not modelled; allowed: a solid geom, or an <inertial>"),
])
def test_a_broken_mjcf_is_refused_in_one_line_naming_the_part(tmp_path, edit, message):
    """Each way an MJCF can be broken ends in one ConfigError naming the file and the
    mesh, include or body: never a Drake assertion or a traceback."""
    path = _robosuite_style(tmp_path)
    edit(path)
    arm = DescribedArm(description=str(path), base=ArmBase(mass=100.0),
                       end_effector=EndEffectorFrame(frame="link3"))
    with pytest.raises(ConfigError, match=message) as error:
        MakeRobotPlant(arm)
    assert "\n" not in str(error.value)


@pytest.mark.parametrize("setting, message", [
    ("q0: [.nan, 0.1, 0.2]", r"q0\[0\] = nan is not finite"),
    ("q0: [.inf, 0.1, 0.2]", r"q0\[0\] = inf is not finite"),
    ("q0: [1.0e308, 0.1, 0.2]", r"q0 = \[1e\+308, 0.1, 0.2\]; allowed: angles within "
                                r"\+-1000 rad"),
    ("task: !EndEffectorAttitude\n  reference: {axis: [0, 0, 0]}",
     r"task\.reference\.axis = \[0\.0, 0\.0, 0\.0\]; allowed: a non-zero 3-vector"),
    ("task: !EndEffectorAttitude\n  reference: {axis: [0, 1]}",
     r"task\.reference\.axis = \[0\.0, 1\.0\]; allowed: a non-zero 3-vector"),
    ("task: !EndEffectorAttitude\n  reference: {axis: [.nan, 0, 1]}",
     r"task\.reference\.axis\[0\] = nan is not finite"),
    ("task: !EndEffectorAttitude\n  reference: {initial_error_axis: [0, 0, 0]}",
     r"task\.reference\.initial_error_axis = \[0\.0, 0\.0, 0\.0\]; allowed"),
])
def test_a_described_arms_start_and_reference_are_checked_before_sizing(
        tmp_path, setting, message):
    """q0 and the reference's axes are checked before the start-pose search, sizing or a
    plant reads them: one line naming the setting, never Drake's AllFinite assertion
    or numpy's 'SVD did not converge'."""
    path = tmp_path / "bad.yaml"
    path.write_text(f"robot: !DescribedArm\n  description: satellite_3dof\n{setting}\n")
    with pytest.raises(ConfigError, match=message):
        load_scenario(path)


def test_an_mjcf_joints_armature_is_in_the_truth_and_in_the_lhs_model(tmp_path):
    """MuJoCo's armature (a motor's reflected rotor inertia, here with gear 3: Drake's
    rotor inertia armature / gear^2) is on H's joint diagonal in the ground truth;
    the reduced model, its derivatives' source and the truth's joint momentum carry it:
    M matches the plant's H_mm - H_mb H_bb^-1 H_bm to round-off, and p = M qdot its
    joint rows of H v; an arm without it differs by exactly diag(armature)."""
    from dacph_drake.kernels.spatial import joint_momentum
    text = (ARMS / "arm3.xml").read_text()
    path = tmp_path / "armature.xml"
    path.write_text(text.replace('<joint name="joint1" type="hinge"',
                                 '<joint name="joint1" armature="0.05" type="hinge"')
                    .replace('<joint name="joint3" type="hinge"',
                             '<joint name="joint3" armature="0.002" type="hinge"')
                    .replace("</worldbody>", '</worldbody><actuator><motor joint="joint1" '
                             'gear="3"/><motor joint="joint2"/><motor joint="joint3"/>'
                             '</actuator>'))
    rng = np.random.default_rng(48)
    plain = None
    for description in (ARMS / "arm3.xml", path):
        arm = DescribedArm(description=str(description), base=ArmBase(mass=100.0),
                           end_effector=EndEffectorFrame(frame="link3"))
        plant = MakeRobotPlant(arm)
        model = FloatingBaseModel(plant)
        context = plant.CreateDefaultContext()
        q = np.array([0.3, 0.8, -0.4])
        qdot = rng.normal(size=3)
        plant.SetPositions(context, model.FullPositions(q))
        H = plant.CalcMassMatrix(context)
        b, m = model.coordinates.base_v, model.coordinates.joint_v
        reduced = H[np.ix_(m, m)] - H[np.ix_(m, b)] @ np.linalg.solve(H[np.ix_(b, b)],
                                                                     H[np.ix_(b, m)])
        M = model.MassMatrix(q)
        np.testing.assert_allclose(M, reduced, rtol=0, atol=1e-12 * np.abs(reduced).max())
        v = np.zeros(plant.num_velocities())
        v[m] = qdot
        v[b] = -np.linalg.solve(H[np.ix_(b, b)], H[np.ix_(b, m)] @ qdot)  # zero momentum
        plant.SetVelocities(context, v)
        tree, (base_pose, _, base_velocity, _) = model.tree, model.coordinates.Split(
            plant.GetPositionsAndVelocities(context))
        p = joint_momentum(tree.base_subspace, tree.parent, tree.joint, tree.X_PF,
                           tree.axis, tree.X_MC, tree.below, *tree.Inertias(context),
                           base_pose, base_velocity, q, qdot)
        np.testing.assert_allclose(p, (H @ v)[m], rtol=0, atol=1e-12 * np.abs(H).max())
        np.testing.assert_allclose(p, M @ qdot, rtol=1e-10, atol=1e-14)
        if plain is None:
            plain = M
    np.testing.assert_allclose(M - plain, np.diag([0.05, 0.0, 0.002]), atol=1e-14)


@pytest.mark.parametrize("edit, message", [
    (lambda p: (p.parent / "arm_body.xml").write_text(
        (p.parent / "arm_body.xml").read_text().replace(
            '<inertial pos="0 0 0.05" mass="0.5" diaginertia="0.0005 0.0005 0.0002"/>',
            '<inertial pos="0 0 0.05" mass="0" diaginertia="0 0 0"/>').replace(
            '<geom name="link3_geom" type="cylinder" pos="0 0 0.05" size="0.02 0.05"/>',
            "")),
     r"joint 'joint3' moves no inertia"),
    (lambda p: p.write_text(p.read_text().replace('<include file="arm_body.xml"/>',
                                                  "<include/>")),
     r"robot\.xml: an <include> without a file attribute"),
    (lambda p: (p.parent / "arm_body.xml").write_text(
        (p.parent / "arm_body.xml").read_text().replace(
            '<joint name="joint2" type="hinge"', '<joint name="joint2" type="ball"')),
     r"joint 'joint2' .*ball.*; allowed: (revolute|an arm of revolute)"),
])
def test_a_broken_mjcf_arm_file_exits_2_in_one_line(tmp_path, edit, message, capsys):
    """Broken descriptions named by a scenario file: `dacph simulate` prints one line
    naming the joint or element and exits 2 (a joint that moves only a massless body:
    its <inertial> of mass 0 and no geom to take one from, as MuJoCo would; an include
    without a file; a ball joint)."""
    from dacph_drake.app.cli import main
    path = _robosuite_style(tmp_path)
    edit(path)
    scenario = tmp_path / "arm.yaml"
    scenario.write_text("robot: !DescribedArm\n  description: robot.xml\n"
                        "  base: {mass: 100.0}\n  end_effector: {frame: link3}\n")
    with pytest.raises(ConfigError, match=message):
        load_scenario(scenario)
    assert main(["--quiet", "simulate", str(scenario), "--out",
                 str(tmp_path / "out")]) == 2
    error = capsys.readouterr().err.strip().splitlines()
    assert len(error) == 1 and error[0].startswith("dacph: error:"), error


def test_joint_friction_kept_acts_in_the_truth_and_conserves_momentum(tmp_path):
    """robot.joint_friction: keep puts an MJCF joint's frictionloss (here through a
    <default> class and a body's childclass) into the ground truth's RHS as
    f tanh(qdot / FRICTION_VELOCITY): the logged D~ holds its secant (f / v at rest,
    f / |qdot| beyond v), the run conserves the spatial momentum, and the step is sized
    for its slope; the default ("zero") leaves the truth as Drake's plant has it."""
    from dacph_drake.kernels.loop import FRICTION_VELOCITY, add_friction
    from dacph_drake.robots.description import joint_friction
    from dacph_drake.loop.metrics import run_metrics
    qdot = np.array([0.0, 1e-9, 0.05, -3.0])
    D = np.zeros(4)
    add_friction(np.array([0.2, 0.2, 0.2, 0.0]), qdot, D)
    np.testing.assert_allclose(D[:2], 0.2 / FRICTION_VELOCITY, rtol=1e-12)
    np.testing.assert_allclose(D[2] * qdot[2], 0.2 * np.tanh(0.05 / FRICTION_VELOCITY),
                               rtol=1e-12)
    assert D[3] == 0.0
    text = (ARMS / "arm3.xml").read_text()
    path = tmp_path / "friction.xml"
    path.write_text(text.replace('<compiler angle="radian"/>',
                                 '<compiler angle="radian"/><default><default class="arm">'
                                 '<joint frictionloss="0.05"/></default></default>')
                    .replace('<body name="link2" pos="0 0 0.4">',
                             '<body name="link2" pos="0 0 0.4" childclass="arm">'))
    assert joint_friction(path) == {"joint2": 0.05, "joint3": 0.05}
    runs = {}
    for setting in ("zero", "keep"):
        scenario_file = tmp_path / f"{setting}.yaml"
        scenario_file.write_text(
            f"robot: !DescribedArm\n  description: friction.xml\n  base: {{mass: 100.0}}\n"
            f"  end_effector: {{frame: link3}}\n  joint_friction: {setting}\n"
            "q0: [0.3, 0.8, -0.4]\n"
            "phases: {warmup: 0.3, linear: 0.3, nonlinear: 0.3, disturbance: 0.3}\n")
        scenario = load_scenario(scenario_file)
        runs[setting] = (scenario, simulate(scenario, "dac"))
    (zero, plain), (keep, rubbed) = runs["zero"], runs["keep"]
    assert plain.status == rubbed.status == "ok"
    assert keep.simulator.max_step_size <= zero.simulator.max_step_size
    from dacph_drake.robots.sizing import truth_step
    model = robot_of(keep).model
    q = np.array([keep.q0])
    assert truth_step(model, q, keep.uncertainty, keep.periods.rhs, np.full(3, 5.0)) < \
        truth_step(model, q, keep.uncertainty, keep.periods.rhs)
    D_keep, D_zero = (run.logs["true_matrices"][:, 9:] for run in (rubbed, plain))
    # joints 2 and 3: D~ grows by the secant, at least f tanh(3 / v) / 3 below 3 rad/s;
    # joint 1 (no friction) differs only by the trajectory its state-dependent D~ sees
    assert np.all(D_keep[:, 1:] - D_zero[:, 1:] > 0.05 * np.tanh(3 / FRICTION_VELOCITY)
                  / 3 - 1e-3 * D_zero[:, 1:])
    assert np.all(np.abs(D_keep[:, 0] - D_zero[:, 0]) < 1e-3 * D_zero[:, 0])
    assert run_metrics(rubbed.logs, keep)["max_momentum"] < 1e-8


def test_an_arm_as_mjcf_with_defaults_includes_and_geom_inertia_is_its_urdf(tmp_path):
    """serial_arm_mjcf writes the serial arm as MuJoCo models are written (its bodies in
    an included file, the joints' limits and frictionloss from a <default> class passed
    down by childclass, two links' inertia from their geoms' mass); read as MuJoCo reads
    it, its reduced mass matrix is the URDF's (to the files' 6 digits), its joint limits
    and damping too, and with armature it gains exactly diag(armature)."""
    from dacph_drake.robots.serial_arm import serial_arm_mjcf
    from dacph_drake.robots.start_pose import joint_limits
    links = [SerialLink(4.0, 0.4, 0.5), SerialLink(3.0, 0.35), SerialLink(2.0, 0.3),
             SerialLink(1.0, 0.2, 0.1)]
    (tmp_path / "arm.urdf").write_text(serial_arm_urdf("arm", links, 0.5))
    armature = [0.02, 0.0, 0.01, 0.003]
    for stem, extra in (("plain", {}), ("geared", {"armature": armature})):
        for file, text in serial_arm_mjcf(stem, links, 0.5, frictionloss=0.05,
                                          from_geoms=[False, True, False, True],
                                          **extra).items():
            (tmp_path / file).write_text(text)
    q = np.array([0.3, 0.7, -0.2, 0.5])
    models = {}
    for file in ("arm.urdf", "plain.xml", "geared.xml"):
        models[file] = FloatingBaseModel(MakeRobotPlant(DescribedArm(
            description=str(tmp_path / file), base=ArmBase(mass=100.0),
            end_effector=EndEffectorFrame(frame="tool"))))
    M = {file: model.MassMatrix(q) for file, model in models.items()}
    np.testing.assert_allclose(M["plain.xml"], M["arm.urdf"], rtol=0,
                               atol=1e-6 * np.abs(M["arm.urdf"]).max())
    np.testing.assert_allclose(M["geared.xml"] - M["plain.xml"], np.diag(armature),
                               atol=1e-14)
    for file in ("plain.xml", "geared.xml"):
        np.testing.assert_array_equal(models[file].joint_damping, [0.5, 0.0, 0.0, 0.1])
        np.testing.assert_allclose(joint_limits(models[file]), [[-2.9] * 4, [2.9] * 4])


def test_urdf_and_sdf_joint_friction_is_read_by_joint(tmp_path):
    """joint_friction reads a URDF's <dynamics friction> and an SDF's
    <axis><dynamics><friction> by joint name (zero left out), and a negative one is
    refused naming the joint."""
    from dacph_drake.robots.description import joint_friction
    urdf = serial_arm_urdf("rubbed", SIX[:3]).replace(
        '<dynamics damping="0"/></joint><link name="link2"',
        '<dynamics damping="0" friction="0.7"/></joint><link name="link2"', 1)
    (tmp_path / "rubbed.urdf").write_text(urdf)
    assert joint_friction(tmp_path / "rubbed.urdf") == {"joint1": 0.7}
    sdf = (ARMS / "arm3.sdf").read_text().replace(
        "<axis><xyz>0 1 0</xyz>", "<axis><xyz>0 1 0</xyz><dynamics><friction>0.3"
                                  "</friction></dynamics>")
    (tmp_path / "rubbed.sdf").write_text(sdf)
    assert joint_friction(tmp_path / "rubbed.sdf") == {"joint2": 0.3}
    (tmp_path / "bad.urdf").write_text(urdf.replace('friction="0.7"', 'friction="-1"'))
    with pytest.raises(ConfigError, match=r"joint 'joint1': friction '-1'; allowed: a "
                                          r"number >= 0"):
        joint_friction(tmp_path / "bad.urdf")


def test_an_mjcf_motors_gear_scales_its_torque_limit(tmp_path):
    """A <motor gear="3" ctrlrange="-2 2">: MuJoCo's torque is gear x ctrl, so the loop's
    u (the joint torque, as Drake applies it) is limited to +-6 N m, and its armature is
    reflected through the gear (rotor inertia armature / 9)."""
    text = (ARMS / "arm3.xml").read_text()
    path = tmp_path / "geared.xml"
    path.write_text(text.replace('<joint name="joint1" type="hinge"',
                                 '<joint name="joint1" armature="0.05" type="hinge"')
                    .replace("</worldbody>", '</worldbody><actuator><motor joint="joint1" '
                             'gear="3" ctrlrange="-2 2" ctrllimited="true"/></actuator>'))
    plant = MakeRobotPlant(DescribedArm(description=str(path), base=ArmBase(mass=100.0),
                                        end_effector=EndEffectorFrame(frame="link3")))
    actuator = next(plant.get_joint_actuator(i) for i in plant.GetJointActuatorIndices()
                    if plant.get_joint_actuator(i).joint().name() == "joint1")
    assert actuator.effort_limit() == pytest.approx(6.0)
    assert actuator.default_rotor_inertia() * 9 == pytest.approx(0.05)


def test_an_mjcfs_servos_act_as_torque_motors(tmp_path, caplog):
    """A <position> servo (gear 2, forcerange +-30 from its class), a <general> servo (affine bias, no
    force limit) and a <general> torque motor (gain 4, ctrlrange +-2) on the three joints:
    the controller commands each joint's torque, so each is a motor without a servo law,
    its effort limit |gear| x forcerange (60 N m), none, and gain x ctrlrange (8 N m);
    the servos are named in one warning, and DAC runs with them."""
    path = tmp_path / "servos.xml"
    path.write_text((ARMS / "arm3.xml").read_text().replace("</worldbody>", (
        '</worldbody><default><default class="servo"><position forcerange="-30 30"/>'
        '</default></default><actuator><position name="servo1" class="servo" '
        'joint="joint1" kp="100" kv="10" ctrlrange="-1 1" gear="2"/><general joint="joint2" '
        'gainprm="50" biasprm="0 -50 -5" biastype="affine" ctrlrange="-2 2"/>'
        '<general joint="joint3" gainprm="4" ctrlrange="-2 2"/></actuator>')))
    arm = DescribedArm(description=str(path), base=ArmBase(mass=100.0),
                       end_effector=EndEffectorFrame(frame="link3"))
    with caplog.at_level(logging.WARNING):
        plant = MakeRobotPlant(arm)
    actuators = {plant.get_joint_actuator(i).joint().name(): plant.get_joint_actuator(i)
                 for i in plant.GetJointActuatorIndices()}
    assert [actuators[f"joint{k}"].effort_limit() for k in (1, 2, 3)] == \
        pytest.approx([60.0, np.inf, 8.0])
    assert not any(actuator.has_controller() for actuator in actuators.values())
    servos = [r.getMessage() for r in caplog.records if "torque motors" in r.getMessage()]
    assert len(servos) == 1 and "position 'servo1' on joint 'joint1'" in servos[0] \
        and "general '(unnamed)' on joint 'joint2'" in servos[0] \
        and "joint3" not in servos[0]
    scenario = arm_scenario(arm)
    scenario.phases.warmup, scenario.phases.linear = 0.2, 0.3
    scenario.phases.nonlinear = scenario.phases.disturbance = 0.0
    assert simulate(scenario, "dac").status == "ok"


@pytest.mark.parametrize("mode", ["legacy", "exact"])
def test_a_mesh_whose_mujoco_inertia_is_not_its_exact_one_is_named(tmp_path, caplog, mode):
    """Link 1's inertia from a mesh of two boxes apart (not star-shaped from its faces'
    centroid): MuJoCo's default "legacy" mesh inertia counts each face's pyramid positive
    (volume about 1.5x the exact here), Drake takes the exact one; the run names the mesh in a
    warning, and MuJoCo's model differs. With <mesh inertia="exact"> both agree (1e-12)
    and nothing is said."""
    pytest.importorskip("mujoco")
    import trimesh
    from dacph_drake.robots.mujoco_reference import compare_with_mujoco
    boxes = trimesh.util.concatenate([
        trimesh.creation.box([0.05, 0.05, 0.3]).apply_translation([x, 0.0, 0.2])
        for x in (-0.06, 0.06)])
    boxes.export(tmp_path / "twin.stl")
    inertia = "" if mode == "legacy" else ' inertia="exact"'
    text = (ARMS / "arm3.xml").read_text().replace(
        '<inertial pos="0 0 0.2" mass="3" diaginertia="0.04 0.04 0.002"/>', "").replace(
        '<geom name="link1_geom" type="cylinder" pos="0 0 0.2" size="0.04 0.2"/>',
        '<geom name="link1_geom" type="mesh" mesh="twin" mass="3"/>').replace(
        "<worldbody>", f'<asset><mesh name="twin" file="twin.stl"{inertia}/></asset>'
                       "<worldbody>")
    path = tmp_path / "twin.xml"
    path.write_text(text)
    with caplog.at_level(logging.WARNING):
        difference = compare_with_mujoco(path, "link3", samples=3)
    named = [r.getMessage() for r in caplog.records if "mesh 'twin'" in r.getMessage()]
    if mode == "legacy":
        assert len(named) == 1 and "legacy: volume" in named[0]
        assert difference.mass_matrix > 1e-4
    else:
        assert not named
        assert difference.mass_matrix < 1e-12


def test_an_mjcfs_compiler_angle_and_eulerseq_are_read_as_mujoco_reads_them(tmp_path):
    """<compiler angle="degree" eulerseq="ZYX"/> (fixed axes: R = R_x(c) R_y(b) R_z(a) for
    euler="a b c") with its ranges in degrees gives the arm of the same file in radians
    with that rotation as a quaternion: the same reduced mass matrix and joint limits; the
    lowercase (moving-axes) sequence gives another arm."""
    from pydrake.math import RotationMatrix
    from dacph_drake.robots.start_pose import joint_limits
    a, b, c = np.radians([30.0, 20.0, 10.0])
    R = (RotationMatrix.MakeXRotation(c) @ RotationMatrix.MakeYRotation(b)
         @ RotationMatrix.MakeZRotation(a))
    w, x, y, z = R.ToQuaternion().wxyz()
    text = (ARMS / "arm3.xml").read_text()
    link2 = '<body name="link2" pos="0 0 0.4"'
    degrees = f"{np.degrees(2.9):.12g}"
    files = {
        "radian": text.replace(link2, f'{link2} quat="{w:.17g} {x:.17g} {y:.17g} {z:.17g}"'),
        "degree": text.replace('<compiler angle="radian"/>',
                               '<compiler angle="degree" eulerseq="ZYX"/>')
                      .replace(link2, f'{link2} euler="30 20 10"')
                      .replace('range="-2.9 2.9"', f'range="-{degrees} {degrees}"'),
    }
    files["moving"] = files["degree"].replace('eulerseq="ZYX"', 'eulerseq="zyx"')
    models = {}
    for name, content in files.items():
        (tmp_path / f"{name}.xml").write_text(content)
        models[name] = FloatingBaseModel(MakeRobotPlant(DescribedArm(
            description=str(tmp_path / f"{name}.xml"), base=ArmBase(mass=100.0),
            end_effector=EndEffectorFrame(frame="link3"))))
    q = np.array([0.3, 0.7, -0.2])
    M = {name: model.MassMatrix(q) for name, model in models.items()}
    np.testing.assert_allclose(M["degree"], M["radian"], rtol=0, atol=1e-12)
    np.testing.assert_allclose(joint_limits(models["degree"]), [[-2.9] * 3, [2.9] * 3],
                               rtol=1e-12)
    assert np.abs(M["moving"] - M["radian"]).max() > 1e-4


def _mujoco_reference_files(tmp_path: Path) -> Dict[str, Path]:
    """MJCF arms of every kind the MJCF path rewrites or reads itself: plain; robosuite's
    layout (include with root <mujocoinclude>, meshdir, an STL mesh, a massless mount);
    <default> classes passed by
    childclass with frictionloss, armature, two links' inertia from their geoms and a
    shell geom on a body with an <inertial>; the compiler's degrees and fixed-axes euler
    sequence with inertiafromgeom="true" and a geom density."""
    from dacph_drake.robots.serial_arm import serial_arm_mjcf
    files = {"plain": ARMS / "arm3.xml"}
    robosuite = tmp_path / "robosuite"
    robosuite.mkdir()
    files["robosuite"] = _robosuite_style(robosuite)
    # MuJoCo 3 no longer reads the legacy .msh: the shoulder as an STL there; the
    # included file with the older root <mujocoinclude>, which MuJoCo still reads.
    text = files["robosuite"].read_text().replace('file="link2.msh"', 'file="link1.stl"')
    files["robosuite"].write_text(text)
    body = robosuite / "arm_body.xml"
    body.write_text(body.read_text().replace("<mujoco>", "<mujocoinclude>").replace(
        "</mujoco>", "</mujocoinclude>"))
    links = [SerialLink(4.0, 0.4, 0.5), SerialLink(3.0, 0.35), SerialLink(2.0, 0.3),
             SerialLink(1.0, 0.2, 0.1)]
    for file, content in serial_arm_mjcf("classes", links, 0.5, frictionloss=0.05,
                                         from_geoms=[False, True, False, True],
                                         armature=[0.02, 0.0, 0.01, 0.003]).items():
        # A shell geom on a body with an <inertial>: MuJoCo does not use its inertia.
        (tmp_path / file).write_text(content.replace(
            'name="link1_geom"', 'name="link1_geom" shellinertia="true"'))
    files["classes"] = tmp_path / "classes.xml"
    degrees = f"{np.degrees(2.9):.12g}"
    compiled = (ARMS / "arm3.xml").read_text().replace(
        '<compiler angle="radian"/>',
        '<compiler angle="degree" eulerseq="ZYX" inertiafromgeom="true"/>').replace(
        '<body name="link2" pos="0 0 0.4"', '<body name="link2" pos="0 0 0.4" '
        'euler="30 20 10"').replace('range="-2.9 2.9"', f'range="-{degrees} {degrees}"'
                                    ).replace('name="link2_geom"',
                                              'name="link2_geom" density="500"')
    files["compiler"] = tmp_path / "compiler.xml"
    files["compiler"].write_text(compiled)
    return files


@pytest.mark.parametrize("kind", ["plain", "robosuite", "classes", "compiler"])
def test_an_mjcf_arm_is_mujocos_own_model(tmp_path, kind):
    """MuJoCo itself is the reference (robots.mujoco_reference): for each kind of file,
    the ground truth's joint-space mass matrix (armature included) equals MuJoCo's M at
    random joint angles, and the joints' damping, frictionloss (as robot.joint_friction:
    keep reads it) and limits are MuJoCo's, joint by joint."""
    pytest.importorskip("mujoco")
    from dacph_drake.robots.mujoco_reference import compare_with_mujoco
    path = _mujoco_reference_files(tmp_path)[kind]
    n = {"classes": 4}.get(kind, 3)
    difference = compare_with_mujoco(path, "link3", samples=3, seed=7)
    assert difference.joints == difference.dofs == n
    assert difference.mass_matrix < 1e-12
    assert difference.damping == difference.frictionloss == 0.0
    assert difference.limits < 1e-12
