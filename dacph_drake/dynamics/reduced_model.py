"""Reduced-order port-Hamiltonian model of a planar free-floating arm (section "Modeling",
docs/equations.md E7-E20). At zero momentum, with the base unactuated,

    qdot0 = -H_bb^-1 H_bm qdot                         (paper: qdot0 = -H_q0^-1 H_q qdot)
    M(q) = H_mm - H_bm^T H_bb^-1 H_bm                  (paper: M(q), reduced mass matrix)

with H the full mass matrix, velocities (vx, vy, omega0, qdot). Each entry of H is a sum
of 1, cos(s_r), sin(s_r) over the joint-angle sums s_r = q_a + ... + q_b, fitted to
CalcMassMatrix to round-off, so H and dH/dq are exact and closed-form."""
from dataclasses import dataclass

import numpy as np
from pydrake.autodiffutils import ExtractGradient, InitializeAutoDiff
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import Frame, JacobianWrtVariable

from dacph_drake.dynamics.inertial_parameters import InertialParameters
from dacph_drake.dynamics.plant import (ArmCoordinates, END_EFFECTOR, joint_damping,
                                        link_name)

@dataclass(slots=True)
class ReducedDynamics:
    """The reduced model at one state (q, qdot), in the paper's symbols.

    Attributes:
        M: M(q), n x n, symmetric positive definite.
        Mdot: dM/dt = sum_k dM/dq_k qdot_k.
        dM: dM[k] = dM/dq_k, shape (n, n, n).
        C: C'(q, p) in Christoffel form, C_ij = sum_k Gamma_ijk qdot_k with
            Gamma_ijk = (dM_ij/dq_k + dM_ik/dq_j - dM_jk/dq_i) / 2: Mdot - 2 C' is skew.
        dH_dq: dH/dq at fixed p = -(Mdot - C') qdot = -(1/2) qdot^T (dM/dq_i) qdot.
        D: The task Jacobian D(q), 1 x n as a vector: alpha_dot = D qdot.
        dD: dD[k] = dD/dq_k, shape (n, n).
        base_velocity_map: -H_bb^-1 H_bm (3 x n), qdot -> (vx, vy, omega0) at theta0 = 0."""
    M: np.ndarray
    Mdot: np.ndarray
    dM: np.ndarray
    C: np.ndarray
    dH_dq: np.ndarray
    D: np.ndarray
    dD: np.ndarray
    base_velocity_map: np.ndarray


