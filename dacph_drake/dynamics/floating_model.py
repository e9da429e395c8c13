"""The reduced model of any free-floating manipulator plant (planar, or spatial from a
description file), computed from the plant itself: at zero momentum the arm's
dynamics are the Euler-Lagrange equations of T = qdot^T M(q) qdot / 2 (docs/equations.md
E5-E9),

    M(q) qddot + C'(q, qdot) qdot = tau,

with M the Schur complement of the plant's mass matrix H over the base velocities,

    M = H_mm - H_mb H_bb^-1 H_bm,

C' in Christoffel form from dM/dq (closed-form Schur derivative), the
base velocity implied by zero momentum v_b = -H_bb^-1 H_bm qdot, and the generalized
Jacobian (GJM) of any frame, J_bar = J_m - J_b H_bb^-1 H_bm. M and C' do not depend on
the base's pose (the base sits at the plant's default pose here); v_b and the GJM are
expressed in the world frame at the base pose given.

H and dH/dq come from the plant's kinematic tree (kinematic_tree.KinematicTree) by a
compiled kernel (kernels/spatial.py: composite inertias and their rotation about
each joint's axis), about 16 us for 6 joints where Drake's AutoDiff of H took 320
us; tests/test_spatial.py checks them against Drake's CalcMassMatrix and its
AutoDiff derivatives. Planar arms keep their closed-form, compiled
ReducedOrderModel (reduced_model.py) on the fast path; this model holds for every
robot, and the planar model is tested against it."""
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
    """Reduced model of a finalized free-floating plant.

    The plant's moving joints are its free base and revolute joints; a scratch
    context of the plant holds the inertias it evaluates with.

    Args:
        plant: The finalized free-floating plant.
    """

    def __init__(self, plant: MultibodyPlant):
        self._plant = plant
        self._context = plant.CreateDefaultContext()
        self.coordinates = ArmCoordinates.FromPlant(plant)
        self.tree = KinematicTree.FromPlant(plant)
        self.parameters = InertialParameters(plant)
        self._inertial_parameters = self.parameters.FromContext(self._context)
        self._inertias = self.tree.Inertias(self._context)
        self._frames = {}

    @property
    def joint_damping(self) -> np.ndarray:
        """The description's joint damping b (n) [N m s/rad] (dynamics.ReducedModel)."""
        return joint_damping(self._plant, self.coordinates.joint_v)

    @property
    def inertial_parameters(self) -> np.ndarray:
        """The bodies' inertial parameters this model evaluates with
        (inertial_parameters.InertialParameters layout; the plant's at first)."""
        return self._inertial_parameters

    def SetInertialParameters(self, pi: np.ndarray) -> None:
        """Evaluates with the bodies' inertias pi from now on.

        The plant itself is not changed.

        Args:
            pi: The bodies' inertial parameters (InertialParameters layout): the
                controller's model error, scenario.DescribedArm.nominal_inertia_scale,
                or an InertialIdentifier's estimate.
        """
        pi = np.asarray(pi, float)
        if np.array_equal(pi, self._inertial_parameters):
            return
        self._inertial_parameters = pi.copy()
        self.parameters.Apply(self._context, pi)
        self._inertias = self.tree.Inertias(self._context)

    @property
    def num_joints(self) -> int:
        return self.coordinates.num_joints

    @property
    def plant(self) -> MultibodyPlant:
        return self._plant

    def FullPositions(self, q: np.ndarray, base_positions: Optional[np.ndarray] = None
                      ) -> np.ndarray:
        """The plant's positions (ArmCoordinates.Positions).

        Args:
            q: The joint angles (n) [rad].
            base_positions: The base joint's own coordinates (default: the origin).

        Returns:
            The plant's position vector, the joints at q and the base at
                ``base_positions``."""
        return self.coordinates.Positions(q, base_positions)

    @property
    def kernel_tree(self) -> tuple:
        """The tree's arrays in kernels.spatial's argument order, then the inertias."""
        return (*self.tree.KernelArrays(), *self._inertias)

    def Evaluate(self, q: np.ndarray, derivatives: bool = True) -> tuple:
        """The reduced model and its kinematics, the base at the identity pose.

        Computed by kernels.spatial.reduced_model.

        Args:
            q: The joint angles (n) [rad].
            derivatives: Whether to compute dM and dA (zero otherwise).

        Returns:
            (M, dM, A = H_bb^-1 H_bm, dA = dA/dq, X (body poses), S (joint motion
                subspaces))."""
        return spatial.reduced_model(*self.kernel_tree, np.asarray(q, float),
                                     derivatives)

    def MassMatrix(self, q: np.ndarray) -> np.ndarray:
        """M(q) = H_mm - H_mb H_bb^-1 H_bm.

        Args:
            q: The joint angles (n) [rad].

        Returns:
            M(q) (n x n)."""
        return self.Evaluate(q, derivatives=False)[0]

    def MassMatrixAndDerivatives(self, q: np.ndarray
                                 ) -> Tuple[np.ndarray, np.ndarray]:
        """M and its derivatives by the joint angles.

        dM = dH_mm - dH_mb A - A^T dH_bm + A^T dH_bb A, A = H_bb^-1 H_bm.

        Args:
            q: The joint angles (n) [rad].

        Returns:
            (M, dM) with dM[k] = dM/dq_k (n x n x n)."""
        M, dM = self.Evaluate(q)[:2]
        return M, dM

    def Coriolis(self, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
        """C'(q, qdot) in Christoffel form.

        C'_ij = sum_k Gamma_ijk qdot_k and
        Gamma_ijk = (dM_ij/dq_k + dM_ik/dq_j - dM_jk/dq_i) / 2, so that Mdot - 2 C'
        is skew-symmetric.

        Args:
            q: The joint angles (n) [rad].
            qdot: The joint rates (n) [rad/s].

        Returns:
            C' (n x n)."""
        return self.MassAndCoriolis(q, qdot)[1]

    def MassAndCoriolis(self, q: np.ndarray, qdot: np.ndarray
                        ) -> Tuple[np.ndarray, np.ndarray]:
        """M(q) and C'(q, qdot) from one evaluation.

        Args:
            q: The joint angles (n) [rad].
            qdot: The joint rates (n) [rad/s].

        Returns:
            (M(q), C'(q, qdot)), each n x n."""
        M, dM = self.Evaluate(q)[:2]
        return M, spatial.christoffel(dM, np.asarray(qdot, float))

    def Momentum(self, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
        """p = M(q) qdot, the port's momentum at zero total momentum.

        Args:
            q: The joint angles (n) [rad].
            qdot: The joint rates (n) [rad/s].

        Returns:
            p (n)."""
        return self.MassMatrix(q) @ np.asarray(qdot, float)

    def _BaseRotation(self, base_positions) -> np.ndarray:
        """R_WB of the base joint's coordinates (identity for None): a free base's
        quaternion (qw, qx, qy, qz, ...) or a planar base's angle (x, y, theta)."""
        if base_positions is None:
            return np.eye(3)
        if self.tree.base_subspace.shape[1] == 3:
            return RotationMatrix.MakeZRotation(float(base_positions[2])).matrix()
        quaternion = np.asarray(base_positions[:4], float)
        return RotationMatrix(Quaternion(quaternion / np.linalg.norm(quaternion))
                              ).matrix()

    def BaseVelocity(self, q: np.ndarray, qdot: np.ndarray,
                     base_positions: Optional[np.ndarray] = None) -> np.ndarray:
        """The base joint's velocities implied by zero momentum.

        v_b = -H_bb^-1 H_bm qdot, at the base pose given.

        Args:
            q: The joint angles (n) [rad].
            qdot: The joint rates (n) [rad/s].
            base_positions: The base joint's coordinates (default: the identity pose).

        Returns:
            v_b (a free base's omega_W, v_W; a planar base's vx, vy, omega)."""
        R, Sb = self._BaseRotation(base_positions), self.tree.base_subspace
        twist = Sb @ (-self.Evaluate(q, derivatives=False)[2] @ np.asarray(qdot, float))
        twist = np.concatenate([R @ twist[:3], R @ twist[3:]])
        return Sb.T @ twist

    def FramePose(self, frame: Frame, evaluation: tuple,
                  base_positions: Optional[np.ndarray] = None) -> np.ndarray:
        """The orientation of a plant frame in the world.

        Args:
            frame: A frame of the plant.
            evaluation: This model's Evaluate result at the joint angles.
            base_positions: The base joint's coordinates (default: the identity pose).

        Returns:
            R_WF (3 x 3)."""
        node, X_CF = self.FrameNode(frame)
        return self._BaseRotation(base_positions) @ evaluation[4][node, :3, :3] @ X_CF[:3, :3]

    def FrameNode(self, frame: Frame) -> Tuple[int, np.ndarray]:
        """Where a plant frame sits in the kinematic tree (cached).

        Args:
            frame: A frame of the plant.

        Returns:
            (node, X_CF), its body's node and its pose in that body (4 x 4)."""
        key = int(frame.index())
        if key not in self._frames:
            self._frames[key] = self.tree.Node(frame)
        return self._frames[key]

    def GeneralizedJacobian(self, q: np.ndarray, frame: Frame,
                            p_FoP_F: np.ndarray = np.zeros(3),
                            base_positions: Optional[np.ndarray] = None,
                            evaluation: Optional[tuple] = None) -> np.ndarray:
        """The generalized Jacobian J_bar of a point P fixed in a frame.

        [omega; v] of P in the world (Drake's order) = J_bar qdot at zero momentum.

        Args:
            q: The joint angles (n) [rad].
            frame: The frame P is fixed in.
            p_FoP_F: P's position in ``frame`` [m].
            base_positions: The base joint's coordinates (default: the identity pose).
            evaluation: This model's Evaluate(q), when the caller has it.

        Returns:
            J_bar (6 x n)."""
        _, _, A, _, X, S = (self.Evaluate(q, derivatives=False) if evaluation is None
                            else evaluation)
        node, X_CF = self.FrameNode(frame)
        p_W = X[node, :3, :3] @ (X_CF[:3, :3] @ p_FoP_F + X_CF[:3, 3]) + X[node, :3, 3]
        J = spatial.point_jacobian(self.tree.base_subspace, self.tree.parent,
                                   self.tree.joint, X, S, A, node, p_W)
        R = self._BaseRotation(base_positions)
        return np.vstack([R @ J[:3], R @ J[3:]])
