"""An arm's own description mounted on a base from the scenario (robot.base), its
end-effector frame named by the scenario (robot.end_effector), package:// URIs
resolved through robot.package_paths or ROS_PACKAGE_PATH, and joints that are not
the arm's refused by name (issue 24)."""
import re

import numpy as np
import pytest

from dacph_drake.dynamics.floating_model import FloatingBaseModel
from dacph_drake.scenario.errors import ConfigError
from dacph_drake.robots.description import (MODELS, AddRobotFromDescription,
                                            MakeRobotPlant, ParsedDescription)
from dacph_drake.scenario import ArmBase, DescribedArm, EndEffectorFrame

MOUNT = ArmBase(mass=250.0, size=[1.0, 1.0, 1.0], mount=[0.0, 0.0, 0.5, 0.0, 0.0, 0.0])


def _arm_alone(text: str) -> str:
    """satellite_3dof's description without its base: a massless root link
    "arm_root" carries joint 1 at its origin (the arm as a vendor ships it)."""
    text = re.sub(r'<link name="base">.*?</link>', '<link name="arm_root"/>', text,
                  flags=re.S)
    text = text.replace('<parent link="base"/>', '<parent link="arm_root"/>')
    return text.replace('<origin xyz="0 0 0.5" rpy="0 0 0"/>',
                        '<origin xyz="0 0 0" rpy="0 0 0"/>', 1)


@pytest.fixture
def arm_file(tmp_path):
    path = tmp_path / "arm.urdf"
    path.write_text(_arm_alone((MODELS / "satellite_3dof.urdf").read_text()))
    return path


def _joint2_as(arm_file, name: str, opening: str):
    """A copy of the arm's file named ``name`` whose joint 2 opens with ``opening``
    (another type, or extra elements) instead of its continuous joint tag."""
    path = arm_file.with_name(name)
    path.write_text(arm_file.read_text().replace(
        '<joint name="joint2" type="continuous">', opening))
    return path


def test_a_mounted_arm_is_the_combined_description(arm_file, rng):
    """The arm alone on a 250 kg, 1 m box at the shoulder's place has the combined
    file's reduced mass matrix at any configuration (the file's base inertia is
    rounded to 6 digits: within 1e-6) and the same end-effector pose."""
    combined = FloatingBaseModel(MakeRobotPlant("satellite_3dof"))
    mounted = FloatingBaseModel(MakeRobotPlant(DescribedArm(description=str(arm_file),
                                                            base=MOUNT)))
    assert mounted.num_joints == combined.num_joints == 3
    for _ in range(5):
        q = rng.uniform(-np.pi, np.pi, 3)
        np.testing.assert_allclose(mounted.MassMatrix(q), combined.MassMatrix(q),
                                   rtol=1e-6, atol=1e-9)
    plants = [m.plant for m in (combined, mounted)]
    poses = []
    for plant, model in zip(plants, (combined, mounted)):
        context = plant.CreateDefaultContext()
        plant.SetPositions(context, model.FullPositions(np.array([0.3, -0.8, 1.6])))
        poses.append(plant.GetFrameByName("end_effector").CalcPoseInWorld(context))
    np.testing.assert_allclose(poses[0].GetAsMatrix4(), poses[1].GetAsMatrix4(),
                               atol=1e-12)


def test_the_end_effector_frame_is_a_setting(arm_file):
    """robot.end_effector names any frame of the description with an offset; the
    arm without an end_effector frame and without the setting, a frame it lacks,
    or a second end_effector are refused with one line naming the setting."""
    text = arm_file.read_text()
    bare = arm_file.with_name("bare.urdf")
    bare.write_text(re.sub(r'<link name="end_effector"/>\s*<joint name="end_effector_weld"'
                           r'.*?</joint>', "", text, flags=re.S))
    arm = DescribedArm(description=str(bare), base=MOUNT,
                       end_effector=EndEffectorFrame("link3", [0.6, 0.0, 0.0]))
    reference = MakeRobotPlant(DescribedArm(description=str(arm_file), base=MOUNT))
    plant = MakeRobotPlant(arm)
    for p in (plant, reference):
        context = p.CreateDefaultContext()
        p.SetPositions(context, FloatingBaseModel(p).FullPositions(np.array([0.3, 0.2, 0.1])))
        p.pose = p.GetFrameByName("end_effector").CalcPoseInWorld(context).GetAsMatrix4()
    np.testing.assert_allclose(plant.pose, reference.pose, atol=1e-12)
    for settings, message in (
            (DescribedArm(description=str(bare), base=MOUNT),
             r"has no frame named 'end_effector'; allowed: .*robot.end_effector.frame"),
            (DescribedArm(description=str(bare), base=MOUNT,
                          end_effector=EndEffectorFrame("link9")),
             r"robot.end_effector.frame = 'link9' is not a frame of"),
            (DescribedArm(description=str(arm_file), base=MOUNT,
                          end_effector=EndEffectorFrame("link3")),
             r"which has its own frame 'end_effector'")):
        with pytest.raises(ConfigError, match=message):
            MakeRobotPlant(settings)


