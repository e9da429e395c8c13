"""Region-of-attraction certificates for the LHS sliding dynamics, by sums of squares
(Drake's ``RegionOfAttraction``, Clarabel).

Planar model (its assumptions are part of the certificate): frozen q, nu = 0, exact RHS
(e_tau = 0), tanh(x) replaced by x - x^3 / 3,

    M(q) sdot = -C'(q, s) s - K_d s - chi (s / epsilon - (s / epsilon)^3 / 3),
    C'(q, s) = sum_k s_k Gamma_k(q);

{V <= rho}, V = s^T M(q) s / 2, contains ||s|| <= sqrt(2 rho / lambda_max(M(q))).

A spatial arm's LHS (K_d = damping_rate M(q)) drops chi tanh(w_i s_i) (too steep for
a polynomial; it only lowers dV/dt). With s = M^-1/2 w r, ||w|| = 1 (V = r^2 / 2),

    dV/dt = -damping_rate r^2 - c(w) r^3,   c(w) = s^T C'(q, s) s at r = 1,

so {V < rho}, rho = (damping_rate / gamma)^2 / 2, holds for any gamma >= max_{|w|=1} c(w),
bounded by a small SOS program on the sphere (cubic_maximum_on_sphere)."""
import multiprocessing
from dataclasses import asdict, dataclass

import numpy as np
from pydrake.solvers import ClarabelSolver, MathematicalProgram
from pydrake.symbolic import Evaluate as EvaluateExpression
from pydrake.symbolic import MakeVectorVariable, Variables
from pydrake.systems.analysis import (RegionOfAttraction,
                                      RegionOfAttractionOptions)
from pydrake.systems.primitives import SymbolicVectorSystem

from dacph_drake.dynamics.floating_model import FloatingBaseModel
from dacph_drake.dynamics.reduced_model import ReducedOrderModel


@dataclass
class RegionCertificate:
    """A region-of-attraction certificate {V(s) <= rho} of the sliding dynamics.

    Attributes:
        q: The frozen configuration q [rad].
        rho: The certified level of V = s^T M s / 2 [J].
        radius: A ball ||s|| <= radius inside the region [rad/s].
        assumptions: The polynomial model's assumptions (part of the certificate).
        skipped: Why no certificate was computed (the budget), or ""."""
    q: list
    rho: float                      # level of V = s^T M s / 2 [J]
    radius: float                   # a ball ||s|| <= radius inside the region [rad/s]
    assumptions: str
    skipped: str = ""               # why no certificate was computed (budget), or ""

    def as_dict(self) -> dict:
        """This certificate as a plain dict (for JSON)."""
        return asdict(self)

    def Contains(self, s0_norm: float) -> bool:
        """Whether the ball this certificate gives holds s(0): s0_norm <= radius.

        Args:
            s0_norm: ||s(0)|| [rad/s]."""
        return s0_norm <= self.radius


@dataclass
class MovingConfigurationCertificate:
    """The spatial LHS's region of attraction with nothing frozen: every s. With C' the
    Christoffel form of dM, Mdot - 2 C' is skew, so along eq. E26 (any nu, q, s)

        M sdot = -C'(q, qdot) s - damping_rate M s - b s - chi tanh(w s) + e_tau,
        dV/dt = -2 damping_rate V - s^T b s - chi sum_i s_i tanh(w_i s_i)
                <= -2 damping_rate V        (e_tau = 0),

    resting on C'(q, e_k) + C'(q, e_k)^T = dM/dq_k, checked by central differences
    (FD_STEP) at q0 and sampled configurations.

    Attributes:
        configurations: How many configurations were checked.
        residual: max |C'_k + C'_k^T - dM/dq_k| / max |M| over them [-].
        tolerance: The residual allowed [-].
        frozen_radius: The frozen-configuration certificate's ball at q0 [rad/s].
        assumptions: The model's assumptions (part of the certificate).
        skipped: Always "" (nothing is budgeted)."""
    configurations: int
    residual: float
    tolerance: float
    frozen_radius: float
    assumptions: str
    skipped: str = ""

    def as_dict(self) -> dict:
        """This certificate as a plain dict (for JSON)."""
        return {"region": "every s", **asdict(self)}

    def Contains(self, s0_norm: float) -> bool:
        """Whether s(0) is in the region: every s is when residual <= tolerance.

        Args:
            s0_norm: ||s(0)|| [rad/s] (any)."""
        return self.residual <= self.tolerance