class ReducedOrderModel:
    """Evaluates the reduced model of a planar arm's plant (one scratch context, reused).

    Args:
        plant: An arm built by dynamics/plant.py.

    Raises:
        ValueError: Not a planar revolute chain in dynamics/plant.py's velocity layout."""

    def __init__(self, plant: MultibodyPlant):
        self._plant = plant
        self._context = plant.CreateDefaultContext()
        coordinates = ArmCoordinates.FromPlant(plant)
        n = coordinates.num_joints
        if not (np.array_equal(coordinates.base_v, np.arange(3))
                and np.array_equal(coordinates.joint_v, np.arange(3, 3 + n))):
            raise ValueError("ReducedOrderModel needs the base joint's velocities "
                             "first and the arm joints after them (dynamics/plant.py's layout)")
        self._num_joints = n
        self._coordinates = coordinates
        self._ones = np.ones(n)
        self._W = np.vstack([np.zeros((3, n)), np.eye(n)])
        self._ee_frame = plant.GetFrameByName(END_EFFECTOR)
        self._link_bodies = [plant.GetBodyByName(link_name(k)) for k in range(n)]
        self._FitTrigonometricCoefficients()

    @property
    def plant(self) -> MultibodyPlant:
        return self._plant

    @property
    def inertial_parameters(self) -> np.ndarray:
        """The model's inertial parameters pi (InertialParameters' layout), its plant's."""
        return InertialParameters(self._plant).FromContext(self._context)

    @property
    def joint_damping(self) -> np.ndarray:
        """The plant's joint damping b (n) [N m s/rad] (dynamics.ReducedModel)."""
        return joint_damping(self._plant, self._coordinates.joint_v)

    @property
    def num_joints(self) -> int:
        return self._num_joints

    @property
    def trigonometric_representation(self):
        """(coefficients, ranges) of H(q) = coefficients psi(q), for kernels.arm."""
        return self._coefficients, self._ranges

    def CoefficientBasis(self, parameters: InertialParameters) -> np.ndarray:
        """The trigonometric coefficients, linear in pi: coefficients(pi) = tensordot(pi,
        basis, 1), basis (parameters.size, N*N, 1 + 2R).

        Args:
            parameters: The InertialParameters of this model's plant."""
        context = self._plant.CreateDefaultContext()
        samples = []
        for q in self._fit_samples:
            self._plant.SetPositions(context, self._coordinates.Positions(q))
            samples.append(parameters.MassMatrixBasis(context).reshape(parameters.size, -1))
        samples = np.array(samples)                                    # (S, P, N*N)
        return np.einsum("rs,spe->per", self._fit_operator, samples)

    def WithInertialParameters(self, parameters: InertialParameters, pi: np.ndarray
                               ) -> "ReducedOrderModel":
        """A copy whose M, C', D use the inertial parameters pi (same plant and GJMs).

        Args:
            parameters: The InertialParameters layout of this model's plant.
            pi: The bodies' inertial parameters, e.g. an InertialIdentifier's estimate."""
        copy = object.__new__(ReducedOrderModel)
        copy.__dict__.update(self.__dict__)
        copy._coefficients = np.tensordot(pi, self.CoefficientBasis(parameters), 1)
        return copy

    def _FullMassMatrix(self, q_full: np.ndarray) -> np.ndarray:
        self._plant.SetPositions(self._context, q_full)
        return self._plant.CalcMassMatrix(self._context)

    def _Basis(self, q: np.ndarray) -> np.ndarray:
        """[psi, dpsi/dq_1..n] of psi = (1, cos s_r, sin s_r), (1 + 2R, 1 + n)."""
        trig = np.sin(self._phase_ranges @ q + self._phase_offsets)
        basis = self._basis_buffer
        half = len(trig) // 2
        basis[1:, 0] = trig[:half]
        basis[1:, 1:] = trig[half:, None] * self._derivative_mask
        return basis

    def _MassMatrixAndDerivatives(self, q: np.ndarray):
        """[H, dH/dq_1, ..., dH/dq_n] (1 + n, N, N) in closed form, base pose at zero."""
        N = self._num_joints + 3
        return (self._coefficients @ self._Basis(q)).T.reshape(-1, N, N)

    def _FitTrigonometricCoefficients(self) -> None:
        n = self._num_joints
        self._ranges = np.array([[1.0 if a <= k <= b else 0.0 for k in range(n)]
                                 for a in range(n) for b in range(a, n)])
        R = len(self._ranges)
        self._phase_ranges = np.vstack([self._ranges] * 4)
        self._phase_offsets = np.repeat([np.pi / 2, 0.0, np.pi, np.pi / 2], R)
        self._derivative_mask = np.vstack([self._ranges] * 2)
        self._basis_buffer = np.zeros((1 + 2 * R, 1 + n))
        self._basis_buffer[0, 0] = 1.0
        rng = np.random.default_rng(0)
        samples = rng.uniform(-np.pi, np.pi, (4 * (1 + 2 * R) + 8, n))
        fit, check = samples[:-8], samples[-8:]

        def full_mass_matrix(q):
            return self._FullMassMatrix(self._coordinates.Positions(q)).reshape(-1)

        Psi = np.array([self._Basis(q)[:, 0].copy() for q in fit])
        H = np.array([full_mass_matrix(q) for q in fit])
        self._fit_samples = fit
        self._fit_operator = np.linalg.pinv(Psi)                       # (1+2R, S)
        self._coefficients = (self._fit_operator @ H).T                 # (N*N, 1+2R)
        scale = np.max(np.abs(H))
        error = max(np.max(np.abs(self._MassMatrixAndDerivatives(q)[0].reshape(-1)
                                  - full_mass_matrix(q))) for q in check)
        error = max(error, self._DerivativeErrorAgainstAutoDiff(check[0]))
        if error > 1e-10 * scale:
            raise ValueError(
                "the plant's mass matrix is not a trigonometric sum over consecutive "
                f"joint-angle ranges (error {error:.2e}); ReducedOrderModel supports "
                "planar chains of revolute joints only")

    def _DerivativeErrorAgainstAutoDiff(self, q: np.ndarray) -> float:
        ad_plant = self._plant.ToAutoDiffXd()
        ad_context = ad_plant.CreateDefaultContext()
        ad_plant.SetPositions(ad_context,
                              InitializeAutoDiff(self._coordinates.Positions(q)))
        H_ad = ad_plant.CalcMassMatrix(ad_context)
        N = H_ad.shape[0]
        dH_ad = ExtractGradient(H_ad.reshape(-1))[:, 3:].T.reshape(-1, N, N)
        return float(np.max(np.abs(self._MassMatrixAndDerivatives(q)[1:] - dH_ad)))

    def MassMatrix(self, q: np.ndarray) -> np.ndarray:
        """M(q) = H_mm - H_bm^T H_bb^-1 H_bm (n x n).

        Args:
            q: The joint angles (n) [rad]."""
        H = self._MassMatrixAndDerivatives(q)[0]
        return H[3:, 3:] - H[:3, 3:].T @ np.linalg.solve(H[:3, :3], H[:3, 3:])

    def MassMatrixAndDerivatives(self, q: np.ndarray
                                 ) -> "tuple[np.ndarray, np.ndarray]":
        """(M, dM) with dM[k] = dM/dq_k (n x n x n).

        Args:
            q: The joint angles (n) [rad]."""
        dynamics = self.Evaluate(q, np.zeros(self._num_joints))
        return dynamics.M, dynamics.dM

    def Evaluate(self, q: np.ndarray, qdot: np.ndarray) -> ReducedDynamics:
        """The reduced model at (q, qdot) (ReducedDynamics).

        Args:
            q: The joint angles (n) [rad].
            qdot: The joint rates (n) [rad/s]."""
        n = self._num_joints
        H_and_dH = self._MassMatrixAndDerivatives(q)
        H = H_and_dH[0]
        Hbb_inv = np.linalg.inv(H[:3, :3])
        A = Hbb_inv @ H[:3, 3:]
        # With W = [-A; I]: M = W^T H W and dM/dq_k = W^T (dH/dq_k) W (the derivative
        # of the Schur complement); dA/dq_k = H_bb^-1 [dH_bb/dq_k, dH_bm/dq_k] W.
        W = self._W
        W[:3] = -A
        HW = H_and_dH @ W
        M_and_dM = W.T @ HW
        M, dM = M_and_dM[0], M_and_dM[1:]
        dA_omega = Hbb_inv[2] @ HW[1:, :3, :]          # d(row omega0 of A)/dq_k
        # G[i, j] = sum_k dM_jk/dq_i qdot_k
        G = dM @ qdot
        Mdot = (qdot @ dM.reshape(n, n * n)).reshape(n, n)
        C = 0.5 * (Mdot + G.T - G)
        return ReducedDynamics(M=M, Mdot=Mdot, dM=dM, C=C, dH_dq=-0.5 * G @ qdot,
                               D=self._ones - A[2], dD=-dA_omega,
                               base_velocity_map=-A)

    def BaseVelocity(self, q_full: np.ndarray, qdot: np.ndarray) -> np.ndarray:
        """qdot0 = -H_bb^-1 H_bm qdot at zero momentum: (vx, vy, omega0), world.

        Args:
            q_full: The plant's positions (base pose included).
            qdot: The joint rates (n) [rad/s]."""
        H = self._FullMassMatrix(q_full)
        return -np.linalg.solve(H[:3, :3], H[:3, 3:] @ qdot)

    def GeneralizedJacobian(self, q_full: np.ndarray, frame: Frame,
                            p_FoP_F: np.ndarray = np.zeros(3)) -> np.ndarray:
        """J_bar (6 x n) = J_k - H_k H_q0^-1 H_q of a point P: [omega; v] = J_bar qdot.

        Args:
            q_full: The plant's positions (base pose included).
            frame: The frame P is fixed in.
            p_FoP_F: P's position in ``frame`` [m]."""
        H = self._FullMassMatrix(q_full)
        J = self._plant.CalcJacobianSpatialVelocity(
            self._context, JacobianWrtVariable.kV, frame, p_FoP_F,
            self._plant.world_frame(), self._plant.world_frame())
        return J[:, 3:] - J[:, :3] @ np.linalg.solve(H[:3, :3], H[:3, 3:])

    def EndEffectorJacobian(self, q_full: np.ndarray) -> np.ndarray:
        """GJM J_bar (6 x n) of the end effector; its omega_z row is D(q).

        Args:
            q_full: The plant's positions (base pose included)."""
        return self.GeneralizedJacobian(q_full, self._ee_frame)

    def LinkJacobians(self, q_full: np.ndarray) -> list:
        """GJM of each link's centre of mass, [J_bar_1, ..., J_bar_n], each 6 x n.

        Args:
            q_full: The plant's positions (base pose included)."""
        return [self.GeneralizedJacobian(q_full, body.body_frame(),
                                         body.default_com())
                for body in self._link_bodies]

    def EndEffectorAngle(self, q_full: np.ndarray) -> float:
        """alpha = theta0 + q1 + ... + qn, the end effector's unwrapped angle [rad].

        Args:
            q_full: The plant's positions."""
        theta0 = q_full[self._coordinates.base_q[2]]
        return float(theta0 + np.sum(q_full[self._coordinates.joint_q]))

    def Momentum(self, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
        """p = M(q) qdot (n).

        Args:
            q: The joint angles (n) [rad].
            qdot: The joint rates (n) [rad/s]."""
        return self.MassMatrix(q) @ qdot

    def Hamiltonian(self, q: np.ndarray, p: np.ndarray) -> float:
        """The kinetic energy H(q, p) = p^T M^-1(q) p / 2 [J].

        Args:
            q: The joint angles (n) [rad].
            p: The momentum (n)."""
        return 0.5 * float(p @ np.linalg.solve(self.MassMatrix(q), p))


_MASS_MATRIX_BOUNDS = {}      # (trigonometric coefficients, grid) -> bounds


# The largest arm whose bounds come from the grid (its cost grows as 73^n): larger
# arms' bounds are searched (inertia_bound.search_mass_matrix_bounds).
GRID_JOINTS = 2


def mass_matrix_bounds(model: ReducedOrderModel, samples_per_joint: int = 73
                       ) -> "tuple[float, float]":
    """(inf_q lambda_min(M), sup_q lambda_max(M)): by grid up to GRID_JOINTS, else searched.

    Args:
        model: The arm's reduced model.
        samples_per_joint: The grid's points per joint."""
    key = (model._coefficients.tobytes(), model._coefficients.shape, samples_per_joint)
    if key not in _MASS_MATRIX_BOUNDS:
        if model.num_joints <= GRID_JOINTS:
            _MASS_MATRIX_BOUNDS[key] = grid_mass_matrix_bounds(model, samples_per_joint)
        else:
            from dacph_drake.dynamics.inertia_bound import search_mass_matrix_bounds
            _MASS_MATRIX_BOUNDS[key] = search_mass_matrix_bounds(model)
    return _MASS_MATRIX_BOUNDS[key]


def grid_mass_matrix_bounds(model: ReducedOrderModel, samples_per_joint: int = 73
                            ) -> "tuple[float, float]":
    """(min lambda_min(M), max lambda_max(M)) over a grid of [-pi, pi)^n.

    Args:
        model: The arm's reduced model.
        samples_per_joint: The grid's points per joint."""
    n = model.num_joints
    axes = [np.linspace(-np.pi, np.pi, samples_per_joint, endpoint=False)] * n
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, n)
    lo, hi = np.inf, 0.0
    for q in grid:
        eig = np.linalg.eigvalsh(model.MassMatrix(q))
        lo, hi = min(lo, eig[0]), max(hi, eig[-1])
    return float(lo), float(hi)
