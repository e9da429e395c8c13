"""The ground-truth free-floating arm as a Drake MultibodyPlant (SPEC section 1).

Bodies: ``base`` on a PlanarJoint ``base_joint`` (x, y, theta0) w.r.t. the world;
``link1`` ... ``linkn`` on RevoluteJoints ``q1`` ... ``qn`` about +z, each driven by an
actuator ``tau1`` ... ``taun`` (the base is not actuated); gravity is zero. The frame
``end_effector`` sits at the far end of the last link.

Continuous time by default (time_step = 0): measured in scripts/bench.py over 20 s of
free flight, the continuous plant under fixed-step Runge-Kutta 3 at 0.25 ms keeps the
total momentum at ~1e-13, while Drake's discrete plant (semi-implicit) at the same step
drifts to ~1e-5. The discrete controllers already stop the integrator at every RHS
sample, so the continuous plant costs no more steps than a discrete one would.
"""
from dataclasses import dataclass
from typing import List

import numpy as np
from pydrake.geometry import Box, SceneGraph
from pydrake.math import RigidTransform
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph, MultibodyPlant
from pydrake.multibody.tree import (FixedOffsetFrame, PlanarJoint,
                                    RevoluteJoint, RotationalInertia,
                                    SpatialInertia)
from pydrake.systems.framework import DiagramBuilder

from dacph_drake.robot import RobotParams

BASE_JOINT = "base_joint"
END_EFFECTOR = "end_effector"
GEOMETRY_DEPTH = 0.05  # extent of the boxes along z [m]; does not enter the dynamics


def joint_name(k: int) -> str:
    """Name of the k-th arm joint, k = 0 .. n-1 (the paper's q_{k+1})."""
    return f"q{k + 1}"


def link_name(k: int) -> str:
    return f"link{k + 1}"


@dataclass
class ArmCoordinates:
    """Where the base and the joints sit in a plant's q and v vectors.

    ``base_v`` lists the PlanarJoint's velocities (vx, vy, omega0) in the world frame,
    ``joint_v`` the arm's joint rates qdot; likewise ``base_q`` / ``joint_q``.
    """
    base_q: np.ndarray
    base_v: np.ndarray
    joint_q: np.ndarray
    joint_v: np.ndarray

    @staticmethod
    def FromPlant(plant: MultibodyPlant) -> "ArmCoordinates":
        base = plant.GetJointByName(BASE_JOINT)
        n = plant.num_actuators()
        joints = [plant.GetJointByName(joint_name(k)) for k in range(n)]
        return ArmCoordinates(
            base_q=np.arange(base.position_start(), base.position_start() + 3),
            base_v=np.arange(base.velocity_start(), base.velocity_start() + 3),
            joint_q=np.array([j.position_start() for j in joints]),
            joint_v=np.array([j.velocity_start() for j in joints]))

    @property
    def num_joints(self) -> int:
        return len(self.joint_v)


def AddFreeFloatingArm(builder: DiagramBuilder, robot: RobotParams,
                       time_step: float = 0.0) -> "tuple[MultibodyPlant, SceneGraph]":
    """Adds the finalized arm plant, with visual geometry registered with a
    SceneGraph (for Meshcat), to ``builder``; continuous unless ``time_step`` > 0.

    No collision geometry: the arm in free flight never touches its base in a
    runnable scenario (the potential field keeps it off), and contact queries cost
    30 % of the plant's derivative evaluation. A run is stopped with a named reason
    when the links' kinematic clearance from the base reaches zero
    (run._Simulate), and the start is checked (diagrams._RequireRunnableStart)."""
    robot.Validate()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, time_step=time_step)
    _PopulateArm(plant, robot)
    plant.Finalize()
    return plant, scene_graph


def MakeArmPlant(robot: RobotParams) -> MultibodyPlant:
    """A finalized arm plant without geometry, for a controller's internal model."""
    robot.Validate()
    plant = MultibodyPlant(time_step=0.0)
    _PopulateArm(plant, robot)
    plant.Finalize()
    return plant


def _PopulateArm(plant: MultibodyPlant, robot: RobotParams) -> None:
    base = robot.base
    base_body = plant.AddRigidBody("base", SpatialInertia.MakeFromCentralInertia(
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
        body = plant.AddRigidBody(link_name(k), SpatialInertia.MakeFromCentralInertia(
            link.mass, [link.com, 0.0, 0.0],
            RotationalInertia(link.inertia - along, along, link.inertia)))
        joint = plant.AddJoint(RevoluteJoint(
            joint_name(k), parent_frame, body.body_frame(), [0.0, 0.0, 1.0]))
        plant.AddJointActuator(f"tau{k + 1}", joint)
        parent_frame = plant.AddFrame(FixedOffsetFrame(
            END_EFFECTOR if k == robot.num_links - 1 else f"elbow{k + 1}",
            body.body_frame(), RigidTransform([link.length, 0.0, 0.0])))
        bodies.append(body)
    plant.mutable_gravity_field().set_gravity_vector(np.zeros(3))
    if plant.geometry_source_is_registered():
        _RegisterGeometry(plant, robot, bodies)


def _RegisterGeometry(plant: MultibodyPlant, robot: RobotParams, bodies: List) -> None:
    shapes = [(bodies[0], Box(robot.base.size, robot.base.size, GEOMETRY_DEPTH),
               RigidTransform(), np.array([0.75, 0.75, 0.8, 1.0]))]
    for k, link in enumerate(robot.links):
        shapes.append((bodies[k + 1], Box(link.length, link.width, GEOMETRY_DEPTH),
                       RigidTransform([link.length / 2, 0.0, 0.0]),
                       np.array([0.85, 0.45, 0.1, 1.0]) if k % 2 == 0
                       else np.array([0.2, 0.45, 0.8, 1.0])))
    for body, shape, X_BG, rgba in shapes:
        plant.RegisterVisualGeometry(body, X_BG, shape, body.name() + "_visual", rgba)


def total_momentum(plant: MultibodyPlant, context) -> np.ndarray:
    """[h_A_z, h_L_x, h_L_y]: the system's angular momentum about the world origin
    and its linear momentum (paper eq. for h_L, h_A); the other three components of
    a planar system's spatial momentum are identically zero."""
    h = plant.CalcSpatialMomentumInWorldAboutPoint(context, np.zeros(3))
    return np.array([h.rotational()[2], h.translational()[0], h.translational()[1]])