def test_an_arm_alone_without_a_base_setting_is_named(arm_file):
    """Without robot.base the arm's massless root link would be the free base (a
    singular mass matrix): refused with the setting that mounts it, not a numpy
    error later."""
    with pytest.raises(ConfigError, match=r"the free base 'arm_root' has no mass; "
                                          r"allowed: .* robot.base"):
        MakeRobotPlant(DescribedArm(description=str(arm_file)))


def test_package_uris_resolve_through_package_paths_or_ros_package_path(
        arm_file, tmp_path, monkeypatch):
    """A description in a ROS package whose visual mesh is a package:// URI loads
    with robot.package_paths naming the folder, or with ROS_PACKAGE_PATH; without
    either the unknown package is named in one line."""
    from pydrake.systems.framework import DiagramBuilder
    package = tmp_path / "packages" / "my_arm"
    (package / "meshes").mkdir(parents=True)
    (package / "urdf").mkdir()
    (package / "package.xml").write_text(
        '<?xml version="1.0"?><package format="2"><name>my_arm</name>'
        '<version>0.0.1</version><description>d</description>'
        '<maintainer email="a@b.c">m</maintainer><license>BSD</license></package>')
    (package / "meshes" / "link.obj").write_text(
        "v 0 0 0\nv 0.1 0 0\nv 0 0.1 0\nv 0 0 0.1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n")
    text = arm_file.read_text().replace(
        '<geometry><cylinder radius="0.06" length="0.2"/></geometry>',
        '<geometry><mesh filename="package://my_arm/meshes/link.obj"/></geometry>', 1)
    urdf = package / "urdf" / "arm.urdf"
    urdf.write_text(text)
    monkeypatch.delenv("ROS_PACKAGE_PATH", raising=False)
    with pytest.raises(ConfigError, match=r"my_arm"):
        AddRobotFromDescription(DiagramBuilder(), DescribedArm(description=str(urdf),
                                                               base=MOUNT))
    plant, _ = AddRobotFromDescription(DiagramBuilder(), DescribedArm(
        description=str(urdf), base=MOUNT, package_paths=[str(tmp_path / "packages")]))
    assert plant.num_velocities() == 6 + 3
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(tmp_path / "packages"))
    plant, _ = AddRobotFromDescription(DiagramBuilder(), DescribedArm(description=str(urdf),
                                                                      base=MOUNT))
    assert plant.num_velocities() == 6 + 3


def test_joints_that_are_not_the_arms_are_locked(arm_file, rng, caplog):
    """A gripper's slide (a prismatic joint) is welded at 0 with a note; a revolute
    joint named in robot.locked_joints is welded at its position: the arm's
    reduced mass matrix is then the full arm's at that position without the
    locked joint's row and column, and its end-effector pose the same; a planar
    joint, or a locked name that is no joint, is refused naming it."""
    full = FloatingBaseModel(MakeRobotPlant(DescribedArm(description=str(arm_file),
                                                         base=MOUNT)))
    prismatic = _joint2_as(arm_file, "prismatic.urdf",
                           '<joint name="joint2" type="prismatic"><limit lower="-0.1" '
                           'upper="0.1" effort="10" velocity="1"/>')
    with caplog.at_level("WARNING"):
        slid = FloatingBaseModel(MakeRobotPlant(DescribedArm(description=str(prismatic),
                                                             base=MOUNT)))
    assert slid.num_joints == 2 and "locked (welded) joints: joint2 at 0" in caplog.text
    locked = FloatingBaseModel(MakeRobotPlant(DescribedArm(
        description=str(arm_file), base=MOUNT, locked_joints={"joint2": 0.4})))
    assert locked.num_joints == 2
    for _ in range(3):
        q1, q3 = rng.uniform(-np.pi, np.pi, 2)
        M = full.MassMatrix(np.array([q1, 0.4, q3]))
        np.testing.assert_allclose(locked.MassMatrix(np.array([q1, q3])),
                                   M[np.ix_([0, 2], [0, 2])], rtol=1e-12, atol=1e-12)
        poses = []
        for model, q in ((full, [q1, 0.4, q3]), (locked, [q1, q3])):
            context = model.plant.CreateDefaultContext()
            model.plant.SetPositions(context, model.FullPositions(np.array(q)))
            poses.append(model.plant.GetFrameByName("end_effector").CalcPoseInWorld(
                context).GetAsMatrix4())
        np.testing.assert_allclose(poses[0], poses[1], atol=1e-12)
    planar = _joint2_as(arm_file, "planar.urdf", '<joint name="joint2" type="planar">')
    with pytest.raises(ConfigError, match=r"joint 'joint2' is a .* joint; allowed: "
                                          r"revolute joints"):
        MakeRobotPlant(DescribedArm(description=str(planar), base=MOUNT))
    with pytest.raises(ConfigError, match=r"robot.locked_joints names 'gripper', which is "
                                          r"not a revolute or prismatic joint"):
        MakeRobotPlant(DescribedArm(description=str(arm_file), base=MOUNT,
                                    locked_joints={"gripper": 0.0}))


