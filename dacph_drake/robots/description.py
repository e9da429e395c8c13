"""Free-floating manipulators from robot description files with Drake's Parser: the root
body a free 6-DOF base, every revolute joint actuated, zero gravity; the project ships
its own descriptions (SPATIAL_ROBOTS)."""
import difflib
import logging
import os
import re
import sysconfig
from pathlib import Path
from typing import Dict, Optional, Tuple, Union

import numpy as np
from pydrake.geometry import (Box, CollisionFilterDeclaration, GeometrySet,
                             ProximityProperties, Role, SceneGraph)
from pydrake.common.eigen_geometry import AngleAxis
from pydrake.math import RigidTransform, RollPitchYaw, RotationMatrix
from pydrake.multibody.parsing import PackageMap, Parser
from pydrake.multibody.plant import CoulombFriction, MultibodyPlant
from pydrake.multibody.tree import (BodyIndex, FixedOffsetFrame, PrismaticJoint,
                                   RevoluteJoint, SpatialInertia)
from pydrake.systems.framework import Context, DiagramBuilder

from dacph_drake.scenario.errors import ConfigError
from dacph_drake.robots.description_quirks import (parser_warnings_once, refuse_xacro,
                                                   without_duplicate_materials)
from dacph_drake.robots.meshes import urdf_with_obj_meshes
from dacph_drake.robots.mjcf import MjcfFile, nonnegative_number
from dacph_drake.dynamics.plant import BASE_JOINT, END_EFFECTOR, joint_name, link_name
from dacph_drake.scenario.planar_arm import RobotParams
from dacph_drake.scenario import ArmBase, DescribedArm, EndEffectorFrame

MODELS = Path(__file__).resolve().parents[1] / "models"


class _EachWarningOnce(logging.Filter):
    """Passes each distinct message once per process."""

    def __init__(self):
        super().__init__()
        self._seen = set()

    def filter(self, record) -> bool:
        message = record.getMessage()
        if message in self._seen:
            return False
        self._seen.add(message)
        return True


logging.getLogger("drake").addFilter(_EachWarningOnce())
logging.getLogger(__name__).addFilter(_EachWarningOnce())
# The description formats Drake's parser reads: URDF, SDF and MJCF (MuJoCo's .xml).
DESCRIPTION_SUFFIXES = (".urdf", ".sdf", ".xml")
# scripts/make_spatial_models.py writes them.
SPATIAL_ROBOTS = {"satellite_3dof": MODELS / "satellite_3dof.urdf",
                  "satellite_6dof": MODELS / "satellite_6dof.urdf"}


def robot_description(name_or_path: Union[str, Path],
                      package_map: Optional[PackageMap] = None) -> Path:
    """The path of the description file a scenario's robot.description names.

    Args:
        name_or_path: A shipped robot's name (SPATIAL_ROBOTS), a package:// URI or a path.
        package_map: Resolves a package:// URI (package_map_of).

    Raises:
        ConfigError: For an unknown package or a path that is no description file."""
    if str(name_or_path) in SPATIAL_ROBOTS:
        return SPATIAL_ROBOTS[str(name_or_path)]
    text = str(name_or_path)
    if text.startswith("package://"):
        package, _, rest = text[len("package://"):].partition("/")
        if package_map is not None and not package_map.Contains(package):
            _AddPythonPackage(package_map, package)
        if package_map is None or not package_map.Contains(package):
            raise ConfigError(f"robot description {text!r}: unknown package {package!r}; "
                              "allowed: a package on robot.package_paths, "
                              "robot.packages, ROS_PACKAGE_PATH or AMENT_PREFIX_PATH, or "
                              "one installed with pip (e.g. pip install "
                              "'dacph-drake[robots]' for example-robot-data), or an "
                              "installed Python package of that name (robosuite)")
        path = Path(package_map.GetPath(package)) / rest
    else:
        path = Path(name_or_path)
    if path.name.endswith(".xacro") and path.is_file():
        refuse_xacro(path, "")
    if path.suffix not in DESCRIPTION_SUFFIXES or not path.is_file():
        raise ConfigError(f"robot description {text!r}: no such .urdf or .sdf file; "
                          f"allowed: a file, or one of {', '.join(SPATIAL_ROBOTS)}, or "
                          "a package:// URI of a file (.urdf, .sdf, or MuJoCo's MJCF "
                          ".xml)")
    return path


