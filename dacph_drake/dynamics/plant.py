"""The ground-truth free-floating arm as a Drake MultibodyPlant (docs/equations.md E6-E11):
``base`` on the PlanarJoint ``base_joint`` (x, y, theta0); ``link1``..``linkn`` on
RevoluteJoints ``q1``..``qn`` about +z, driven by ``tau1``..``taun``; frame
``end_effector`` at the last link's tip; zero gravity; continuous time by default."""
from dataclasses import dataclass
from typing import List, Optional, Sequence, Tuple

import numpy as np
from pydrake.geometry import Box, SceneGraph
from pydrake.math import RigidTransform
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph, MultibodyPlant
from pydrake.multibody.tree import (BodyIndex, FixedOffsetFrame, ModelInstanceIndex,
                                    PlanarJoint, RevoluteJoint, RotationalInertia,
                                    SpatialInertia, WeldJoint, default_model_instance)
from pydrake.systems.framework import Context, DiagramBuilder, System
from pydrake.systems.primitives import Selector, SelectorParams

from dacph_drake.scenario.planar_arm import RobotParams

BASE_JOINT = "base_joint"
END_EFFECTOR = "end_effector"
TRIAL_INSTANCE = "trial{}"      # a batch's plant: each trial's arm (AddFreeFloatingArms)
GEOMETRY_DEPTH = 0.05  # extent of the boxes along z [m]; does not enter the dynamics


def joint_name(k: int) -> str:
    """Name of the k-th arm joint (the paper's q_{k+1}): q1, q2, ...

    Args:
        k: The joint's index, k = 0 .. n-1."""
    return f"q{k + 1}"


def link_name(k: int) -> str:
    """The name of a planar arm's link: link1, link2, ...

    Args:
        k: The link's index (0-based)."""
    return f"link{k + 1}"


@dataclass
class ArmCoordinates:
    """Where the base and the joints sit in a plant's q and v vectors.

    Attributes:
        base_q: The base joint's position indices in q.
        base_v: Its velocity indices in v, world frame (vx, vy, omega0; free: omega_W, v_W).
        joint_q: The joint angles' indices in q.
        joint_v: The joint rates' indices in v.
        base_origin: The base joint's coordinates at the origin (free: identity quaternion).
        plant_positions: The whole plant's number of positions (a batch: every trial's)."""
    base_q: np.ndarray
    base_v: np.ndarray
    joint_q: np.ndarray
    joint_v: np.ndarray
    base_origin: np.ndarray
    plant_positions: int

    @staticmethod
    def FromPlant(plant: MultibodyPlant, instance: Optional[ModelInstanceIndex] = None
                  ) -> "ArmCoordinates":
        """The layout of a finalized free-floating plant (base on the world, actuated arm).

        Args:
            plant: The finalized free-floating plant.
            instance: The model instance to describe (default: the whole plant).

        Raises:
            ValueError: The plant (or instance) has not exactly one joint on the world."""
        among = () if instance is None else (instance,)
        on_world = [plant.get_joint(i) for i in plant.GetJointIndices(*among)
                    if plant.get_joint(i).parent_body().index()
                    == plant.world_body().index()]
        if len(on_world) != 1:
            raise ValueError(f"a free-floating plant has one joint on the world (its "
                             f"base's); this one has {len(on_world)}")
        base = on_world[0]
        joints = [plant.get_joint_actuator(i).joint()
                  for i in plant.GetJointActuatorIndices(*among)]
        return ArmCoordinates(
            base_q=np.arange(base.position_start(),
                             base.position_start() + base.num_positions()),
            base_v=np.arange(base.velocity_start(),
                             base.velocity_start() + base.num_velocities()),
            joint_q=np.array([j.position_start() for j in joints]),
            joint_v=np.array([j.velocity_start() for j in joints]),
            base_origin=np.array(base.default_positions()),
            plant_positions=plant.num_positions())

    @staticmethod
    def ForPlanarArm(num_joints: int) -> "ArmCoordinates":
        """A planar arm's layout (AddFreeFloatingArm, MakeArmPlant): x, y, theta0 first.

        Args:
            num_joints: The arm's number of links (and joints)."""
        joints = np.arange(3, 3 + num_joints)
        return ArmCoordinates(base_q=np.arange(3), base_v=np.arange(3), joint_q=joints,
                              joint_v=joints, base_origin=np.zeros(3),
                              plant_positions=3 + num_joints)

    @property
    def num_joints(self) -> int:
        return len(self.joint_v)

    @property
    def num_positions(self) -> int:
        return len(self.base_q) + len(self.joint_q)

    def Positions(self, q: np.ndarray, base_pose: Optional[np.ndarray] = None
                  ) -> np.ndarray:
        """The plant's position vector.

        Args:
            q: The joint angles (n) [rad].
            base_pose: The base joint's coordinates (default: base_origin)."""
        positions = np.zeros(self.num_positions)
        positions[self.base_q] = self.base_origin if base_pose is None else base_pose
        positions[self.joint_q] = q
        return positions

    def StateIndices(self) -> np.ndarray:
        """Indices into x of [theta0, base velocity (3), q, qdot] (kernels.loop)."""
        nq = self.plant_positions
        return np.concatenate([self.base_q[2:3], nq + self.base_v, self.joint_q,
                               nq + self.joint_v]).astype(np.int64)

    def Split(self, x: np.ndarray
              ) -> Tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The parts (base_pose, q, base_velocity, qdot) of plant state(s).

        Args:
            x: Plant state(s) [positions, velocities] (the last axis)."""
        v = x[..., self.plant_positions:]
        return (x[..., self.base_q], x[..., self.joint_q], v[..., self.base_v],
                v[..., self.joint_v])


def trial_coordinates(plant: MultibodyPlant) -> List[ArmCoordinates]:
    """Each trial's ArmCoordinates in a batch's plant, in trial order.

    Args:
        plant: The batch's plant (AddFreeFloatingArms); a plant of one arm is one trial."""
    instances = [plant.GetModelInstanceByName(TRIAL_INSTANCE.format(i))
                 for i in range(plant.num_model_instances())
                 if plant.HasModelInstanceNamed(TRIAL_INSTANCE.format(i))]
    if not instances:
        return [ArmCoordinates.FromPlant(plant)]
    return [ArmCoordinates.FromPlant(plant, instance) for instance in instances]


