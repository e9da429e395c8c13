"""The reduced model of any free-floating manipulator plant (planar, or spatial from a
description file), from the plant itself (docs/equations.md E5-E9). At zero momentum

    M(q) qddot + C'(q, qdot) qdot = tau,        M = H_mm - H_mb H_bb^-1 H_bm,

C' the Christoffel form of dM/dq, v_b = -H_bb^-1 H_bm qdot and the GJM
J_bar = J_m - J_b H_bb^-1 H_bm (world frame). H and dH/dq come from the kinematic tree by
a compiled kernel (kernels/spatial.py)."""
from typing import Optional, Tuple

import numpy as np
from pydrake.common.eigen_geometry import Quaternion
from pydrake.math import RotationMatrix
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import Frame

from dacph_drake.dynamics.inertial_parameters import InertialParameters
from dacph_drake.dynamics.kinematic_tree import KinematicTree
from dacph_drake.dynamics.plant import ArmCoordinates, joint_damping
from dacph_drake.kernels import spatial


class FloatingBaseModel:
    """Reduced model of a finalized free-floating plant (a free base and revolute joints).

    Args:
        plant: The finalized free-floating plant."""

    def __init__(self, plant: MultibodyPlant):
        self._plant = plant
        self._context = plant.CreateDefaultContext()
        self.coordinates = ArmCoordinates.FromPlant(plant)
        self.tree = KinematicTree.FromPlant(plant)
        self.parameters = InertialParameters(plant)
        self._inertial_parameters = self.parameters.FromContext(self._context)
        self._inertias = self.tree.Inertias(self._context)
        self._parameter_nodes = self.parameters.Nodes(self.tree)
        self._frames = {}

    @property
    def joint_damping(self) -> np.ndarray:
        """The description's joint damping b (n) [N m s/rad] (dynamics.ReducedModel)."""
        return joint_damping(self._plant, self.coordinates.joint_v)

    @property
    def inertial_parameters(self) -> np.ndarray:
        """The inertial parameters in use (InertialParameters; at first the plant's)."""
        return self._inertial_parameters

    def SetInertialParameters(self, pi: np.ndarray) -> None:
        """Evaluates with the bodies' inertias pi from now on (the plant is not changed).

        Args:
            pi: The inertial parameters (InertialParameters layout)."""
        pi = np.asarray(pi, float)
        if pi.tobytes() == self._inertial_parameters.tobytes():
            return
        self._inertial_parameters = pi.copy()
        mass, moment, inertia, reflected = (x.copy() for x in self._inertias)
        self.parameters.IntoTreeInertias(pi, self._parameter_nodes, mass, moment, inertia)
        self._inertias = (mass, moment, inertia, reflected)

    @property
    def num_joints(self) -> int:
        return self.coordinates.num_joints

    @property
    def plant(self) -> MultibodyPlant:
        return self._plant

    def FullPositions(self, q: np.ndarray, base_positions: Optional[np.ndarray] = None
                      ) -> np.ndarray:
        """The plant's position vector (ArmCoordinates.Positions).

        Args:
            q: The joint angles (n) [rad].
            base_positions: The base joint's own coordinates (default: the origin)."""
        return self.coordinates.Positions(q, base_positions)

    @property
    def kernel_tree(self) -> tuple:
        """The tree's arrays in kernels.spatial's argument order, then the inertias."""
        return (*self.tree.KernelArrays(), *self._inertias)

    def Evaluate(self, q: np.ndarray, derivatives: bool = True) -> tuple:
        """(M, dM, A = H_bb^-1 H_bm, dA/dq, poses X, subspaces S), the base at identity.

        Args:
            q: The joint angles (n) [rad].
            derivatives: Whether to compute dM and dA (zero otherwise)."""
        return spatial.reduced_model(*self.kernel_tree, np.asarray(q, float),
                                     derivatives)

    def MassMatrix(self, q: np.ndarray) -> np.ndarray:
        """M(q) = H_mm - H_mb H_bb^-1 H_bm (n x n).

        Args:
            q: The joint angles (n) [rad]."""
        return self.Evaluate(q, derivatives=False)[0]

    def MassMatrixAndDerivatives(self, q: np.ndarray
                                 ) -> Tuple[np.ndarray, np.ndarray]:
        """(M, dM), dM[k] = dM/dq_k (n x n x n):
        dM = dH_mm - dH_mb A - A^T dH_bm + A^T dH_bb A, A = H_bb^-1 H_bm.

        Args:
            q: The joint angles (n) [rad]."""
        M, dM = self.Evaluate(q)[:2]
        return M, dM

    def Coriolis(self, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
        """C'(q, qdot) (n x n), C'_ij = sum_k Gamma_ijk qdot_k, Gamma_ijk = (dM_ij/dq_k +
        dM_ik/dq_j - dM_jk/dq_i) / 2 (Mdot - 2 C' is skew).

        Args:
            q: The joint angles (n) [rad].
            qdot: The joint rates (n) [rad/s]."""
        return self.MassAndCoriolis(q, qdot)[1]

    def MassAndCoriolis(self, q: np.ndarray, qdot: np.ndarray
                        ) -> Tuple[np.ndarray, np.ndarray]:
        """(M(q), C'(q, qdot)), each n x n, from one evaluation.

        Args:
            q: The joint angles (n) [rad].
            qdot: The joint rates (n) [rad/s]."""
        M, dM = self.Evaluate(q)[:2]
        return M, spatial.christoffel(dM, np.asarray(qdot, float))

    def Momentum(self, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
        """p = M(q) qdot (n), the port's momentum.

        Args:
            q: The joint angles (n) [rad].
            qdot: The joint rates (n) [rad/s]."""
        return self.MassMatrix(q) @ np.asarray(qdot, float)

    def _BaseRotation(self, base_positions) -> np.ndarray:
        """R_WB of the base coordinates (free: quaternion first; planar: theta third)."""
        if base_positions is None:
            return np.eye(3)
        if self.tree.base_subspace.shape[1] == 3:
            return RotationMatrix.MakeZRotation(float(base_positions[2])).matrix()
        quaternion = np.asarray(base_positions[:4], float)
        return RotationMatrix(Quaternion(quaternion / np.linalg.norm(quaternion))
                              ).matrix()

    def BaseVelocity(self, q: np.ndarray, qdot: np.ndarray,
                     base_positions: Optional[np.ndarray] = None) -> np.ndarray:
        """v_b = -H_bb^-1 H_bm qdot (free: omega_W, v_W; planar: vx, vy, omega).

        Args:
            q: The joint angles (n) [rad].
            qdot: The joint rates (n) [rad/s].
            base_positions: The base joint's coordinates (default: the identity pose)."""
        R, Sb = self._BaseRotation(base_positions), self.tree.base_subspace
        twist = Sb @ (-self.Evaluate(q, derivatives=False)[2] @ np.asarray(qdot, float))
        twist = np.concatenate([R @ twist[:3], R @ twist[3:]])
        return Sb.T @ twist

    def FramePose(self, frame: Frame, evaluation: tuple,
                  base_positions: Optional[np.ndarray] = None) -> np.ndarray:
        """The orientation R_WF (3 x 3) of a plant frame in the world.

        Args:
            frame: A frame of the plant.
            evaluation: This model's Evaluate result at the joint angles.
            base_positions: The base joint's coordinates (default: the identity pose)."""
        node, X_CF = self.FrameNode(frame)
        return self._BaseRotation(base_positions) @ evaluation[4][node, :3, :3] @ X_CF[:3, :3]

    def FrameNode(self, frame: Frame) -> Tuple[int, np.ndarray]:
        """(node, X_CF (4 x 4)): a plant frame's node and its pose in that body (cached).

        Args:
            frame: A frame of the plant."""
        key = int(frame.index())
        if key not in self._frames:
            self._frames[key] = self.tree.Node(frame)
        return self._frames[key]

    def GeneralizedJacobian(self, q: np.ndarray, frame: Frame,
                            p_FoP_F: np.ndarray = np.zeros(3),
                            base_positions: Optional[np.ndarray] = None,
                            evaluation: Optional[tuple] = None) -> np.ndarray:
        """The GJM J_bar (6 x n) of a point P of a frame: [omega; v] of P = J_bar qdot.

        Args:
            q: The joint angles (n) [rad].
            frame: The frame P is fixed in.
            p_FoP_F: P's position in ``frame`` [m].
            base_positions: The base joint's coordinates (default: the identity pose).
            evaluation: This model's Evaluate(q), when the caller has it."""
        _, _, A, _, X, S = (self.Evaluate(q, derivatives=False) if evaluation is None
                            else evaluation)
        node, X_CF = self.FrameNode(frame)
        p_W = X[node, :3, :3] @ (X_CF[:3, :3] @ p_FoP_F + X_CF[:3, 3]) + X[node, :3, 3]
        J = spatial.point_jacobian(self.tree.base_subspace, self.tree.parent,
                                   self.tree.joint, X, S, A, node, p_W)
        R = self._BaseRotation(base_positions)
        return np.vstack([R @ J[:3], R @ J[3:]])


def arm_joints(model: FloatingBaseModel) -> list:
    """The plant's (pydrake) joints of an arm's joint angles q, in q's order.

    Args:
        model: The arm's model."""
    plant = model.plant
    joints = {plant.get_joint(j).position_start(): plant.get_joint(j)
              for j in plant.GetJointIndices() if plant.get_joint(j).num_positions() == 1}
    return [joints[int(i)] for i in model.coordinates.joint_q]