@pytest.mark.parametrize("change, message", [
    (dict(base=ArmBase(mass=-1.0)), r"robot.base.mass = -1.0"),
    (dict(base=ArmBase(mass=10.0, size=[1.0, 0.0, 1.0])), r"robot.base.size\[1\] = 0.0"),
    (dict(base=ArmBase(mass=10.0, mount=[0.0, 0.0, 0.5])),
     r"robot.base.mount has 3 entries; allowed: 6"),
    (dict(package_paths=["/no/such/folder"]), r"robot.package_paths\[0\] = "),
    (dict(joint_damping="ignore"), r"robot.joint_damping = 'ignore'; allowed: keep, zero"),
    (dict(joint_friction="smooth"), r"robot.joint_friction = 'smooth'; allowed: keep, "
                                   r"zero"),
    (dict(joint_limits="clip"), r"robot.joint_limits = 'clip'; allowed: stop, ignore"),
    (dict(effort_limits="scale"), r"robot.effort_limits = 'scale'; allowed: saturate, "
                                  r"ignore"),
    (dict(packages={"my_arm": "/no/such/folder"}), r"robot.packages.my_arm = "),
    (dict(locked_joints={"joint2": float("nan")}),
     r"robot.locked_joints.joint2 = nan is not finite"),
    (dict(end_effector=EndEffectorFrame("link3", [0.1, 0.0])),
     r"robot.end_effector.offset has 2 entries; allowed: 3"),
])
def test_bad_assembly_settings_are_named(change, message):
    from dacph_drake.assembly.registry import robot_of
    from dacph_drake.scenario.built_in import satellite_3dof_scenario
    scenario = satellite_3dof_scenario()
    for name, value in change.items():
        setattr(scenario.robot, name, value)
    with pytest.raises(ConfigError, match=message):
        robot_of(scenario)


def test_a_scenario_file_runs_dac_on_the_mounted_arm(arm_file, tmp_path, capsys):
    """satellite_3dof's scenario with the arm alone mounted on the same box, written
    to a file and run through `dacph simulate`: DAC tracks as on the combined file
    (the attitude error within 1e-4 of it, relative, over 0.5 s; the base inertia
    differs in the 7th digit), with the clearance potential measuring the links
    against the mounted box."""
    from dacph_drake.app.cli import main
    from dacph_drake.loop.run_store import load_run
    from dacph_drake.loop.simulate import simulate
    from dacph_drake.scenario.built_in import satellite_3dof_scenario
    from dacph_drake.assembly.scenario_files import load_scenario, save_scenario
    scenario = satellite_3dof_scenario()
    scenario.robot.description, scenario.robot.base = str(arm_file), MOUNT
    save_scenario(scenario, tmp_path / "mounted.yaml")
    assert load_scenario(tmp_path / "mounted.yaml") == scenario
    assert main(["simulate", str(tmp_path / "mounted.yaml"), "--out",
                 str(tmp_path / "run"), "--duration", "0.5"]) == 0
    mounted = load_run(tmp_path / "run", "dac")[0]["attitude_log"]
    combined = simulate(satellite_3dof_scenario(), "dac", duration=0.5).logs["attitude_log"]
    np.testing.assert_allclose(mounted[:, 3], combined[:, 3], rtol=1e-4)
    clearance = mounted[:, 6]
    assert np.all(np.isfinite(clearance)) and clearance.min() > 0.1