def _AddPythonPackage(package_map: PackageMap, name: str) -> None:
    """Adds an installed Python package's folder (e.g. robosuite's) as package ``name``."""
    import importlib.util
    try:
        spec = importlib.util.find_spec(name)
    except (ImportError, ValueError):
        return
    folders = list(spec.submodule_search_locations or []) if spec else []
    if folders:
        package_map.Add(name, folders[0])


def package_map_of(arm: DescribedArm, package_map: PackageMap) -> PackageMap:
    """Adds the packages an arm's package:// URIs may name to ``package_map``, returned
    (robot.packages, package_paths, ROS_PACKAGE_PATH, ament, cmeel; the first wins).

    Args:
        arm: The scenario's robot section.
        package_map: The map to add them to (changed in place)."""
    for name, folder in arm.packages.items():
        package_map.Add(name, str(folder))
    for folder in arm.package_paths:
        package_map.PopulateFromFolder(str(folder))
    package_map.PopulateFromRosPackagePath()
    prefixes = [Path(p) for p in os.environ.get("AMENT_PREFIX_PATH", "").split(":") if p]
    prefixes.append(Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix")
    for prefix in prefixes:
        index = prefix / "share" / "ament_index" / "resource_index" / "packages"
        for entry in (sorted(index.iterdir()) if index.is_dir() else []):
            if not package_map.Contains(entry.name) and (prefix / "share" / entry.name
                                                         ).is_dir():
                package_map.Add(entry.name, str(prefix / "share" / entry.name))
    return package_map


def planar_arm_urdf(robot: RobotParams) -> str:
    """The URDF text of a planar arm: plant.AddFreeFloatingArm's bodies, joints and frames.

    Args:
        robot: The arm (scenario.planar_arm.RobotParams)."""
    def inertial(mass, com, ixx, iyy, izz):
        return (f'<inertial><origin xyz="{com!r} 0 0"/><mass value="{mass!r}"/>'
                f'<inertia ixx="{ixx!r}" ixy="0" ixz="0" iyy="{iyy!r}" iyz="0" '
                f'izz="{izz!r}"/></inertial>')
    base = robot.base
    parts = [f'<robot name="planar_arm"><link name="base">'
             f'{inertial(base.mass, 0.0, base.inertia / 2, base.inertia / 2, base.inertia)}'
             f'</link><joint name="{BASE_JOINT}" type="planar"><parent link="world"/>'
             '<child link="base"/><axis xyz="0 0 1"/></joint>']
    parent, offset = "base", base.shoulder_offset
    for k, link in enumerate(robot.links):
        along = min(link.inertia, link.mass * link.com * (link.length - link.com))
        parts.append(f'<link name="{link_name(k)}">'
                     f'{inertial(link.mass, link.com, link.inertia - along, along, link.inertia)}'
                     f'</link><joint name="{joint_name(k)}" type="continuous">'
                     f'<parent link="{parent}"/><child link="{link_name(k)}"/>'
                     f'<origin xyz="{offset!r} 0 0"/><axis xyz="0 0 1"/></joint>')
        parent, offset = link_name(k), link.length
    parts.append(f'<link name="{END_EFFECTOR}"/><joint name="{END_EFFECTOR}_weld" '
                 f'type="fixed"><parent link="{parent}"/><child link="{END_EFFECTOR}"/>'
                 f'<origin xyz="{offset!r} 0 0"/></joint></robot>')
    return "".join(parts)


def described_arm(description: Union[str, Path, DescribedArm]) -> DescribedArm:
    """A described robot as a scenario's robot section (a section is returned as it is).

    Args:
        description: A robot section (scenario.DescribedArm), or a bare name or path."""
    return (description if hasattr(description, "description")
            else DescribedArm(description=str(description)))


def PopulateFromDescription(plant: MultibodyPlant,
                            name_or_path: Union[str, Path, DescribedArm, RobotParams]
                            ) -> Dict[str, float]:
    """Parses a description into a plant: gravity off, each unactuated revolute joint
    actuated, another moving joint refused. Returns the joints' Coulomb friction
    (joint_friction; none with robot.joint_friction "zero").

    Args:
        plant: The plant (not finalized; left so).
        name_or_path: A shipped name, a .urdf/.sdf path, a DescribedArm or a RobotParams.

    Raises:
        ConfigError: Naming what in the description or robot section is not allowed."""
    efforts, friction, armature = {}, {}, {}
    if isinstance(name_or_path, RobotParams):
        name_or_path.Validate()
        Parser(plant).AddModelsFromString(planar_arm_urdf(name_or_path), "urdf")
        path = "the planar arm's description"
    else:
        arm = described_arm(name_or_path)
        parser = Parser(plant)
        path = robot_description(arm.description,
                                 package_map_of(arm, parser.package_map()))
        converted, kind = None, path.suffix[1:]
        mjcf = MjcfFile(path) if path.suffix == ".xml" else None
        if mjcf is not None:
            converted = mjcf.drake_text
            if mjcf.mesh_inertia_notes:
                logging.getLogger(__name__).warning(
                    "%s: MuJoCo takes the inertia of %s otherwise than from the mesh's "
                    "exact volume, as Drake does: those bodies' inertias differ from "
                    "MuJoCo's (<mesh inertia=\"exact\"> makes them agree)", path,
                    ", ".join(mjcf.mesh_inertia_notes))
            if mjcf.servos:
                logging.getLogger(__name__).warning(
                    "%s: %s act as torque motors: the controller commands each joint's "
                    "torque (a servo's forcerange is its effort limit)", path,
                    ", ".join(mjcf.servos))
        elif path.suffix == ".urdf":
            text = path.read_text(encoding="utf-8")
            refuse_xacro(path, text)
            converted = urdf_with_obj_meshes(path, parser.package_map(),
                                             without_duplicate_materials(text, path)[0])
        efforts = (_UrdfEffortLimits(path) if path.suffix == ".urdf"
                   and arm.effort_limits == "saturate" else {})
        friction = ({} if arm.joint_friction != "keep" else
                    mjcf.JointAttribute("frictionloss") if mjcf else joint_friction(path))
        armature = mjcf.JointAttribute("armature") if mjcf else {}
        if friction:
            from dacph_drake.kernels.loop import FRICTION_VELOCITY
            logging.getLogger(__name__).warning(
                "%s: the joint friction of %s acts in the ground truth as f tanh(qdot / "
                "%g rad/s), which Drake's parser does not model (robot.joint_friction: "
                "keep)", path, ", ".join(f"{name} {f:g} N m" for name, f in
                                        friction.items()), FRICTION_VELOCITY)
        try:
            with parser_warnings_once(path):
                instances = (parser.AddModels(str(path)) if converted is None
                             else parser.AddModelsFromString(converted, kind))
            if arm.base.mass > 0:
                _MountOnBase(plant, instances, arm.base)
            if path.suffix == ".xml":
                _GearedEffortLimits(plant)
        except (RuntimeError, ValueError) as e:    # Drake's parser raises both
            raise ConfigError(f"{path}: {_DrakeMessage(e, path)}") from e
        _LockJoints(plant, arm.locked_joints, path)
    moving = [plant.get_joint(i) for i in plant.GetJointIndices()
              if plant.get_joint(i).num_velocities() > 0]
    for joint in moving:
        if not isinstance(joint, RevoluteJoint) and joint.parent_body().index() != \
                plant.world_body().index():
            raise ConfigError(f"{path}: joint {joint.name()!r} is a "
                              f"{joint.type_name()} joint; allowed: revolute joints "
                              "between the base and the end effector, and revolute or "
                              "prismatic joints locked (robot.locked_joints)")
    joints = [joint for joint in moving if isinstance(joint, RevoluteJoint)]
    if not joints:
        raise ConfigError(f"{path} has no revolute joint; allowed: an arm of revolute "
                          "joints on a free base")
    actuated = {plant.get_joint_actuator(i).joint().index()
                for i in plant.GetJointActuatorIndices()}     # by the file's transmissions
    for joint in joints:
        if joint.index() not in actuated:
            actuator = plant.AddJointActuator(f"tau_{joint.name()}", joint,
                                              efforts.get(joint.name(), np.inf))
            # An MJCF joint's armature without a <motor> (MuJoCo's joint property;
            # Drake reads it only through one): the same reflected inertia, gear 1.
            actuator.set_default_rotor_inertia(armature.get(joint.name(), 0.0))
    plant.mutable_gravity_field().set_gravity_vector([0.0, 0.0, 0.0])
    if not isinstance(name_or_path, RobotParams):
        arm = described_arm(name_or_path)
        _AddEndEffector(plant, arm.end_effector, path)
        damped = [joint for joint in joints if joint.default_damping() > 0]
        if damped and arm.joint_damping == "zero":
            for joint in damped:
                joint.set_default_damping(0.0)
            logging.getLogger(__name__).warning(
                "%s: the joint damping of %s is set to zero (robot.joint_damping: zero)",
                path, ", ".join(joint.name() for joint in damped))
    return friction


def _DrakeMessage(error: Exception, path: Path) -> str:
    """The first line of a parser error, located in the user's file."""
    return re.sub(r"<literal-string>\.urdf", path.name, str(error).splitlines()[0])


def _MountOnBase(plant: MultibodyPlant, instances, base: ArmBase) -> None:
    """Welds the arm's root body at base.mount to a uniform box "base" of base.mass."""
    roots = [plant.get_body(b) for instance in instances
             for b in plant.GetBodyIndices(instance)]
    _DropWorldAnchors(plant, instances)
    children = {plant.get_joint(j).child_body().index() for instance in instances
                for j in plant.GetJointIndices(instance)}
    root = next(body for body in roots if body.index() not in children)
    body = plant.AddRigidBody("base", plant.AddModelInstance("base"),
                              SpatialInertia.SolidBoxWithMass(base.mass, *base.size))
    if plant.geometry_source_is_registered():
        box = Box(*base.size)
        plant.RegisterCollisionGeometry(body, RigidTransform(), box, "base_collision",
                                        CoulombFriction(1.0, 1.0))
        plant.RegisterVisualGeometry(body, RigidTransform(), box, "base_visual",
                                     [0.75, 0.75, 0.8, 1.0])
    plant.WeldFrames(body.body_frame(), root.body_frame(), RigidTransform(
        RollPitchYaw(base.mount[3:]), base.mount[:3]))


def _GearedEffortLimits(plant: MultibodyPlant) -> None:
    """An MJCF <motor>'s torque is gear x ctrl and Drake takes ctrlrange as u's effort
    limit, so the torque's limit is |gear| x ctrlrange."""
    for index in plant.GetJointActuatorIndices():
        actuator = plant.get_joint_actuator(index)
        gear, limit = abs(actuator.default_gear_ratio()), actuator.effort_limit()
        if np.isfinite(limit) and gear != 1.0:
            actuator.set_effort_limit(limit * gear)


def _DropWorldAnchors(plant: MultibodyPlant, instances) -> None:
    """Removes (and logs) each weld of the description to the world."""
    world = plant.world_body().index()
    for index in [j for instance in instances for j in plant.GetJointIndices(instance)]:
        joint = plant.get_joint(index)
        if joint.parent_body().index() != world:
            continue
        if joint.num_velocities() > 0:
            raise ConfigError(f"joint {joint.name()!r} moves the arm against the world "
                              f"({joint.type_name()}); allowed: a weld to the world "
                              "(dropped when the arm is mounted on robot.base) or none")
        name = joint.name()
        plant.RemoveJoint(joint)
        logging.getLogger(__name__).warning(
            "the description's weld %r to the world is dropped: the arm is mounted on "
            "robot.base", name)


def joint_friction(path: Path) -> Dict[str, float]:
    """Joint name -> the description's Coulomb friction [N m] where positive, which Drake's
    parsers do not model (URDF <dynamics friction>, SDF <friction>, MJCF frictionloss).

    Args:
        path: The description file.

    Raises:
        ConfigError: A friction that is not a number >= 0, naming the joint."""
    if path.suffix == ".xml":
        return MjcfFile(path).JointAttribute("frictionloss")
    root = _XmlRoot(path)
    where = "dynamics" if path.suffix == ".urdf" else "axis/dynamics/friction"
    friction = {}
    for joint in root.iter("joint"):
        element = joint.find(where)
        value = (None if element is None else element.get("friction")
                 if path.suffix == ".urdf" else element.text)
        if value is None:
            continue
        loss = nonnegative_number(value, f"{path}: joint {joint.get('name')!r}: "
                                         f"friction {value!r}")
        if loss > 0:
            friction[joint.get("name")] = loss
    return friction


def _XmlRoot(path: Path):
    """A URDF's or SDF's XML root (ConfigError naming a file that is no XML)."""
    import xml.etree.ElementTree as ElementTree
    try:
        return ElementTree.parse(path).getroot()
    except ElementTree.ParseError as e:
        raise ConfigError(f"{path}: {e}") from e


def _UrdfEffortLimits(path: Path) -> dict:
    """Joint name -> the URDF's <limit effort> [N m] (joints with a positive one)."""
    limits = {}
    for joint in _XmlRoot(path).iter("joint"):
        limit = joint.find("limit")
        if limit is not None and float(limit.get("effort", "0") or 0) > 0:
            limits[joint.get("name")] = float(limit.get("effort"))
    return limits


def _LockJoints(plant: MultibodyPlant, locked, path) -> None:
    """Welds each joint in ``locked`` (name: position) and every other prismatic joint."""
    wanted, welded = dict(locked), []
    if any(isinstance(plant.get_joint(j), PrismaticJoint) or plant.get_joint(j).name()
           in wanted for j in plant.GetJointIndices()):
        for constraint in plant.GetConstraintIds():
            plant.RemoveConstraint(constraint)
    for index in list(plant.GetJointIndices()):
        joint = plant.get_joint(index)
        revolute, prismatic = (isinstance(joint, RevoluteJoint),
                               isinstance(joint, PrismaticJoint))
        if not (prismatic or (revolute and joint.name() in wanted)):
            continue
        name = joint.name()         # the joint object is gone after RemoveJoint
        position = float(wanted.pop(name, 0.0))
        motion = (RigidTransform(RotationMatrix(AngleAxis(position, joint.revolute_axis())),
                                 np.zeros(3)) if revolute
                  else RigidTransform(position * joint.translation_axis()))
        parent, child = joint.frame_on_parent(), joint.frame_on_child()
        for actuator in list(plant.GetJointActuatorIndices()):
            if plant.get_joint_actuator(actuator).joint().index() == index:
                plant.RemoveJointActuator(plant.get_joint_actuator(actuator))
        plant.RemoveJoint(joint)
        plant.WeldFrames(parent, child, motion)
        welded.append(f"{name} at {position:g}")
    if wanted:
        raise ConfigError(f"robot.locked_joints names {next(iter(wanted))!r}, which is "
                          f"not a revolute or prismatic joint of {path}; allowed: the "
                          "names of its joints")
    if welded:
        logging.getLogger(__name__).warning(
            "%s: locked (welded) joints: %s (robot.locked_joints)", path,
            ", ".join(welded))


def _AddEndEffector(plant: MultibodyPlant, end_effector: EndEffectorFrame, path) -> None:
    """Adds frame END_EFFECTOR at end_effector.offset from end_effector.frame (or not)."""
    if not end_effector.frame:
        if not plant.HasFrameNamed(END_EFFECTOR):
            raise ConfigError(
                f"{path} has no frame named {END_EFFECTOR!r}; allowed: a description "
                "with one, or robot.end_effector.frame naming a frame of it (e.g. its "
                "last link)")
        return
    if not plant.HasFrameNamed(end_effector.frame):
        frames = [plant.get_body(BodyIndex(i)).name() for i in range(1, plant.num_bodies())
                  if plant.get_body(BodyIndex(i)).name() != "base"]
        close = difflib.get_close_matches(end_effector.frame, frames, n=1)
        raise ConfigError(f"robot.end_effector.frame = {end_effector.frame!r} is not a "
                          f"frame of {path}"
                          + (f" (did you mean {close[0]!r}?)" if close else "")
                          + f"; allowed: one of its link frames: {', '.join(frames)}")
    if plant.HasFrameNamed(END_EFFECTOR):
        raise ConfigError(f"robot.end_effector.frame = {end_effector.frame!r} with "
                          f"{path}, which has its own frame {END_EFFECTOR!r}; allowed: "
                          "an empty robot.end_effector.frame (that frame is used)")
    plant.AddFrame(FixedOffsetFrame(END_EFFECTOR, plant.GetFrameByName(end_effector.frame),
                                    RigidTransform(end_effector.offset)))


class ParsedDescription:
    """A description parsed once into a finalized continuous ``plant`` and its
    ``scene_graph`` (no proximity role: the truth computes no contact); the truth, the model
    and the clearance potential use contexts of their own.

    Args:
        name_or_path: The description, as PopulateFromDescription reads it.

    Raises:
        ConfigError: As PopulateFromDescription, or not one free base with mass."""

    def __init__(self, name_or_path: Union[str, Path, DescribedArm, RobotParams]):
        self.plant, self.scene_graph = MultibodyPlant(time_step=0.0), SceneGraph()
        self.plant.set_name("plant")        # names SceneGraph's plant_pose port
        self.scene_graph.set_name("scene_graph")
        self.plant.RegisterAsSourceForSceneGraph(self.scene_graph)
        # The description's joint Coulomb friction by joint name [N m] (the plant
        # does not hold it; the ground truth's RHS applies it).
        self.joint_friction = PopulateFromDescription(self.plant, name_or_path)
        self.plant.Finalize()
        _RequireFreeFloating(self.plant, name_or_path)
        inspector, source = self.scene_graph.model_inspector(), self.plant.get_source_id()
        self._proximity = {geometry: ProximityProperties(
            inspector.GetProximityProperties(geometry))
            for geometry in inspector.GetAllGeometryIds(Role.kProximity)}
        for geometry in self._proximity:
            self.scene_graph.RemoveRole(source, geometry, Role.kProximity)
        self._added = False

    def AddTo(self, builder: DiagramBuilder) -> "tuple[MultibodyPlant, SceneGraph]":
        """Adds the plant and SceneGraph to a diagram (once): (plant, scene_graph).

        Args:
            builder: The diagram's builder."""
        if self._added:
            raise RuntimeError("a ParsedDescription's plant is already in a diagram; "
                               "parse the description again for another one")
        self._added = True
        plant, scene_graph = self.plant, self.scene_graph
        builder.AddSystem(plant)
        builder.AddSystem(scene_graph)
        builder.Connect(plant.get_geometry_pose_output_port(),
                        scene_graph.get_source_pose_port(plant.get_source_id()))
        builder.Connect(plant.get_deformable_body_configuration_output_port(),
                        scene_graph.get_source_configuration_port(plant.get_source_id()))
        builder.Connect(scene_graph.get_query_output_port(),
                        plant.get_geometry_query_input_port())
        return plant, scene_graph

    def ClearanceContexts(self) -> Tuple[Context, Context]:
        """(plant context, SceneGraph context) for collision queries (proximity role given
        back): set positions, UpdatePoses, then query."""
        plant, context = self.plant, self.scene_graph.CreateDefaultContext()
        for geometry, properties in self._proximity.items():
            self.scene_graph.AssignRole(context, plant.get_source_id(), geometry,
                                        properties)

        def geometries(bodies):
            return GeometrySet([g for body in bodies
                                for g in plant.GetCollisionGeometriesForBody(body)])
        filters = CollisionFilterDeclaration()
        for index in plant.GetJointIndices():
            joint = plant.get_joint(index)
            filters.ExcludeBetween(geometries([joint.parent_body()]),
                                   geometries([joint.child_body()]))
        for group in {tuple(sorted(int(b.index()) for b in plant.GetBodiesWeldedTo(
                plant.get_body(BodyIndex(i))))) for i in range(plant.num_bodies())}:
            filters.ExcludeWithin(geometries([plant.get_body(BodyIndex(b))
                                              for b in group]))
        self.scene_graph.collision_filter_manager(context).Apply(filters)
        return plant.CreateDefaultContext(), context

    def UpdatePoses(self, plant_context: Context, scene_graph_context: Context) -> None:
        """Sets the SceneGraph context's geometry poses from the plant's positions.

        Args:
            plant_context: The plant's context (ClearanceContexts).
            scene_graph_context: The SceneGraph's context (ClearanceContexts)."""
        self.scene_graph.get_source_pose_port(self.plant.get_source_id()).FixValue(
            scene_graph_context,
            self.plant.get_geometry_pose_output_port().Eval(plant_context))


def AddRobotFromDescription(builder: DiagramBuilder,
                            name_or_path: Union[str, Path, DescribedArm, RobotParams]
                            ) -> "tuple[MultibodyPlant, SceneGraph]":
    """Adds a description's plant and SceneGraph to a diagram: (plant, scene_graph).

    Args:
        builder: The diagram's builder.
        name_or_path: The description, as ParsedDescription takes it.

    Raises:
        ConfigError: As ParsedDescription."""
    return ParsedDescription(name_or_path).AddTo(builder)


def MakeRobotPlant(name_or_path: Union[str, Path, DescribedArm, RobotParams]
                   ) -> MultibodyPlant:
    """Makes a finalized plant of a description without geometry (a controller's model).

    Args:
        name_or_path: The description, as PopulateFromDescription takes it.

    Raises:
        ConfigError: As ParsedDescription."""
    plant = MultibodyPlant(time_step=0.0)
    PopulateFromDescription(plant, name_or_path)
    plant.Finalize()
    _RequireFreeFloating(plant, name_or_path)
    return plant


def _RequireFreeFloating(plant: MultibodyPlant, name_or_path) -> None:
    if isinstance(name_or_path, RobotParams):
        return                                  # its base is on a planar joint
    description = described_arm(name_or_path).description
    floating = plant.GetFloatingBaseBodies()
    multi = [plant.get_joint(j) for j in plant.GetJointIndices()
             if plant.get_joint(j).num_velocities() > 1
             and plant.get_joint(j).parent_body().index() != plant.world_body().index()]
    if multi:
        raise ConfigError(f"{description}: joint {multi[0].name()!r} "
                          f"({multi[0].type_name()}) moves {multi[0].child_body().name()!r} "
                          f"in {multi[0].num_velocities()} directions; allowed: an arm of "
                          "revolute, prismatic and fixed joints")
    if len(floating) > 1:
        base, *loose = [plant.get_body(b).name() for b in sorted(floating)]
        raise ConfigError(f"{description}: {len(floating)} free bodies: the base "
                          f"{base!r} and {', '.join(map(repr, loose))} (a floating "
                          "joint, which Drake's parser frees, or a link without a joint "
                          "to the arm); allowed: one root body (the base), the arm "
                          "attached to it by revolute, prismatic and fixed joints")
    if not floating:
        raise ConfigError(f"{description}: 0 free bodies; allowed: one root body (the "
                          "base), the arm attached to it by joints (or robot.base to "
                          "mount it on one)")
    base = plant.get_body(next(iter(floating)))
    if not base.default_mass() > 0:
        raise ConfigError(f"{described_arm(name_or_path).description}: the free base "
                          f"{base.name()!r} has no mass; allowed: a description whose "
                          "root body has mass, or robot.base to mount the arm on one")