ASSUMPTIONS = ("frozen configuration q; nu = 0; e_tau = 0; tanh replaced by its "
               "cubic Taylor polynomial; candidate V = s^T M(q) s / 2")


# The wall time the planar arm's sums-of-squares program in s may take [s] (dacph
# verify --region-budget): it grows steeply with the number of joints.
REGION_BUDGET = 300.0


def sliding_region_of_attraction(model: ReducedOrderModel, q: np.ndarray, Kd: float,
                                 chi: float, epsilon: float,
                                 budget: float = REGION_BUDGET) -> RegionCertificate:
    """The planar LHS's certificate: K_d = Kd I, tanh(s / epsilon); past ``budget`` rho and
    radius are nan and ``skipped`` says why.

    Args:
        model: The controller's reduced model.
        q: The frozen configuration [rad] (n).
        Kd: The LHS damping K_d = Kd I.
        chi: The robust term's gain chi.
        epsilon: The boundary layer's thickness.
        budget: The wall time the sums-of-squares program may take [s]."""
    n = model.num_joints
    M = model.Evaluate(q, np.zeros(n)).M
    Gamma = [model.Evaluate(q, np.eye(n)[k]).C for k in range(n)]
    return _BudgetedRegion(budget, q, M, Gamma, Kd * np.eye(n), chi,
                           np.full(n, 1.0 / epsilon))


SPATIAL_ASSUMPTIONS = ("frozen configuration q; nu = 0; e_tau = 0; the robust term "
                       "dropped (dissipative for every chi); candidate "
                       "V = s^T M(q) s / 2")


def attitude_region_of_attraction(model: FloatingBaseModel, q: np.ndarray,
                                  damping_rate: float) -> RegionCertificate:
    """A spatial arm's LHS's certificate for every chi (module docstring).

    Args:
        model: The arm's model (floating_model.FloatingBaseModel).
        q: The frozen configuration [rad] (n).
        damping_rate: The LHS's damping rate [1/s]."""
    n = model.num_joints
    M = model.MassMatrix(q)
    Gamma = np.array([model.Coriolis(q, np.eye(n)[k]) for k in range(n)])
    eigenvalues, eigenvectors = np.linalg.eigh(M)
    L = eigenvectors @ np.diag(eigenvalues**-0.5) @ eigenvectors.T      # M^-1/2
    # c(w) = sum_abc T_abc w_a w_b w_c: s_k s^T Gamma_k s with s = L w.
    T = np.einsum("kij,ka,ib,jc->abc", Gamma, L, L, L)
    gamma = cubic_maximum_on_sphere(T)
    rho = 0.5 * (damping_rate / gamma)**2 if gamma > 0 else float("inf")
    return RegionCertificate(q=[float(v) for v in q], rho=rho,
                             radius=float(np.sqrt(2 * rho / eigenvalues[-1])),
                             assumptions=SPATIAL_ASSUMPTIONS)


MOVING_ASSUMPTIONS = ("the configuration moving (any nu); e_tau = 0 (the envelope "
                      "check bounds it); the robust term and b dropped (dissipative for "
                      "every chi); candidate V = s^T M(q) s / 2; Mdot = C' + C'^T")
FD_STEP = 1e-6                 # central-difference step of dM/dq [rad]
SKEW_TOLERANCE = 1e-6          # relative residual of C' + C'^T = Mdot allowed
SKEW_CONFIGURATIONS = 16       # q0 and random configurations checked


def moving_region_of_attraction(model: FloatingBaseModel, q0: np.ndarray,
                                damping_rate: float) -> MovingConfigurationCertificate:
    """The spatial LHS's certificate with nothing frozen (MovingConfigurationCertificate).

    Args:
        model: The arm's model (floating_model.FloatingBaseModel).
        q0: The run's start [rad] (n).
        damping_rate: The LHS's damping rate [1/s] (for the frozen certificate)."""
    n = model.num_joints
    samples = np.random.default_rng(0).uniform(-np.pi, np.pi,
                                               (SKEW_CONFIGURATIONS - 1, n))
    residual = 0.0
    for q in [np.asarray(q0, float), *samples]:
        scale = float(np.abs(model.MassMatrix(q)).max())
        for k in range(n):
            step = FD_STEP * np.eye(n)[k]
            dM = (model.MassMatrix(q + step) - model.MassMatrix(q - step)) / (2 * FD_STEP)
            C = model.Coriolis(q, np.eye(n)[k])
            residual = max(residual, float(np.abs(C + C.T - dM).max()) / scale)
    frozen = attitude_region_of_attraction(model, np.asarray(q0, float), damping_rate)
    return MovingConfigurationCertificate(
        configurations=SKEW_CONFIGURATIONS, residual=residual, tolerance=SKEW_TOLERANCE,
        frozen_radius=frozen.radius, assumptions=MOVING_ASSUMPTIONS)