def SetArmAtRest(plant: MultibodyPlant, plant_context: Context, q0: np.ndarray
                 ) -> None:
    """SetArmsAtRest of a plant of one arm.

    Args:
        plant: The plant of one arm.
        plant_context: Its context, set in place.
        q0: The joint angles [rad]."""
    SetArmsAtRest(plant, plant_context, [q0])


def SetArmsAtRest(plant: MultibodyPlant, plant_context: Context,
                  q0s: Sequence[np.ndarray]) -> None:
    """Sets every trial's base at the origin and its joints at its q0, all at rest.

    Args:
        plant: The batch's plant.
        plant_context: Its context, set in place.
        q0s: Each trial's joint angles q0 [rad], in trial order."""
    positions = np.zeros(plant.num_positions())
    for coordinates, q0 in zip(trial_coordinates(plant), q0s, strict=True):
        positions[coordinates.base_q] = coordinates.base_origin
        positions[coordinates.joint_q] = q0
    plant.SetPositions(plant_context, positions)
    plant.SetVelocities(plant_context, np.zeros(plant.num_velocities()))


STATE_SIGNALS = ("base_pose", "q", "base_velocity", "qdot")    # AddStateSplitter's


def FixStateInputs(system: System, context: Context, x: np.ndarray) -> None:
    """Fixes ``state`` and STATE_SIGNALS of a planar arm's system tested alone.

    Args:
        system: The system.
        context: Its context.
        x: The plant state [positions, velocities]."""
    if system.HasInputPort("state"):
        system.GetInputPort("state").FixValue(context, x)
    num_joints = (len(x) - 6) // 2
    for name, value in zip(STATE_SIGNALS, ArmCoordinates.ForPlanarArm(num_joints).Split(x)):
        if system.HasInputPort(name):
            system.GetInputPort(name).FixValue(context, value)


def AddStateSplitter(builder: DiagramBuilder, plant: MultibodyPlant) -> Selector:
    """Adds and returns the Selector "state_splitter" (C++) giving ``base_pose``, ``q``,
    ``base_velocity`` (world frame) and ``qdot``, each the trials' stacked in trial order.

    Args:
        builder: The builder it is added to.
        plant: The (batch's) plant, in ``builder``."""
    trials = trial_coordinates(plant)
    nq = plant.num_positions()

    def stacked(field: str) -> np.ndarray:
        return np.concatenate([getattr(c, field) for c in trials])

    def output(name, indices):
        return SelectorParams.OutputPortParams(name=name, selections=[
            SelectorParams.OutputSelection(input_port_index=0, input_offset=int(i))
            for i in indices])
    splitter = builder.AddNamedSystem("state_splitter", Selector(SelectorParams(
        inputs=[SelectorParams.InputPortParams(name="state",
                                               size=nq + plant.num_velocities())],
        outputs=[output("base_pose", stacked("base_q")),
                 output("q", stacked("joint_q")),
                 output("base_velocity", nq + stacked("base_v")),
                 output("qdot", nq + stacked("joint_v"))])))
    builder.Connect(plant.get_state_output_port(), splitter.get_input_port())
    return splitter


