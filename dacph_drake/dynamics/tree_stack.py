"""A batch's controller plants as kernels/identification.py reads them: one topology, each
member's fixed transforms and inertias stacked along a first axis."""
from typing import Sequence

import numpy as np
from pydrake.multibody.plant import MultibodyPlant

from dacph_drake.dynamics.inertial_parameters import InertialParameters
from dacph_drake.dynamics.kinematic_tree import KinematicTree
from dacph_drake.kernels import identification


class TreeStack:
    """The members' plants (trials, or trials' model draws) as stacked kernel arrays.

    Args:
        plants: Each member's plant, all of one kinematic topology.

    Raises:
        ValueError: The plants differ in their kinematic tree's topology."""

    def __init__(self, plants: Sequence[MultibodyPlant]):
        trees = [KinematicTree.FromPlant(plant) for plant in plants]
        first = trees[0]
        for tree in trees[1:]:
            if not all(np.array_equal(a, b) for a, b in zip(
                    (tree.parent, tree.joint, tree.below, tree.base_subspace),
                    (first.parent, first.joint, first.below, first.base_subspace))):
                raise ValueError("the trials' arms differ in their kinematic tree")
        self.parameters = InertialParameters(plants[0])
        self.nodes = self.parameters.Nodes(first)
        self._topology = (first.base_subspace, first.parent, first.joint)
        self.X_PF, self._axis, self._X_MC = (
            np.array([getattr(tree, name) for tree in trees])
            for name in ("X_PF", "axis", "X_MC"))
        self._below, self._joint_below = first.below, first.joint_below
        fixed = [tree.Inertias(plant.CreateDefaultContext())
                 for tree, plant in zip(trees, plants)]
        self._inertias = tuple(np.array(x) for x in zip(*fixed))

    def __len__(self) -> int:
        return len(self.X_PF)

    def AddInformation(self, base_pose: np.ndarray, base_velocity: np.ndarray,
                       q: np.ndarray, qdot: np.ndarray, information: np.ndarray) -> None:
        """information[i] += vec(Y^T Y) at member i's measured state (in place).

        Args:
            base_pose: Each member's base pose (members, base positions).
            base_velocity: Each member's base velocity (members, base velocities).
            q: Each member's joint angles (members, n) [rad].
            qdot: Each member's joint rates (members, n) [rad/s].
            information: Each member's information (members, parameters^2)."""
        identification.add_momentum_information(
            *self._topology, self.X_PF, self._axis, self._X_MC, self._below,
            self.nodes, base_pose, base_velocity, q, qdot, information)

    def AddNoiseInformation(self, base_pose: np.ndarray, q: np.ndarray,
                            base_velocities: int, rate_columns: slice,
                            base_rate_variance: float, joint_rate_variance: float,
                            information: np.ndarray) -> None:
        """information[i] += sum_j sigma_j^2 vec(Y(q, e_j)^T Y(q, e_j)) (in place): what
        white noise of variance sigma_j^2 on velocity j adds to the information in
        expectation, the momentum being linear in the velocities (the base's rates in
        ``rate_columns`` at base_rate_variance, every joint rate at joint_rate_variance).

        Args:
            base_pose: Each member's base pose (members, base positions).
            q: Each member's joint angles (members, n) [rad].
            base_velocities: The size of a base velocity.
            rate_columns: The base velocity's noisy (gyro) columns.
            base_rate_variance: Their noise's variance [rad^2/s^2].
            joint_rate_variance: The joint rates' noise's variance [rad^2/s^2].
            information: Each member's information (members, parameters^2)."""
        members, n = q.shape
        still_base, still_joints = np.zeros((members, base_velocities)), np.zeros((members, n))
        if base_rate_variance > 0:
            for column in range(rate_columns.start, rate_columns.stop):
                unit = still_base.copy()
                unit[:, column] = np.sqrt(base_rate_variance)
                self.AddInformation(base_pose, unit, q, still_joints, information)
        if joint_rate_variance > 0:
            for joint in range(n):
                unit = still_joints.copy()
                unit[:, joint] = np.sqrt(joint_rate_variance)
                self.AddInformation(base_pose, still_base, q, unit, information)

    def ReducedMassMatrices(self, pis: np.ndarray, q: np.ndarray) -> np.ndarray:
        """M(q_i) with member i's bodies at pis[i] (non-finite where H_bb is not PD).

        Args:
            pis: Each member's inertial parameters (members, parameters).
            q: Each member's joint angles (members, n) [rad]."""
        return identification.reduced_mass_matrices(
            *self._topology, self.X_PF, self._axis, self._X_MC, self._below,
            self._joint_below, *self._inertias, self.nodes, pis, q)


def positive_definite(M: np.ndarray) -> np.ndarray:
    """Per matrix of the stack M: finite and positive definite.

    Args:
        M: A stack of symmetric matrices (k, n, n)."""
    finite = np.all(np.isfinite(M), axis=(1, 2))
    safe = np.where(finite[:, None, None], M, np.eye(M.shape[1]))
    return finite & (np.linalg.eigvalsh(safe)[:, 0] > 0)