def test_the_descriptions_joint_damping_is_part_of_the_lhs_model_or_zeroed(arm_file,
                                                                          caplog):
    """A description's joint damping b acts in the ground truth (the plant applies
    it) and, with robot.joint_damping "keep" (default), is part of the LHS model as
    the inertias are: the model's joint_damping is b, the attitude controller
    requests b nu and the port observer adds b qdot, so the logged port D~
    (true_matrices) is the RHS's alone, the same with or without b; "zero" removes
    b from the plant and the model with a note. In a DAC run with b the observed
    port torque is the true RHS's B~ u - D~ qdot + d (what acts beyond b)."""
    from dacph_drake.controllers import build_closed_loop
    from dacph_drake.dynamics.plant import trial_coordinates
    from dacph_drake.loop.simulate import simulate
    from dacph_drake.scenario.built_in import satellite_3dof_scenario
    damped = _joint2_as(arm_file, "damped.urdf", '<joint name="joint2" '
                        'type="continuous"><dynamics damping="0.03"/>')
    logged = {}
    for setting in ("keep", "zero"):
        scenario = satellite_3dof_scenario()
        scenario.robot.description, scenario.robot.base = str(damped), MOUNT
        scenario.robot.joint_damping = setting
        with caplog.at_level("WARNING"):
            loop = build_closed_loop("model-based", scenario)
        b = 0.03 if setting == "keep" else 0.0
        assert loop.plant.GetJointByName("joint2").default_damping() == b
        np.testing.assert_array_equal(loop.model.joint_damping, [0.0, b, 0.0])
        truth = loop.systems["true_rhs"]
        context = truth.CreateDefaultContext()
        plant_context = loop.plant.CreateDefaultContext()
        loop.plant.SetPositions(plant_context, loop.model.FullPositions(
            np.array([0.3, -0.8, 1.6])))
        truth.GetInputPort("state").FixValue(
            context, loop.plant.GetPositionsAndVelocities(plant_context))
        truth.GetInputPort("u").FixValue(context, np.zeros(3))
        truth.GetInputPort("disturbance_model").FixValue(context, np.zeros(3 + 5 * 3))
        logged[setting] = truth.GetOutputPort("true_matrices").Eval(context)[9:]
    np.testing.assert_array_equal(logged["keep"], logged["zero"])
    assert "joint damping of joint2 is set to zero" in caplog.text
    scenario = satellite_3dof_scenario()
    scenario.robot.description, scenario.robot.base = str(damped), MOUNT
    scenario.robot.joint_damping = "keep"
    logs = simulate(scenario, "dac", duration=1.0).logs
    coordinates = trial_coordinates(build_closed_loop("dac", scenario).plant)[0]
    qdot = logs["state"][:, len(coordinates.base_q) + len(coordinates.joint_q)
                         + len(coordinates.base_v):][:, :3]
    late = logs["time"] > 0.4              # past the start's fast transient
    miss = logs["tau_observed"][late] - logs["tau"][late]
    damping_torque = 0.03 * qdot[late, 1]
    assert np.sqrt(np.mean(miss[:, 1] ** 2)) < 0.1 * np.sqrt(np.mean(
        damping_torque ** 2))


def _stl(triangles: np.ndarray, binary: bool) -> bytes:
    """An STL file of ``triangles`` (k, 3, 3)."""
    if binary:
        records = np.zeros(len(triangles), np.dtype([("normal", "<f4", 3),
                                                     ("vertices", "<f4", (3, 3)),
                                                     ("attribute", "<u2")]))
        records["vertices"] = triangles
        return b"\0" * 80 + np.uint32(len(triangles)).tobytes() + records.tobytes()
    facets = "".join("facet normal 0 0 0\n outer loop\n" + "".join(
        f"  vertex {x!r} {y!r} {z!r}\n" for x, y, z in triangle) + " endloop\nendfacet\n"
        for triangle in triangles.tolist())
    return f"solid box\n{facets}endsolid box\n".encode()