def cubic_maximum_on_sphere(T: np.ndarray) -> float:
    """An upper bound gamma of max_{|w| = 1} sum_abc T_abc w_a w_b w_c: the least gamma with
    gamma - c(w) = sigma(w) + lambda(w) (|w|^2 - 1), sigma SOS (degree 4), lambda of degree
    2, raised by the solver's tolerance (1e-7 relative).

    Args:
        T: The cubic form's coefficients (n x n x n).

    Raises:
        RuntimeError: The sums-of-squares program failed."""
    n = T.shape[0]
    program = MathematicalProgram()
    w = program.NewIndeterminates(n, "w")
    gamma = program.NewContinuousVariables(1, "gamma")[0]
    multiplier = program.NewFreePolynomial(Variables(w), 2).ToExpression()
    with np.errstate(invalid="ignore", divide="ignore"):
        cubic = np.einsum("abc,a,b,c->", T, w, w, w)
        program.AddSosConstraint(gamma - cubic - multiplier * (w.dot(w) - 1.0))
    program.AddLinearCost(gamma)
    result = ClarabelSolver().Solve(program)
    if not result.is_success():
        raise RuntimeError("the sums-of-squares bound of the Coriolis cubic failed: "
                           f"{result.get_solution_result()}")
    value = float(result.GetSolution(gamma))
    return value + 1e-7 * max(abs(value), float(np.abs(T).max()))


def _BudgetedRegion(budget: float, q, *arguments) -> RegionCertificate:
    """_Region in its own process, stopped after ``budget`` s: then no region, and why."""
    context = multiprocessing.get_context("spawn")
    with context.Pool(1) as pool:      # leaving the block terminates the worker
        pending = pool.apply_async(_Region, (q, *arguments))
        try:
            return pending.get(timeout=budget)
        except multiprocessing.TimeoutError:
            return RegionCertificate(
                q=[float(v) for v in q], rho=float("nan"), radius=float("nan"),
                assumptions=ASSUMPTIONS,
                skipped=f"the sums-of-squares program for {len(q)} joints did not finish "
                        f"within the budget of {budget:g} s (dacph verify "
                        "--region-budget)")


def _Region(q, M, Gamma, K_d, chi: float, weights) -> RegionCertificate:
    """The certificate for M sdot = -C'(q, s) s - K_d s - chi (x - x^3 / 3),
    x = weights * s, C'(q, s) = sum_k s_k Gamma[k]."""
    n = M.shape[0]
    s = MakeVectorVariable(n, "s")
    # numpy's object-array arithmetic on symbolic expressions reports stale
    # floating-point status flags as warnings; nothing numeric happens here.
    with np.errstate(invalid="ignore", divide="ignore"):
        x = s * weights
        C_s = sum(s[k] * Gamma[k] for k in range(n))
        force = C_s @ s + K_d @ s + chi * (x - x**3 / 3)
        dynamics = -np.linalg.solve(M, np.eye(n)) @ force
        V = 0.5 * s.dot(M @ s)
    system = SymbolicVectorSystem(state=s, dynamics=dynamics)
    options = RegionOfAttractionOptions()
    options.lyapunov_candidate = V
    options.state_variables = s
    options.solver_id = ClarabelSolver.id()
    scaled = RegionOfAttraction(system, system.CreateDefaultContext(), options)
    probe = {s[0]: 1.0, **{s[k]: 0.0 for k in range(1, n)}}
    rho = float(EvaluateExpression([V], probe)[0, 0]
                / EvaluateExpression([scaled], probe)[0, 0])
    radius = float(np.sqrt(2 * rho / np.max(np.linalg.eigvalsh(M))))
    return RegionCertificate(q=[float(v) for v in q], rho=rho, radius=radius,
                             assumptions=ASSUMPTIONS)
