"""Free-floating manipulators from robot description files (URDF, SDF) with Drake's
Parser: the root body becomes a free 6-DOF base (Drake's quaternion floating joint,
so nq = nv + 1), every revolute joint of the arm is actuated, gravity is zero.

The project ships its own descriptions (Drake's bundled models are fetched from the
internet on first use, which these machines cannot): SPATIAL_ROBOTS names them."""
from pathlib import Path

from pydrake.geometry import Role, SceneGraph
from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph, MultibodyPlant
from pydrake.multibody.tree import RevoluteJoint
from pydrake.systems.framework import DiagramBuilder

from dacph_drake.errors import ConfigError
from dacph_drake.dynamics.plant import BASE_JOINT, END_EFFECTOR, joint_name, link_name
from dacph_drake.arm_parameters import RobotParams

MODELS = Path(__file__).resolve().parents[1] / "models"
# scripts/make_spatial_models.py writes them.
SPATIAL_ROBOTS = {"satellite_3dof": MODELS / "satellite_3dof.urdf",
                  "satellite_6dof": MODELS / "satellite_6dof.urdf"}


def robot_description(name_or_path) -> Path:
    """The description file of a shipped robot (SPATIAL_ROBOTS) or a path to a
    .urdf / .sdf file (ConfigError naming what is allowed otherwise)."""
    if str(name_or_path) in SPATIAL_ROBOTS:
        return SPATIAL_ROBOTS[str(name_or_path)]
    path = Path(name_or_path)
    if path.suffix not in (".urdf", ".sdf") or not path.is_file():
        raise ConfigError(f"robot description {str(name_or_path)!r}: no such .urdf or "
                          f".sdf file; allowed: a file, or one of "
                          f"{', '.join(SPATIAL_ROBOTS)}")
    return path


def planar_arm_urdf(robot: RobotParams) -> str:
    """The URDF of a planar arm (arm_parameters.RobotParams): the same bodies, inertias, joint
    and frame names as plant.AddFreeFloatingArm builds directly (a planar joint
    for the base, continuous z-axis joints, the end effector a massless link)."""
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


def PopulateFromDescription(plant: MultibodyPlant, name_or_path) -> None:
    """Parses the description (a shipped name, a .urdf/.sdf path, or a planar
    RobotParams through planar_arm_urdf) into ``plant`` (not finalized), actuates
    each revolute joint the description leaves unactuated (in its joint order; no
    effort limit) and switches gravity off."""
    if isinstance(name_or_path, RobotParams):
        name_or_path.Validate()
        Parser(plant).AddModelsFromString(planar_arm_urdf(name_or_path), "urdf")
        path = "the planar arm's description"
    else:
        path = robot_description(name_or_path)
        try:
            Parser(plant).AddModels(str(path))
        except RuntimeError as e:
            raise ConfigError(f"{path}: {str(e).splitlines()[0]}") from e
    joints = [plant.get_joint(i) for i in plant.GetJointIndices()
              if isinstance(plant.get_joint(i), RevoluteJoint)]
    if not joints:
        raise ConfigError(f"{path} has no revolute joint; allowed: an arm of revolute "
                          "joints on a free base")
    actuated = {plant.get_joint_actuator(i).joint().index()
                for i in plant.GetJointActuatorIndices()}     # by the file's transmissions
    for joint in joints:
        if joint.index() not in actuated:
            plant.AddJointActuator(f"tau_{joint.name()}", joint)
    plant.mutable_gravity_field().set_gravity_vector([0.0, 0.0, 0.0])


def AddRobotFromDescription(builder: DiagramBuilder, name_or_path,
                            collision_geometry: bool = False
                            ) -> "tuple[MultibodyPlant, SceneGraph]":
    """The finalized continuous plant of the description, with its visual geometry
    registered with a SceneGraph (for Meshcat), added to ``builder``. Its collision
    geometry is dropped unless ``collision_geometry``: the ground truth, like the
    planar one, has no contact (a controller's clearance potential queries its own
    copy, robots.clearance_potential.BaseClearancePotential)."""
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, time_step=0.0)
    PopulateFromDescription(plant, name_or_path)
    if not collision_geometry:
        for geometry in scene_graph.model_inspector().GetAllGeometryIds(Role.kProximity):
            scene_graph.RemoveRole(plant.get_source_id(), geometry, Role.kProximity)
    plant.Finalize()
    _RequireFreeFloating(plant, name_or_path)
    return plant, scene_graph


def MakeRobotPlant(name_or_path) -> MultibodyPlant:
    """A finalized plant of the description without geometry, for a controller's
    internal model."""
    plant = MultibodyPlant(time_step=0.0)
    PopulateFromDescription(plant, name_or_path)
    plant.Finalize()
    _RequireFreeFloating(plant, name_or_path)
    return plant


def _RequireFreeFloating(plant: MultibodyPlant, name_or_path) -> None:
    if isinstance(name_or_path, RobotParams):
        return                                  # its base is on a planar joint
    floating = plant.GetFloatingBaseBodies()
    if len(floating) != 1:
        raise ConfigError(f"{name_or_path}: {len(floating)} free bodies; allowed: one "
                          "root body (the base), the arm attached to it by joints")