def _dae(half_cm: np.ndarray) -> bytes:
    """A Collada box in centimetres (<unit meter="0.01">), its six faces a polylist
    of quads, its geometry's half sizes ``half_cm`` (x, y, z) turned by +90 deg
    about x and moved by 0 through its node's rotate and translate: the box of half
    sizes (x, z, y) cm in the file's frame."""
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
                       ) * half_cm
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4),
             (1, 5, 7, 3)]
    return f"""<?xml version="1.0"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
 <asset><unit name="centimeter" meter="0.01"/><up_axis>Z_UP</up_axis></asset>
 <library_geometries><geometry id="box-mesh"><mesh>
  <source id="box-positions"><float_array id="a" count="24">{" ".join(
        map(repr, corners.ravel().tolist()))}</float_array></source>
  <vertices id="box-vertices"><input semantic="POSITION" source="#box-positions"/>
  </vertices>
  <polylist count="6"><input semantic="VERTEX" source="#box-vertices" offset="0"/>
   <vcount>4 4 4 4 4 4</vcount><p>{" ".join(str(i) for quad in quads for i in quad)}</p>
  </polylist></mesh></geometry></library_geometries>
 <library_visual_scenes><visual_scene id="scene"><node id="box">
  <translate>0 0 0</translate><rotate>1 0 0 90</rotate>
  <instance_geometry url="#box-mesh"/></node></visual_scene></library_visual_scenes>
 <scene><instance_visual_scene url="#scene"/></scene>
</COLLADA>
""".encode()


@pytest.mark.parametrize("kind", ["binary stl", "ascii stl", "dae"])
def test_stl_collision_meshes_are_read_as_their_convex_hull(arm_file, tmp_path, kind):
    """A collision mesh given as STL (binary or ASCII, as ROS packages ship them)
    or as Collada (.dae, in centimetres, placed by its node's transforms), through a
    package:// URI whose package name differs from its package.xml's
    (robot.packages), is converted to OBJ: the clearance potential measures the same
    distance as with the same box given as a primitive."""
    from dacph_drake.robots.clearance_potential import BaseClearancePotential
    from dacph_drake.robots.meshes import dae_triangles, stl_triangles
    half = np.array([0.06, 0.06, 0.1])
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * half
    faces = [(0, 1, 3), (0, 3, 2), (4, 6, 7), (4, 7, 5), (0, 4, 5), (0, 5, 1),
             (2, 3, 7), (2, 7, 6), (0, 2, 6), (0, 6, 4), (1, 5, 7), (1, 7, 3)]
    triangles = corners[np.array(faces)]
    binary = kind == "binary stl"
    if kind == "dae":
        data, suffix = _dae(100 * half[[0, 2, 1]]), "dae"
        read = dae_triangles(data, "box").reshape(-1, 3)
        assert len(read) == 6 * 2 * 3               # each quad fanned into 2 triangles
        np.testing.assert_allclose(read.min(axis=0), -half, atol=1e-12)
        np.testing.assert_allclose(read.max(axis=0), half, atol=1e-12)
    else:
        data, suffix = _stl(triangles, binary), "stl"
        np.testing.assert_allclose(stl_triangles(data, "box"), triangles,
                                   atol=1e-8)     # binary STL holds single precision
    folder = tmp_path / "share" / "vendor_arm"
    (folder / "meshes").mkdir(parents=True)
    (folder / "meshes" / f"link1.{suffix}").write_bytes(data)
    cylinder = '<geometry><cylinder radius="0.06" length="0.2"/></geometry>'
    text = arm_file.read_text()
    boxed = text.replace(cylinder, '<geometry><box size="0.12 0.12 0.2"/></geometry>')
    meshed = text.replace(cylinder, '<geometry><mesh filename="package://vendor-arm/'
                                    f'meshes/link1.{suffix}"/></geometry>')
    distances = []
    for name, urdf_text, packages in (("boxed", boxed, {}),
                                      ("meshed", meshed, {"vendor-arm": str(folder)})):
        path = tmp_path / f"{name}.urdf"
        path.write_text(urdf_text)
        arm = DescribedArm(description=str(path), base=MOUNT, packages=packages)
        if name == "meshed" and kind == "dae":     # the visual .dae is kept as it is
            from dacph_drake.robots.description import package_map_of
            from dacph_drake.robots.meshes import urdf_with_obj_meshes
            from pydrake.multibody.parsing import PackageMap
            read = urdf_with_obj_meshes(path, package_map_of(arm, PackageMap()))
            assert read.count("link1.dae") == 1 and read.count(".obj") == 1
        model = FloatingBaseModel(MakeRobotPlant(arm))
        potential = BaseClearancePotential(parsed=ParsedDescription(arm), model=model,
                                           gain=1.0, margin=0.1)
        q = np.array([0.3, 2.2, 0.5])             # the upper arm tilted towards the base
        distances.append(potential.Evaluate(q, None).min_distance)
    assert np.isfinite(distances[0]) and distances[1] == pytest.approx(distances[0],
                                                                       abs=1e-6)