def AddFreeFloatingArm(builder: DiagramBuilder, robot: RobotParams,
                       time_step: float = 0.0) -> "tuple[MultibodyPlant, SceneGraph]":
    """AddFreeFloatingArms of one arm: (plant, scene_graph).

    Args:
        builder: The builder the plant is added to.
        robot: The arm.
        time_step: The plant's time step [s] (0: continuous)."""
    return AddFreeFloatingArms(builder, [robot], time_step)


def AddFreeFloatingArms(builder: DiagramBuilder, robots: Sequence[RobotParams],
                        time_step: float = 0.0) -> "tuple[MultibodyPlant, SceneGraph]":
    """Adds a batch's finalized plant, one arm per trial (TRIAL_INSTANCE.format(i); one
    arm: the default instance), visual geometry only; returns (plant, scene_graph).

    Args:
        builder: The builder the plant is added to.
        robots: Each trial's arm, in trial order.
        time_step: The plant's time step [s]; continuous unless > 0."""
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, time_step=time_step)
    for i, robot in enumerate(robots):
        robot.Validate()
        _PopulateArm(plant, robot, default_model_instance() if len(robots) == 1
                     else plant.AddModelInstance(TRIAL_INSTANCE.format(i)))
    plant.mutable_gravity_field().set_gravity_vector(np.zeros(3))
    plant.Finalize()
    return plant, scene_graph


def AddClonedArms(builder: DiagramBuilder, sources: Sequence[MultibodyPlant]
                  ) -> "tuple[MultibodyPlant, SceneGraph]":
    """Adds the finalized continuous plant of a batch, one copy of a source arm per trial
    (inertias, joints, actuators, free base; no geometry); returns (plant, scene_graph).

    Args:
        builder: The builder the plant is added to.
        sources: The trials' finalized arm plants (robots.description.ParsedDescription).

    Raises:
        ValueError: A source has a joint that is neither revolute nor a weld."""
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, time_step=0.0)
    for i, source in enumerate(sources):
        instance = plant.AddModelInstance(TRIAL_INSTANCE.format(i))
        bodies = {source.world_body().index(): plant.world_body()}
        for b in range(1, source.num_bodies()):
            body = source.get_body(BodyIndex(b))
            bodies[body.index()] = plant.AddRigidBody(body.name(), instance,
                                                      body.default_spatial_inertia())
        joints = {}
        for index in source.GetJointIndices():
            joint = source.get_joint(index)
            if joint.parent_body().index() == source.world_body().index():
                continue                         # the free base's: Finalize adds it
            frames = [_ClonedFrame(plant, bodies[frame.body().index()], frame)
                      for frame in (joint.frame_on_parent(), joint.frame_on_child())]
            if joint.num_velocities() == 0:
                cloned = WeldJoint(joint.name(), *frames, joint.X_FM())
            elif isinstance(joint, RevoluteJoint):
                cloned = RevoluteJoint(joint.name(), *frames, joint.revolute_axis(),
                                       joint.default_damping())
            else:
                raise ValueError(f"joint {joint.name()!r}: {joint.type_name()}; "
                                 "allowed: revolute joints and welds")
            joints[index] = plant.AddJoint(cloned)
        for a in source.GetJointActuatorIndices():
            actuator = source.get_joint_actuator(a)
            copy = plant.AddJointActuator(actuator.name(), joints[actuator.joint().index()],
                                          actuator.effort_limit())
            copy.set_default_rotor_inertia(actuator.default_rotor_inertia())
            copy.set_default_gear_ratio(actuator.default_gear_ratio())
    plant.mutable_gravity_field().set_gravity_vector(np.zeros(3))
    plant.Finalize()
    return plant, scene_graph


def _ClonedFrame(plant: MultibodyPlant, body, frame):
    """A source's ``frame`` on the cloned ``body``: its body frame or a FixedOffsetFrame."""
    X_BF = frame.GetFixedPoseInBodyFrame()
    if np.array_equal(X_BF.GetAsMatrix4(), np.eye(4)):
        return body.body_frame()
    return plant.AddFrame(FixedOffsetFrame(frame.name(), body.body_frame(), X_BF))


