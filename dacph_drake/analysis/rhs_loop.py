"""The discrete RHS loop as a Drake LinearSystem, and its stability certificate (eqs.
45-48, docs/equations.md E37-E38, E45-E48). u_I(k+1) = u_I(k) + h K e(k), e(k) =
tau_c^r - tau_obs(k), tau_obs(k+1) = B u_I(k) (one sample late); with x = (u_I, tau_obs):

    x(k+1) = [[I, -h K], [B, 0]] x(k) + [[h K], [0]] tau_c^r
    e(k)   = [0, -I] x(k) + tau_c^r

and per mode p the polynomial z^2 - z + h k_p lambda_p; written in closed form, as
``Linearize`` needs AutoDiff, which the package's LeafSystems lack."""
from dataclasses import asdict, dataclass
from typing import Optional

import numpy as np
from pydrake.math import RealDiscreteLyapunovEquation
from pydrake.systems.primitives import LinearSystem

from dacph_drake.gain_rule import (certified_radius, decay_rate, delayed_loop_matrix,
                                   integral_gains, lag_pole, loop_matrix,
                                   separates_by_decay)
from dacph_drake.kernels.certificate import roots_within



def largest_tolerated_delay(B: np.ndarray, K: np.ndarray, period: float,
                            lag: float = 0.0, radius: Optional[float] = None,
                            limit: int = 400, start: int = 0) -> int:
    """The largest command delay D [samples] such that every delay from ``start`` to D
    keeps the RHS loop's spectral radius below ``radius`` (the certificate's by
    default; 1: stability), with the actuators' lag; start - 1 if ``start`` does
    not, ``limit`` if every delay up to it does. Per mode mu of h K B the loop's
    polynomial (kernels.certificate) has delayed_loop_matrix's eigenvalues as roots;
    the radius need not grow with d (a delay speeds the slow root a little), hence the
    scan from ``start`` up.

    Args:
        B: The port's input matrix (n x n).
        K: The integrator's gains (n).
        period: The RHS period h [s].
        lag: The actuators' time constant [s] (0: none).
        radius: The spectral radius the loop must stay below (None: the certificate's
            with the run's own delay, certified_radius(period, start, lag)).
        limit: The largest delay tried.
        start: The delay the scan starts from (the run's own)."""
    modes = np.linalg.eigvals(period * np.diag(K) @ B).astype(complex)
    pole = lag_pole(period, lag)
    if radius is None:
        radius = certified_radius(period, start, lag)
    for delay in range(start, limit + 1):
        if not all(roots_within(mu, delay, pole, radius) for mu in modes):
            return delay - 1
    return limit


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
        separation: sigma_rhs / lambda_LHS (eq. 45); with a delay or lag decay_rate /
            lambda_LHS.
        ok: Whether every check passed.
        reason: Why not ("; "-separated; "" when ok)."""
    spectral_radius: float
    margin: float                  # 1 - spectral radius
    decay_rate: float              # -ln(spectral radius) / h [1/s]
    lyapunov_P_min_eigenvalue: float
    lyapunov_residual: float       # ||A^T P A - P + I|| / ||P||
    dic_ok: bool                   # det B != 0 and Re(lambda_p) > 0
    sigma_rhs: float               # min_p k_p Re(lambda_p) [1/s]
    separation: float              # the separation / lambda_LHS (eq. 45)
    ok: bool
    reason: str

    def as_dict(self) -> dict:
        """This check as a plain dict (for JSON)."""
        return asdict(self)


def check_rhs_loop(B: np.ndarray, K: np.ndarray, period: float, lambda_lhs: float,
                   Td: float, delay: int = 0, lag: float = 0.0) -> RhsLoopCheck:
    """The RHS loop's certificate at one operating point: spectral radius <=
    certified_radius (1 - STABILITY_MARGIN without a delay or lag) and P > 0 from
    RealDiscreteLyapunovEquation(A, I); DIC; and sigma_RHS = min_p k_p Re(lambda_p) >=
    Td lambda_LHS (eq. 45), with a delay or lag the loop's decay rate -ln(rho) / h
    instead of sigma_RHS (gain_rule.separates_by_decay).

    Args:
        B: The port's input matrix (n x n): the learner's B_hat or the truth's B~.
        K: The integrator's gains (n).
        period: The RHS period h [s].
        lambda_lhs: The LHS rate lambda_LHS = 2 lambda_max(K_d) / inf lambda_min(M) [1/s].
        Td: The time-scale separation factor T_d.
        delay: The samples by which the command is late (sensing.rhs_delay + latency).
        lag: The actuators' time constant [s] (sensing.actuator_lag; 0: none)."""
    _, paired, dic_ok = integral_gains(B, 1.0)
    A = (delayed_loop_matrix(B, K, period, delay, lag) if delay or lag
         else rhs_loop_system(B, K, period).A())
    radius = float(np.max(np.abs(np.linalg.eigvals(A))))
    allowed = certified_radius(period, delay, lag)
    reasons = []
    if radius <= allowed:
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
                       f"{allowed:.4f} (period {period:g} s)")
    if not dic_ok:
        reasons.append("DIC violated: det(B_hat) = 0 or Re(lambda_hat_p) <= 0")
    sigma = float(np.min(np.asarray(K) * paired.real))
    decay = decay_rate(radius, period)
    by_decay = separates_by_decay(delay, lag)
    separation = (decay if by_decay else sigma) / lambda_lhs
    if not separation >= Td:
        rate = "the loop's decay rate" if by_decay else "sigma_RHS"
        reasons.append(f"time-scale separation {rate} / lambda_LHS = "
                       f"{separation:.3g} < T_d = {Td:g}")
    return RhsLoopCheck(
        spectral_radius=radius, margin=1.0 - radius, decay_rate=decay,
        lyapunov_P_min_eigenvalue=P_min, lyapunov_residual=residual,
        dic_ok=dic_ok, sigma_rhs=sigma, separation=separation,
        ok=not reasons, reason="; ".join(reasons))