def test_each_parser_warning_prints_once(arm_file, caplog):
    """Drake's parser warnings (here an unsupported URDF tag on every joint) print
    once per process, however often the description is parsed (ground truth,
    controller's model, clearance potential, a sweep's trials)."""
    from dacph_drake.controllers import build_closed_loop
    from dacph_drake.scenario.built_in import satellite_3dof_scenario
    tagged = _joint2_as(arm_file, "tagged.urdf", '<joint name="joint2" '
                        'type="continuous"><safety_controller k_velocity="1"/>')
    scenario = satellite_3dof_scenario()
    scenario.robot.description, scenario.robot.base = str(tagged), MOUNT
    with caplog.at_level("WARNING", logger="drake"):
        for _ in range(2):
            build_closed_loop("dac", scenario)
    warnings = [r for r in caplog.records if "safety_controller" in r.getMessage()]
    assert len(warnings) == 1, [r.getMessage() for r in warnings]


def test_joint_limits_stop_a_run_by_name(arm_file):
    """The description's position limits, which the ground truth does not enforce:
    a run that leaves them stops with the joint named (robot.joint_limits "stop"),
    a q0 outside them is refused; "ignore" runs on."""
    from dacph_drake.loop.simulate import simulate
    from dacph_drake.scenario.built_in import satellite_3dof_scenario
    limited = _joint2_as(arm_file, "limited.urdf",
                         '<joint name="joint2" type="revolute"><limit lower="-0.85" '
                         'upper="-0.75" effort="100" velocity="2"/>')
    scenario = satellite_3dof_scenario()
    scenario.robot.description, scenario.robot.base = str(limited), MOUNT
    stopped = simulate(scenario, "model-based", duration=1.0)
    assert stopped.status == "diverged" and stopped.reason.startswith(
        "joint limit: joint 'joint2' at "), stopped.reason
    assert "beyond its limits [-0.8500, -0.7500] rad" in stopped.reason
    scenario.robot.joint_limits = "ignore"
    assert simulate(scenario, "model-based", duration=1.0).status == "ok"
    scenario.robot.joint_limits = "stop"
    scenario.q0 = [0.3, -0.9, 1.6]
    with pytest.raises(ConfigError, match=r"q0 = \[0.3, -0.9, 1.6\]: joint 'joint2' at "
                                          r"-0.9000 rad beyond .* robot.joint_limits: "
                                          r"ignore"):
        simulate(scenario, "model-based", duration=0.1)


def test_effort_limits_saturate_the_command_and_are_reported(arm_file):
    """A URDF's <limit effort> clips the actuator's command u in the ground truth
    (robot.effort_limits "saturate"), logged per joint (``saturated``) and reported
    (effort_saturated_share); "ignore" leaves u as sent. The 0.3 rad start asks
    joint 2 for far more than 0.2 N m."""
    from dacph_drake.loop.metrics import run_metrics
    from dacph_drake.loop.simulate import simulate
    from dacph_drake.scenario.built_in import satellite_3dof_scenario
    limited = _joint2_as(arm_file, "effort.urdf", '<joint name="joint2" '
                         'type="continuous"><limit effort="0.2" velocity="2"/>')
    scenario = satellite_3dof_scenario()
    scenario.robot.description, scenario.robot.base = str(limited), MOUNT
    runs = {}
    for setting in ("saturate", "ignore"):
        scenario.robot.effort_limits = setting
        result = simulate(scenario, "model-based", duration=0.3)
        runs[setting] = result.logs, run_metrics(result.logs, scenario)
    logs, metrics = runs["saturate"]
    assert np.any(np.abs(logs["u"][:, 1]) > 0.2)           # asked for more ...
    assert np.all(logs["saturated"][np.abs(logs["u"][:, 1]) > 0.2, 1] == 1.0)
    assert metrics["effort_saturated_share"] > 0.0          # ... and clipped, reported
    assert not runs["ignore"][0]["saturated"].any()
    assert runs["ignore"][1]["effort_saturated_share"] == 0.0
