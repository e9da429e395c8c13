"""The discrete RHS loop as a Drake LinearSystem, and its stability certificate (eqs.
45-48, docs/equations.md E37-E38, E45-E48). u_I(k+1) = u_I(k) + h K e(k), e(k) =
tau_c^r - tau_obs(k), tau_obs(k+1) = B u_I(k) (one sample late); with x = (u_I, tau_obs):

    x(k+1) = [[I, -h K], [B, 0]] x(k) + [[h K], [0]] tau_c^r
    e(k)   = [0, -I] x(k) + tau_c^r

and per mode p the polynomial z^2 - z + h k_p lambda_p; written in closed form, as
``Linearize`` needs AutoDiff, which the package's LeafSystems lack."""
from dataclasses import asdict, dataclass

import numpy as np
from pydrake.math import RealDiscreteLyapunovEquation
from pydrake.systems.primitives import LinearSystem

from dacph_drake.gain_rule import STABILITY_MARGIN, integral_gains, loop_matrix



def rhs_loop_system(B: np.ndarray, K: np.ndarray, period: float) -> LinearSystem:
    """The closed discrete RHS loop as a LinearSystem: tau_c^r in, e_tau out, period h.

    Args:
        B: The port's input matrix (n x n).
        K: The integrator's gains (n).
        period: The RHS period h [s]."""
    n = B.shape[0]
    A = loop_matrix(B, K, period)
    B_in = np.vstack([period * np.diag(K), np.zeros((n, n))])
    C = np.hstack([np.zeros((n, n)), -np.eye(n)])
    return LinearSystem(A, B_in, C, np.eye(n), time_period=period)


@dataclass
class RhsLoopCheck:
    """The RHS loop's certificate at one operating point (check_rhs_loop).

    Attributes:
        spectral_radius: The discrete loop's spectral radius.
        margin: 1 - spectral radius.
        decay_rate: -ln(spectral radius) / h [1/s].
        lyapunov_P_min_eigenvalue: The least eigenvalue of P (nan: the radius check failed).
        lyapunov_residual: ||A^T P A - P + I|| / ||P||.
        dic_ok: det B != 0 and Re(lambda_p) > 0.
        sigma_rhs: min_p k_p Re(lambda_p) [1/s].
        separation: sigma_rhs / lambda_LHS (eq. 45).
        ok: Whether every check passed.
        reason: Why not ("; "-separated; "" when ok)."""
    spectral_radius: float
    margin: float                  # 1 - spectral radius
    decay_rate: float              # -ln(spectral radius) / h [1/s]
    lyapunov_P_min_eigenvalue: float
    lyapunov_residual: float       # ||A^T P A - P + I|| / ||P||
    dic_ok: bool                   # det B != 0 and Re(lambda_p) > 0
    sigma_rhs: float               # min_p k_p Re(lambda_p) [1/s]
    separation: float              # sigma_rhs / lambda_LHS (eq. 45)
    ok: bool
    reason: str

    def as_dict(self) -> dict:
        """This check as a plain dict (for JSON)."""
        return asdict(self)


def check_rhs_loop(B: np.ndarray, K: np.ndarray, period: float, lambda_lhs: float,
                   Td: float) -> RhsLoopCheck:
    """The RHS loop's certificate at one operating point: spectral radius <= 1 -
    STABILITY_MARGIN and P > 0 from RealDiscreteLyapunovEquation(A, I); DIC; and
    sigma_RHS = min_p k_p Re(lambda_p) >= Td lambda_LHS (eq. 45).

    Args:
        B: The port's input matrix (n x n): the learner's B_hat or the truth's B~.
        K: The integrator's gains (n).
        period: The RHS period h [s].
        lambda_lhs: The LHS rate lambda_LHS = 2 lambda_max(K_d) / inf lambda_min(M) [1/s].
        Td: The time-scale separation factor T_d."""
    _, paired, dic_ok = integral_gains(B, 1.0)
    A = rhs_loop_system(B, K, period).A()
    radius = float(np.max(np.abs(np.linalg.eigvals(A))))
    reasons = []
    if radius <= 1.0 - STABILITY_MARGIN:
        P = RealDiscreteLyapunovEquation(A, np.eye(A.shape[0]))
        P_min = float(np.min(np.linalg.eigvalsh(0.5 * (P + P.T))))
        residual = float(np.linalg.norm(A.T @ P @ A - P + np.eye(A.shape[0]))
                         / np.linalg.norm(P))
        if not P_min > 0:
            reasons.append(f"Lyapunov certificate P not positive definite "
                           f"(min eigenvalue {P_min:.3g})")
    else:
        P_min, residual = float("nan"), float("nan")
        reasons.append(f"discrete RHS loop spectral radius {radius:.4f} > "
                       f"{1 - STABILITY_MARGIN:.2f} (period {period:g} s)")
    if not dic_ok:
        reasons.append("DIC violated: det(B_hat) = 0 or Re(lambda_hat_p) <= 0")
    sigma = float(np.min(np.asarray(K) * paired.real))
    separation = sigma / lambda_lhs
    if not separation >= Td:
        reasons.append(f"time-scale separation sigma_RHS / lambda_LHS = "
                       f"{separation:.3g} < T_d = {Td:g}")
    return RhsLoopCheck(
        spectral_radius=radius, margin=1.0 - radius,
        decay_rate=float(-np.log(radius) / period) if radius > 0 else float("inf"),
        lyapunov_P_min_eigenvalue=P_min, lyapunov_residual=residual,
        dic_ok=dic_ok, sigma_rhs=sigma, separation=separation,
        ok=not reasons, reason="; ".join(reasons))
