"""The RHS gain rule (paper eqs. 45-48, docs/equations.md E45-E48) and its discrete-time
realizability check."""
from functools import lru_cache
from typing import Tuple, Union

import numpy as np

from dacph_drake.kernels.certificate import lag_weight, mode_radius
from dacph_drake.scenario.errors import ConfigError
from dacph_drake.scenario import Periods

# With the observer's one-sample delay the discrete RHS loop per mode is
# z^2 - z + g = 0, g = h k_p lambda_p; its roots are real (well damped) for g <= 1/4.
WELL_DAMPED_LOOP_GAIN = 0.25
# A certified loop without a delay or lag keeps its spectral radius at most
# 1 - STABILITY_MARGIN (certified_radius; analysis.rhs_loop).
STABILITY_MARGIN = 0.05


def c_lower_bound(Td: float, Kd_max: float, lambda_min_M: float, beta_hat: float) -> float:
    """The RHS decay rate's lower bound c_min [1/s] of eq. (48):

    c_min = 2 Td^2 lambda_max(K_d) / inf_q lambda_min(M) (1 + ln(beta_hat) / 5).

    Args:
        Td: The time-scale separation factor T_d.
        Kd_max: lambda_max(K_d) of the LHS damping.
        lambda_min_M: inf_q lambda_min(M).
        beta_hat: The learner's uncertainty estimate (< 1: 1; an array: a bound each)."""
    return 2 * Td**2 * Kd_max / lambda_min_M * (1 + np.log(np.maximum(beta_hat, 1.0)) / 5)


def inertia_scaled_c_lower_bound(Td: float, damping_rate: float, beta_hat: float) -> float:
    """c_min [1/s] of eq. (48) for an LHS damping K_d = damping_rate M(q): then
    2 lambda_max(K_d) / inf_q lambda_min(M) is exactly 2 damping_rate, so
    c > 2 Td^2 damping_rate (1 + ln(beta_hat) / 5) whatever the arm's inertia.

    Args:
        Td: The time-scale separation factor T_d.
        damping_rate: The LHS's damping rate [1/s].
        beta_hat: The learner's uncertainty estimate."""
    return c_lower_bound(Td, damping_rate, 1.0, beta_hat)


