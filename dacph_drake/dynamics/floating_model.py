"""The reduced model of any free-floating manipulator plant (planar, or spatial from a
description file), computed from the plant itself: at zero momentum the arm's
dynamics are the Euler-Lagrange equations of T = qdot^T M(q) qdot / 2 (docs/equations.md
E5-E9),

    M(q) qddot + C'(q, qdot) qdot = tau,

with M the Schur complement of the plant's mass matrix H over the base velocities,

    M = H_mm - H_mb H_bb^-1 H_bm,

C' in Christoffel form from dM/dq (AutoDiff of H, closed-form Schur derivative), the
base velocity implied by zero momentum v_b = -H_bb^-1 H_bm qdot, and the generalized
Jacobian (GJM) of any frame, J_bar = J_m - J_b H_bb^-1 H_bm. M and C' do not depend on
the base's pose (the base sits at the plant's default pose here); v_b and the GJM are
expressed in the world frame at the base pose given.

planar arms keep their closed-form, compiled ReducedOrderModel (reduced_model.py) on
the fast path; this model is the reference that holds for every robot, and the
planar model is tested against it."""
import numpy as np
from pydrake.autodiffutils import (AutoDiffXd, ExtractGradient, ExtractValue,
                                   InitializeAutoDiff)
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import JacobianWrtVariable, SpatialInertia_, UnitInertia_

from dacph_drake.dynamics.inertial_parameters import InertialParameters
from dacph_drake.dynamics.plant import ArmCoordinates