def MakeArmPlant(robot: RobotParams) -> MultibodyPlant:
    """A finalized arm plant without geometry, for a controller's internal model.

    Args:
        robot: The arm."""
    robot.Validate()
    plant = MultibodyPlant(time_step=0.0)
    _PopulateArm(plant, robot, default_model_instance())
    plant.mutable_gravity_field().set_gravity_vector(np.zeros(3))
    plant.Finalize()
    return plant


def _PopulateArm(plant: MultibodyPlant, robot: RobotParams, instance) -> None:
    base = robot.base
    base_body = plant.AddRigidBody("base", instance, SpatialInertia.MakeFromCentralInertia(
        base.mass, np.zeros(3),
        RotationalInertia(base.inertia / 2, base.inertia / 2, base.inertia)))
    plant.AddJoint(PlanarJoint(BASE_JOINT, plant.world_frame(), base_body.body_frame()))
    parent_frame = plant.AddFrame(FixedOffsetFrame(
        "shoulder", base_body.body_frame(),
        RigidTransform([base.shoulder_offset, 0.0, 0.0])))
    bodies = [base_body]
    for k, link in enumerate(robot.links):
        # A lamina in the link's x-y plane: the along-link spread (<= m c (l - c))
        # gives Iyy, the across-link spread the rest; Izz = Ixx + Iyy = inertia.
        along = min(link.inertia, link.mass * link.com * (link.length - link.com))
        body = plant.AddRigidBody(link_name(k), instance,
                                  SpatialInertia.MakeFromCentralInertia(
            link.mass, [link.com, 0.0, 0.0],
            RotationalInertia(link.inertia - along, along, link.inertia)))
        joint = plant.AddJoint(RevoluteJoint(
            joint_name(k), parent_frame, body.body_frame(), [0.0, 0.0, 1.0]))
        plant.AddJointActuator(f"tau{k + 1}", joint)
        parent_frame = plant.AddFrame(FixedOffsetFrame(
            END_EFFECTOR if k == robot.num_links - 1 else f"elbow{k + 1}",
            body.body_frame(), RigidTransform([link.length, 0.0, 0.0])))
        bodies.append(body)
    if plant.geometry_source_is_registered():
        _RegisterGeometry(plant, robot, bodies)


BASE_COLOR = (0.75, 0.75, 0.8, 1.0)                          # RGBA of the base's box
LINK_COLORS = ((0.85, 0.45, 0.1, 1.0), (0.2, 0.45, 0.8, 1.0))  # links alternate


def _RegisterGeometry(plant: MultibodyPlant, robot: RobotParams, bodies: List) -> None:
    shapes = [(bodies[0], Box(robot.base.size, robot.base.size, GEOMETRY_DEPTH),
               RigidTransform(), np.array(BASE_COLOR))]
    for k, link in enumerate(robot.links):
        shapes.append((bodies[k + 1], Box(link.length, link.width, GEOMETRY_DEPTH),
                       RigidTransform([link.length / 2, 0.0, 0.0]),
                       np.array(LINK_COLORS[k % len(LINK_COLORS)])))
    for body, shape, X_BG, rgba in shapes:
        plant.RegisterVisualGeometry(body, X_BG, shape, body.name() + "_visual", rgba)


def total_momentum(plant: MultibodyPlant, context: Context) -> np.ndarray:
    """The planar system's total momentum [h_A_z, h_L_x, h_L_y] about the world origin.

    Args:
        plant: The plant.
        context: Its context."""
    h = plant.CalcSpatialMomentumInWorldAboutPoint(context, np.zeros(3))
    return np.array([h.rotational()[2], h.translational()[0], h.translational()[1]])


def joint_damping(plant: MultibodyPlant, joint_v: np.ndarray) -> np.ndarray:
    """The joints' damping [N m s/rad] from the description (Drake applies it in the plant).

    Args:
        plant: The plant.
        joint_v: The joints' velocity indices (ArmCoordinates.joint_v)."""
    by_velocity = {plant.get_joint(j).velocity_start(): plant.get_joint(j)
                   for j in plant.GetJointIndices()
                   if plant.get_joint(j).num_velocities() == 1}
    return np.array([by_velocity[int(v)].default_damping() for v in joint_v])


def effort_limits(plant: MultibodyPlant, joint_v: np.ndarray) -> np.ndarray:
    """The effort limits [N m] of the joints' actuators (inf where one has none).

    Args:
        plant: The plant.
        joint_v: The joints' velocity indices (ArmCoordinates.joint_v)."""
    by_velocity = {plant.get_joint_actuator(a).joint().velocity_start():
                   plant.get_joint_actuator(a).effort_limit()
                   for a in plant.GetJointActuatorIndices()}
    return np.array([by_velocity.get(int(v), np.inf) for v in joint_v])