def integral_gains(B_hat: np.ndarray, c: Union[float, np.ndarray]
                   ) -> Tuple[np.ndarray, np.ndarray, Union[bool, np.ndarray]]:
    """The decentralized integral gains k_p = c / Re(lambda_hat_p) and the DIC check:
    (k, the paired eigenvalues, dic_ok), per trial for a stack; dic_ok says det(B_hat) != 0
    and Re(lambda_p) > 0 (else k is nan). Channel p is paired, in channel order, with the
    free eigenvalue nearest B_hat[p, p].

    Args:
        B_hat: The estimated input matrix (n x n), or a stack (trials, n, n).
        c: The decay rate [1/s] (per trial for a stack)."""
    n = B_hat.shape[-1]
    stack = np.reshape(B_hat, (-1, n, n))
    eigenvalues = np.linalg.eigvals(stack)
    rows = np.arange(len(stack))
    paired = np.empty_like(eigenvalues)
    free = np.ones(eigenvalues.shape, bool)
    for p in range(n):
        distance = np.where(free, np.abs(eigenvalues - stack[:, p, p, None]), np.inf)
        nearest = np.argmin(distance, axis=1)
        paired[:, p] = eigenvalues[rows, nearest]
        free[rows, nearest] = False
    eigenvalues, paired = (x.reshape(B_hat.shape[:-1]) for x in (eigenvalues, paired))
    det = np.prod(eigenvalues, axis=-1).real
    dic_ok = (np.abs(det) > 1e-9) & np.all(paired.real > 0, axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        k = np.where(dic_ok[..., None], np.asarray(c, float)[..., None] / paired.real,
                     np.nan)
    return k, paired, (bool(dic_ok) if dic_ok.ndim == 0 else dic_ok)


def lag_pole(period: float, lag: float) -> float:
    """The pole a = exp(-h / lag) of a first-order actuator lag sampled every h under a
    held command, s(k+1) = a s(k) + (1 - a) u(k); 0 without a lag.

    Args:
        period: The RHS period h [s].
        lag: The actuators' time constant [s] (0: none)."""
    return float(np.exp(-period / lag)) if lag > 0 else 0.0


def best_damped_gain(period: float, delay: int = 0, lag: float = 0.0) -> Tuple[float, float]:
    """(g*, the radius there): the loop gain mu = h k_p lambda_p that minimizes the mode's
    largest root modulus with the command ``delay`` samples late and the actuators'
    ``lag`` (kernels.certificate's polynomial; golden-section search on (0, 1]). Without
    either, g* = 1/4 (WELL_DAMPED_LOOP_GAIN: z^2 - z + 1/4 = (z - 1/2)^2). The
    fastest decay any gain gives the loop is -ln(radius) / h: a separation
    Td lambda_LHS beyond it cannot be met with this delay and lag.

    Args:
        period: The RHS period h [s].
        delay: The samples by which the command is late.
        lag: The actuators' time constant [s] (0: none)."""
    pole = lag_pole(period, lag)
    low, high = 1e-6, 1.0
    ratio = 0.5 * (np.sqrt(5.0) - 1.0)
    for _ in range(80):
        a, b = high - ratio * (high - low), low + ratio * (high - low)
        if mode_radius(complex(a), delay, pole) <= mode_radius(complex(b), delay, pole):
            high = b
        else:
            low = a
    gain = 0.5 * (low + high)
    return gain, mode_radius(complex(gain), delay, pole)


def well_damped_loop_gain(period: float, delay: int = 0, lag: float = 0.0) -> float:
    """The loop gain h c the RHS loop is best damped at: WELL_DAMPED_LOOP_GAIN without a
    delay or lag, else best_damped_gain's g*. The integrator's rate stays at most g* / h
    (stability first: with a delay or a lag the separation of eq. 45 may then be
    missed, which verify reports).

    Args:
        period: The RHS period h [s].
        delay: The samples by which the command is late.
        lag: The actuators' time constant [s] (0: none)."""
    if delay == 0 and lag == 0:
        return WELL_DAMPED_LOOP_GAIN
    return best_damped_gain(period, delay, lag)[0]


def decay_rate(radius: float, period: float) -> float:
    """The decay rate -ln(rho) / h [1/s] of a discrete loop of spectral radius rho
    sampled every h [s] (inf for rho = 0).

    Args:
        radius: The spectral radius rho.
        period: The sample period h [s]."""
    return float(-np.log(radius) / period) if radius > 0 else float("inf")


@lru_cache(maxsize=64)
def certified_radius(period: float, delay: int = 0, lag: float = 0.0) -> float:
    """The largest spectral radius the RHS loop's certificate allows, 1 - m: the margin
    m is the share STABILITY_MARGIN / (1 - 1/2) of the best margin any loop gain gives,
    1 - r* (best_damped_gain), so 1 - STABILITY_MARGIN without a delay or lag (r* = 1/2,
    z^2 - z + 1/4) and the same tenth of the best with them. A margin per sample is not
    the loop's to keep whatever the delay and lag: a first-order lag's own pole,
    exp(-h / lag), is above 0.95 for a lag above 20 h, and no gain brings the loop's
    radius below it; the rate the loop must keep is eq. 45's separation, checked beside.

    Args:
        period: The RHS period h [s].
        delay: The samples by which the command is late.
        lag: The actuators' time constant [s] (0: none)."""
    if delay == 0 and lag == 0:
        return 1.0 - STABILITY_MARGIN
    best = best_damped_gain(period, delay, lag)[1]
    return 1.0 - STABILITY_MARGIN / (1.0 - 0.5) * (1.0 - best)


def separates_by_decay(delay: int = 0, lag: float = 0.0) -> bool:
    """Whether the time-scale separation of eq. 45 is judged on the RHS loop's decay
    rate, -ln(rho) / h >= Td lambda_LHS, rather than on sigma_RHS = min_p k_p
    Re(lambda_p): with a delay or a lag. Eq. 45's sigma_RHS is the decay rate of the
    continuous loop without them, and a lower bound of the discrete loop's there; with
    a lag it is not the loop's rate (beyond the best-damped gain a larger k lambda
    decays slower, the loop's roots turning complex), so the rate the separation asks
    is asked of the loop itself.

    Args:
        delay: The samples by which the command is late.
        lag: The actuators' time constant [s] (0: none)."""
    return bool(delay or lag)


def loop_matrix(B: np.ndarray, K: np.ndarray, period: float) -> np.ndarray:
    """The discrete RHS loop's matrix A = [[I, -h K], [B, 0]] (2n x 2n) on (u_I, tau_obs)
    (analysis.rhs_loop); per mode its polynomial is z^2 - z + h k_p lambda_p.

    Args:
        B: The port's true input matrix (n x n).
        K: The integrator's gains (n).
        period: The RHS period h [s]."""
    n = B.shape[0]
    return np.block([[np.eye(n), -period * np.diag(K)], [B, np.zeros((n, n))]])


def delayed_loop_matrix(B: np.ndarray, K: np.ndarray, period: float, delay: int = 0,
                        lag: float = 0.0) -> np.ndarray:
    """The discrete RHS loop's matrix with the command ``delay`` samples late and a
    first-order actuator lag of time constant ``lag``, on (u_I, the delay line's d
    commands, the actuators' torque s (with a lag), tau_obs):

        s(k+1) = a s(k) + (1 - a) u_I(k - d),             a = exp(-h / lag)
        tau_obs(k+1) = B ((1 - b) u_I(k - d) + b s(k)),    b = (1 - a) / ln(1 / a)

    the lag sampled exactly under a held command, and the port observer's torque its
    output averaged over the sample (a momentum difference; kernels.certificate.
    lag_weight); no lag: tau_obs(k+1) = B u_I(k - d); delay 0 and no lag is
    gain_rule.loop_matrix.

    Args:
        B: The port's input matrix (n x n).
        K: The integrator's gains (n).
        period: The RHS period h [s].
        delay: The samples by which the command is late (computation and sensing).
        lag: The actuators' time constant [s] (0: none)."""
    n = B.shape[0]
    a = lag_pole(period, lag)
    b = lag_weight(a)
    blocks = 1 + delay + (1 if lag > 0 else 0) + 1
    A = np.zeros((blocks * n, blocks * n))
    I = np.eye(n)
    def at(row, column, value):
        A[row * n:(row + 1) * n, column * n:(column + 1) * n] = value
    at(0, 0, I)
    at(0, blocks - 1, -period * np.diag(K))
    for j in range(1, delay + 1):
        at(j, j - 1, I)                       # the delay line
    applied = delay                           # u_I(k - d)'s block
    if lag > 0:
        at(blocks - 2, blocks - 2, a * I)
        at(blocks - 2, applied, (1 - a) * I)
        at(blocks - 1, blocks - 2, b * B)
        at(blocks - 1, applied, (1 - b) * B)
    else:
        at(blocks - 1, applied, B)
    return A


def stays_stable_if_wrong(B_in_use: np.ndarray, K: np.ndarray, period: float,
                          radius: float, delay: int = 0, lag: float = 0.0) -> bool:
    """Whether the loop's spectral radius stays within ``radius`` with a new estimate's
    gains if the estimate in use is the truth: the evidence for a far jump (RhsIntegrator)
    may be wrong, so a jump that would then destabilize the loop is refused.

    Args:
        B_in_use: The estimate in use, taken as the truth.
        K: The new estimate's gains.
        period: The RHS period h [s].
        radius: The largest spectral radius allowed (certified_radius).
        delay: The samples by which the command is late.
        lag: The actuators' time constant [s] (0: none)."""
    A = delayed_loop_matrix(B_in_use, K, period, delay, lag)
    return bool(np.max(np.abs(np.linalg.eigvals(A))) <= radius)


def within_trust(paired: np.ndarray, nominal: np.ndarray, trust_ratio: float
                 ) -> Union[bool, np.ndarray]:
    """The bounded-learning-error condition, made operational: whether every paired
    eigenvalue of B_hat satisfies 1 / trust_ratio <= Re(lambda_hat_p) / lambda0_p <=
    trust_ratio against the anchor (B0's, or the estimate in use's: Rhs.trust_anchor);
    a bool, or one per trial for a stack.

    Mode p's loop gain g_p = h c lambda~_p / Re(lambda_hat_p) must stay < 1 (stable) and
    <= 1/4 (well damped); the check keeps g_p <= h c trust_ratio lambda~_p / lambda0_p, and
    anchored at the estimate in use one accepted refresh changes it by at most trust_ratio.

    Args:
        paired: B_hat's paired eigenvalues (n), or a stack (trials, n).
        nominal: The anchor's eigenvalues.
        trust_ratio: The allowed factor."""
    ratio = paired.real / np.asarray(nominal, float)
    within = np.all((ratio >= 1.0 / trust_ratio) & (ratio <= trust_ratio), axis=-1)
    return bool(within) if within.ndim == 0 else within


def check_rhs_period(periods: Periods, c_nominal: float, c_largest: float,
                     beta_max: float) -> None:
    """Refuses an RHS period that cannot realize the integrator's largest decay rate with a
    well-damped loop, g = h c <= 1/4 (WELL_DAMPED_LOOP_GAIN).

    Args:
        periods: The scenario's periods.
        c_nominal: The rate at beta_hat = 1, where every run starts [1/s].
        c_largest: The integrator's largest rate, (1 + c_margin) c_min(beta_max) [1/s].
        beta_max: rhs.beta_max, for the message.

    Raises:
        ConfigError: Naming periods.rhs and the largest period allowed."""
    bound = WELL_DAMPED_LOOP_GAIN / c_largest
    if periods.rhs > bound:
        raise ConfigError(
            f"periods.rhs = {periods.rhs:g} s cannot realize the RHS decay rate "
            f"c = {c_nominal:.1f} 1/s required by the gain rule (eq. 48) at beta_hat = 1, "
            f"up to {c_largest:.1f} 1/s at rhs.beta_max = {beta_max:g}, with a "
            f"well-damped discrete loop; allowed: periods.rhs <= 1 / (4 c) = "
            f"{bound:.3g} s, or a smaller rhs.beta_max")