class FloatingBaseModel:
    """Reduced model of a finalized free-floating ``plant``; one scratch context
    (double and AutoDiff) made here and reused by every evaluation."""

    def __init__(self, plant: MultibodyPlant):
        self._plant = plant
        self._context = plant.CreateDefaultContext()
        self._ad_plant = plant.ToAutoDiffXd()
        self._ad_context = self._ad_plant.CreateDefaultContext()
        self.coordinates = ArmCoordinates.FromPlant(plant)
        n = self.num_joints
        self._selector = np.zeros((plant.num_positions(), n))   # d q_full / d q
        self._selector[self.coordinates.joint_q, np.arange(n)] = 1.0
        self.parameters = InertialParameters(plant)
        self._inertial_parameters = self.parameters.FromContext(self._context)

    @property
    def inertial_parameters(self) -> np.ndarray:
        """The bodies' inertial parameters this model evaluates with
        (inertial_parameters.InertialParameters layout; the plant's at first)."""
        return self._inertial_parameters

    def SetInertialParameters(self, pi: np.ndarray) -> None:
        """Evaluates with the bodies' inertias pi from now on (the controller's
        model error, scenario.DescribedArm.nominal_inertia_scale, or an
        InertialIdentifier's estimate); the plant itself is not changed."""
        pi = np.asarray(pi, float)
        if np.array_equal(pi, self._inertial_parameters):
            return
        self._inertial_parameters = pi.copy()
        self.parameters.Apply(self._context, pi)
        ad_bodies = [self._ad_plant.get_body(body.index()) for body in self.parameters.bodies]
        for body, inertia in zip(ad_bodies, self.parameters.SpatialInertias(pi)):
            G = inertia.get_unit_inertia()
            moments, products = G.get_moments(), G.get_products()
            ad = [AutoDiffXd(float(x)) for x in (*moments, *products)]
            body.SetSpatialInertiaInBodyFrame(self._ad_context, SpatialInertia_[AutoDiffXd](
                AutoDiffXd(inertia.get_mass()),
                np.array([AutoDiffXd(float(x)) for x in inertia.get_com()]),
                UnitInertia_[AutoDiffXd](*ad), True))

    @property
    def num_joints(self) -> int:
        return self.coordinates.num_joints

    @property
    def plant(self) -> MultibodyPlant:
        return self._plant

    def FullPositions(self, q, base_positions=None) -> np.ndarray:
        """The plant's positions: joints at q, the base at ``base_positions`` (the
        base joint's own coordinates; default: the origin), ArmCoordinates.Positions."""
        return self.coordinates.Positions(q, base_positions)

    def _Blocks(self, H: np.ndarray):
        b, m = self.coordinates.base_v, self.coordinates.joint_v
        return H[np.ix_(b, b)], H[np.ix_(b, m)], H[np.ix_(m, m)]

    def MassMatrix(self, q) -> np.ndarray:
        """M(q) = H_mm - H_mb H_bb^-1 H_bm (n x n)."""
        self._plant.SetPositions(self._context, self.FullPositions(q))
        Hbb, Hbm, Hmm = self._Blocks(self._plant.CalcMassMatrix(self._context))
        return Hmm - Hbm.T @ np.linalg.solve(Hbb, Hbm)

    def MassMatrixAndDerivatives(self, q):
        """(M, dM) with dM[k] = dM/dq_k (n x n x n), from the AutoDiff derivatives of
        H: dM = dH_mm - dH_mb A - A^T dH_bm + A^T dH_bb A, A = H_bb^-1 H_bm."""
        n = self.num_joints
        self._ad_plant.SetPositions(self._ad_context, InitializeAutoDiff(
            self.FullPositions(q), self._selector))
        H_ad = self._ad_plant.CalcMassMatrix(self._ad_context)
        H = ExtractValue(H_ad)
        N = H.shape[0]
        dH = ExtractGradient(H_ad.reshape(-1)).reshape(N, N, n).transpose(2, 0, 1)
        Hbb, Hbm, Hmm = self._Blocks(H)
        A = np.linalg.solve(Hbb, Hbm)
        M = Hmm - Hbm.T @ A
        dM = np.empty((n, n, n))
        for k in range(n):
            dbb, dbm, dmm = self._Blocks(dH[k])
            dM[k] = dmm - dbm.T @ A - A.T @ dbm + A.T @ dbb @ A
        return M, dM

    def Coriolis(self, q, qdot) -> np.ndarray:
        """C'(q, qdot) with C'_ij = sum_k Gamma_ijk qdot_k and
        Gamma_ijk = (dM_ij/dq_k + dM_ik/dq_j - dM_jk/dq_i) / 2, so that Mdot - 2 C'
        is skew-symmetric."""
        return self.MassAndCoriolis(q, qdot)[1]

    def MassAndCoriolis(self, q, qdot):
        """(M(q), C'(q, qdot)) from one AutoDiff evaluation of H."""
        M, dM = self.MassMatrixAndDerivatives(q)
        qdot = np.asarray(qdot, float)
        Mdot = np.tensordot(qdot, dM, axes=(0, 0))       # sum_k dM_ij/dq_k qdot_k
        second = np.einsum("jik,k->ij", dM, qdot)          # sum_k dM_ik/dq_j qdot_k
        third = np.einsum("ijk,k->ij", dM, qdot)           # sum_k dM_jk/dq_i qdot_k
        return M, 0.5 * (Mdot + second - third)

    def Momentum(self, q, qdot) -> np.ndarray:
        """p = M(q) qdot, the port's momentum at zero total momentum."""
        return self.MassMatrix(q) @ np.asarray(qdot, float)

    def BaseVelocity(self, q, qdot, base_positions=None) -> np.ndarray:
        """The base joint's velocities implied by zero momentum,
        v_b = -H_bb^-1 H_bm qdot, at the base pose given."""
        self._plant.SetPositions(self._context, self.FullPositions(q, base_positions))
        Hbb, Hbm, _ = self._Blocks(self._plant.CalcMassMatrix(self._context))
        return -np.linalg.solve(Hbb, Hbm @ np.asarray(qdot, float))

    def GeneralizedJacobian(self, q, frame, p_FoP_F=np.zeros(3),
                            base_positions=None) -> np.ndarray:
        """J_bar (6 x n) of point P fixed in ``frame``: [omega; v] of P in the world
        (Drake's order) = J_bar qdot at zero momentum."""
        self._plant.SetPositions(self._context, self.FullPositions(q, base_positions))
        Hbb, Hbm, _ = self._Blocks(self._plant.CalcMassMatrix(self._context))
        J = self._plant.CalcJacobianSpatialVelocity(
            self._context, JacobianWrtVariable.kV, frame, p_FoP_F,
            self._plant.world_frame(), self._plant.world_frame())
        b, m = self.coordinates.base_v, self.coordinates.joint_v
        return J[:, m] - J[:, b] @ np.linalg.solve(Hbb, Hbm)
