"""A free-floating plant's kinematic tree as plain arrays for kernels/spatial.py: parents
before children, node 0 the base (free or planar joint), each body on its inboard joint
(revolute or a weld), X_WC = X_WP X_PF Rot(axis, q_j) X_MC; joints in actuator order.
Inertias and reflected inertias rho^2 I_r are not part of the tree (Inertias)."""
from dataclasses import dataclass
from typing import Tuple

import numpy as np
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import BodyIndex, Frame, RevoluteJoint
from pydrake.systems.framework import Context

from dacph_drake.dynamics.plant import ArmCoordinates


def _Matrix(X) -> np.ndarray:
    return X.GetAsMatrix4()


@dataclass
class KinematicTree:
    """A free-floating plant's kinematic tree as arrays.

    Attributes:
        bodies: The plant's bodies, in node order.
        base_subspace: The base velocities' motion subspace (6, base velocities).
        parent: Each node's parent node (nodes,), -1 for the base.
        joint: The joint moving each node (nodes,) (0..n-1), -1 for a weld.
        X_PF: Each inboard joint's frame F in its parent's frame (nodes, 4, 4).
        axis: Each joint's unit axis in F (nodes, 3) (zero for a weld).
        X_MC: Each body's frame C in its joint's moving frame M (nodes, 4, 4).
        below: True where joint k moves the node (n, nodes).
        joint_below: True where joint k moves joint j's axis (j != k) (n, n).
        joint_node: The node each joint moves (n,).
        actuators: (joint, actuator) of every actuator on a joint of the tree."""
    bodies: list
    base_subspace: np.ndarray
    parent: np.ndarray
    joint: np.ndarray
    X_PF: np.ndarray
    axis: np.ndarray
    X_MC: np.ndarray
    below: np.ndarray
    joint_below: np.ndarray
    joint_node: np.ndarray
    actuators: list

    @staticmethod
    def FromPlant(plant: MultibodyPlant) -> "KinematicTree":
        """The tree of a finalized free-floating plant.

        Args:
            plant: A finalized plant with a free base and revolute joints (and welds).

        Raises:
            ValueError: Not such a plant (free or planar base, revolute joints, welds)."""
        coordinates = ArmCoordinates.FromPlant(plant)
        joint_of_velocity = {int(v): j for j, v in enumerate(coordinates.joint_v)}
        inboard = {}
        for index in plant.GetJointIndices():
            joint = plant.get_joint(index)
            inboard[int(joint.child_body().index())] = joint
        world = int(plant.world_body().index())
        order, node_of = [], {}
        on_world = [joint for joint in inboard.values()
                    if int(joint.parent_body().index()) == world]
        base_joint = on_world[0]
        if base_joint.num_velocities() == 6:
            base_subspace = np.eye(6)
        elif base_joint.type_name() == "planar":
            base_subspace = np.zeros((6, 3))
            base_subspace[3, 0] = base_subspace[4, 1] = base_subspace[2, 2] = 1.0
        else:
            raise ValueError(f"base joint {base_joint.name()!r}: "
                             f"{base_joint.type_name()}; allowed: free or planar")
        frontier = [int(base_joint.child_body().index())]
        children = {}
        for child, joint in inboard.items():
            children.setdefault(int(joint.parent_body().index()), []).append(child)
        while frontier:
            body = frontier.pop(0)
            node_of[body] = len(order)
            order.append(body)
            frontier += sorted(children.get(body, []))
        nodes = len(order)
        n = coordinates.num_joints
        parent = np.full(nodes, -1)
        joint_index = np.full(nodes, -1)
        X_PF = np.tile(np.eye(4), (nodes, 1, 1))
        axis = np.zeros((nodes, 3))
        X_MC = np.tile(np.eye(4), (nodes, 1, 1))
        for node, body in enumerate(order[1:], start=1):
            joint = inboard[body]
            if int(joint.parent_body().index()) == world:
                raise ValueError("one body on the world: the free base")
            parent[node] = node_of[int(joint.parent_body().index())]
            X_PF[node] = _Matrix(joint.frame_on_parent().GetFixedPoseInBodyFrame())
            X_MC[node] = np.linalg.inv(
                _Matrix(joint.frame_on_child().GetFixedPoseInBodyFrame()))
            if isinstance(joint, RevoluteJoint):
                joint_index[node] = joint_of_velocity[joint.velocity_start()]
                axis[node] = joint.revolute_axis()
            elif joint.num_velocities() == 0:
                X_PF[node] = X_PF[node] @ _Matrix(joint.X_FM())
            else:
                raise ValueError(f"joint {joint.name()!r}: {joint.type_name()}; the "
                                 "kinematic tree has revolute joints and welds")
        below = np.zeros((n, nodes), bool)
        for node in range(1, nodes):
            ancestor = node
            while ancestor > 0:
                if joint_index[ancestor] >= 0:
                    below[joint_index[ancestor], node] = True
                ancestor = parent[ancestor]
        joint_node = np.zeros(n, int)
        for node in range(nodes):
            if joint_index[node] >= 0:
                joint_node[joint_index[node]] = node
        joint_below = below[:, joint_node].copy()
        joint_below[np.arange(n), np.arange(n)] = False
        return KinematicTree(
            bodies=[plant.get_body(BodyIndex(b)) for b in order],
            base_subspace=base_subspace, parent=parent,
            joint=joint_index, X_PF=X_PF, axis=axis, X_MC=X_MC, below=below,
            joint_below=joint_below, joint_node=joint_node,
            actuators=[(joint_of_velocity[actuator.joint().velocity_start()], actuator)
                       for actuator in (plant.get_joint_actuator(i)
                                        for i in plant.GetJointActuatorIndices())
                       if actuator.joint().velocity_start() in joint_of_velocity])

    def KernelArrays(self) -> tuple:
        """The tree's arrays in kernels.spatial's argument order (the inertias follow)."""
        return (self.base_subspace, self.parent, self.joint, self.X_PF, self.axis,
                self.X_MC, self.below, self.joint_below)

    def Inertias(self, context: Context
                 ) -> Tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(mass (nodes,), m c (nodes, 3), inertia about the origin (nodes, 3, 3), reflected
        rho^2 I_r (n,) [kg m^2]) as the plant holds them in a context, in each body's frame.

        Args:
            context: A context of the plant."""
        nodes = len(self.bodies)
        mass, moment, inertia = np.zeros(nodes), np.zeros((nodes, 3)), np.zeros((nodes, 3, 3))
        for node, body in enumerate(self.bodies):
            M = body.CalcSpatialInertiaInBodyFrame(context)
            mass[node] = M.get_mass()
            moment[node] = M.get_mass() * M.get_com()
            inertia[node] = M.CalcRotationalInertia().CopyToFullMatrix3()
        reflected = np.zeros(len(self.joint_node))
        for joint, actuator in self.actuators:
            reflected[joint] += actuator.calc_reflected_inertia(context)
        return mass, moment, inertia, reflected

    def Node(self, frame: Frame) -> Tuple[int, np.ndarray]:
        """(node, X_CF (4 x 4)): a plant frame's body's node and its pose in that body.

        Args:
            frame: A frame of the plant."""
        body = frame.body()
        node = next(k for k, b in enumerate(self.bodies) if b.index() == body.index())
        return node, _Matrix(frame.GetFixedPoseInBodyFrame())
