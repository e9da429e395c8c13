"""The LHS Lyapunov check (paper sections "LHS Model-Based Control" and "Stability
Analysis"): V = s^T M(q) s / 2 along a run against the exponential envelope.

With r_slow = 2 lambda_min(K_d) / sup lambda_max(M), r_fast = 2 lambda_max(K_d) /
inf lambda_min(M) and the robust term -chi tanh(s / epsilon) (s_i (1 - tanh(|s_i| /
epsilon)) <= kappa epsilon, kappa = max_x x (1 - tanh x) = 0.2785), over each logged
interval where ||e_tau|| <= chi at both ends:

    upper:  Vdot <= -r_slow V + delta,          delta = n kappa chi epsilon
    lower:  Vdot >= -r_low V - e^2 / (2 lambda_max(K_d)),
            r_low = (3 lambda_max(K_d) + 2 chi / epsilon) / inf lambda_min(M)

integrated over [t_k, t_k+1] to V_k e^(-r dt) +- (delta / r)(1 - e^(-r dt)). An
excitation ||tau_pe|| <= a makes the upper rate r_slow / 2, adds a^2 / (2 lambda_min(K_d))
to delta and a to ||e_tau|| in the lower bound (Young). The spatial LHS (K_d = r M(q),
chi tanh(w_i s_i), w_i = M_ii / phi, phi = epsilon + chi / b), lambda = inf_q
lambda_min(M), m = sup_q max_i M_ii:

    upper:  Vdot <= -2 r V + n kappa chi phi / lambda  (excitation: -r V and
            a^2 / (2 r lambda))
    lower:  Vdot >= -(3 r + 2 (chi / phi) m / lambda) V - e^2 / (2 r lambda)"""
from dataclasses import asdict, dataclass
from typing import Tuple, Union

import numpy as np

KAPPA = 0.2785          # max_x x (1 - tanh x)


@dataclass
class EnvelopeConstants:
    """The envelope's constants, planar or spatial (module docstring).

    Attributes:
        rate_slow: The paper's upper-bound rate r_slow [1/s].
        rate_fast: The paper's lower-bound rate r_fast [1/s].
        damping_low: The damping part of the lower rate [1/s].
        young_e: Young's weight for e_tau.
        young_a: Young's weight for the excitation.
        n: The number of joints.
        layer_base: The slack's boundary layer Layer(chi) at chi = 0.
        layer_per_chi: d Layer / d chi.
        slope_scale: The lower-bound tanh rate is 2 slope_scale chi / Layer(chi)."""
    rate_slow: float
    rate_fast: float
    damping_low: float
    young_e: float
    young_a: float
    n: int
    layer_base: float
    layer_per_chi: float
    slope_scale: float          # lower-bound tanh rate = 2 slope_scale chi / layer

    @staticmethod
    def ForConstantDamping(Kd_min: float, Kd_max: float, lambda_min_M: float,
                           lambda_max_M: float, epsilon: float, n: int,
                           layer_per_chi: float = 0.0) -> "EnvelopeConstants":
        """The planar LHS's constants: K_d between Kd_min and Kd_max, tanh(s / phi),
        phi = epsilon + layer_per_chi chi.

        Args:
            Kd_min: lambda_min(K_d).
            Kd_max: lambda_max(K_d).
            lambda_min_M: inf_q lambda_min(M).
            lambda_max_M: sup_q lambda_max(M).
            epsilon: The boundary layer's thickness at chi = 0.
            n: The number of joints.
            layer_per_chi: d phi / d chi (0: the paper's tanh(s / epsilon))."""
        return EnvelopeConstants(
            rate_slow=2 * Kd_min / lambda_max_M, rate_fast=2 * Kd_max / lambda_min_M,
            damping_low=3 * Kd_max / lambda_min_M, young_e=Kd_max, young_a=Kd_min,
            n=n, layer_base=epsilon, layer_per_chi=layer_per_chi,
            slope_scale=1.0 / lambda_min_M)

    @staticmethod
    def ForInertiaScaled(damping_rate: float, lambda_min_M: float,
                         max_diagonal_M: float, epsilon: float, boundary_rate: float,
                         n: int) -> "EnvelopeConstants":
        """The spatial LHS's constants: K_d = damping_rate M, tanh(M_ii s_i / phi),
        phi = epsilon + chi / boundary_rate.

        Args:
            damping_rate: The LHS's damping rate r [1/s].
            lambda_min_M: inf_q lambda_min(M) (lambda).
            max_diagonal_M: sup_q max_i M_ii (m).
            epsilon: The boundary layer's thickness at chi = 0.
            boundary_rate: The boundary rate b [1/s].
            n: The number of joints."""
        r, lam = damping_rate, lambda_min_M
        return EnvelopeConstants(
            rate_slow=2 * r, rate_fast=2 * r, damping_low=3 * r, young_e=r * lam,
            young_a=r * lam, n=n, layer_base=epsilon / lam,
            layer_per_chi=1.0 / (boundary_rate * lam),
            slope_scale=max_diagonal_M / lam**2)

    def Layer(self, chi: Union[float, np.ndarray]) -> Union[float, np.ndarray]:
        """The boundary layer phi = layer_base + layer_per_chi chi (chi's shape).

        Args:
            chi: The RHS bound chi (a scalar or an array)."""
        return self.layer_base + self.layer_per_chi * chi

    def TanhRate(self, chi: Union[float, np.ndarray]) -> Union[float, np.ndarray]:
        """The lower bound's tanh rate [1/s]: 2 chi / epsilon / lambda (planar),
        2 (chi / phi) m / lambda (spatial).

        Args:
            chi: The RHS bound chi (a scalar or an array)."""
        return 2 * self.slope_scale * chi / self.Layer(chi)


@dataclass
class EnvelopeCheck:
    """The outcome of check_envelope.

    Attributes:
        rate_slow: The paper's upper-bound rate [1/s].
        rate_fast: The paper's lower-bound rate [1/s].
        rate_low: The lower-bound rate with the tanh and e_tau terms [1/s].
        samples_checked: The intervals with ||e_tau|| <= chi at both ends.
        fraction_inside: The fraction of those on which V stays in the envelope.
        worst_violation: max (V - bound) / bound over the intervals.
        worst_time: When the worst violation was [s].
        ok: Whether fraction_inside reaches the required fraction.
        reason: Why not ok ("" when ok)."""
    rate_slow: float                # the paper's upper-bound rate [1/s]
    rate_fast: float                # the paper's lower-bound rate [1/s]
    rate_low: float                 # lower-bound rate with the tanh and e_tau terms
    samples_checked: int            # intervals with ||e_tau|| <= chi at both ends
    fraction_inside: float
    worst_violation: float          # max (V - bound) / bound over the intervals
    worst_time: float
    ok: bool
    reason: str

    def as_dict(self) -> dict:
        """This check as a plain dict (for JSON)."""
        return asdict(self)


def envelope_bounds(V: np.ndarray, dt: np.ndarray, e_norm: np.ndarray, chi: np.ndarray,
                    constants: EnvelopeConstants, excitation_norm: float = 0.0
                    ) -> Tuple[np.ndarray, np.ndarray]:
    """(lower, upper) envelope bounds (each T - 1) on V[1:] from V[:-1] (module docstring).

    Args:
        V: V = s^T M s / 2 at the logged samples (T).
        dt: The steps between them [s] (T - 1).
        e_norm: ||e_tau|| at the samples (T).
        chi: The RHS bound chi at the samples (T).
        constants: The envelope's constants.
        excitation_norm: a, the bound on ||tau_pe|| (0 without excitation)."""
    a, c = excitation_norm, constants
    r_slow = c.rate_slow / (2 if a > 0 else 1)
    r_low = c.damping_low + c.TanhRate(chi[:-1])
    delta = c.n * KAPPA * chi[:-1] * c.Layer(chi[:-1]) + a**2 / (2 * c.young_a)
    e2 = (np.maximum(e_norm[:-1], e_norm[1:]) + a) ** 2 / (2 * c.young_e)
    decay_slow, decay_low = np.exp(-r_slow * dt), np.exp(-r_low * dt)
    upper = V[:-1] * decay_slow + delta / r_slow * (1 - decay_slow)
    lower = V[:-1] * decay_low - e2 / r_low * (1 - decay_low)
    return lower, upper


def check_lyapunov_envelope(t: np.ndarray, V: np.ndarray, e_norm: np.ndarray,
                            chi: np.ndarray, Kd_min: float, Kd_max: float,
                            lambda_min_M: float, lambda_max_M: float, epsilon: float,
                            n: int, required_fraction: float = 0.99,
                            excitation_norm: float = 0.0) -> EnvelopeCheck:
    """check_envelope for the planar LHS (EnvelopeConstants.ForConstantDamping).

    Args:
        t: The logged times [s] (T).
        V: V = s^T M s / 2 at them (T).
        e_norm: ||e_tau|| at them (T).
        chi: The RHS bound chi at them (T).
        Kd_min: lambda_min(K_d).
        Kd_max: lambda_max(K_d).
        lambda_min_M: inf_q lambda_min(M).
        lambda_max_M: sup_q lambda_max(M).
        epsilon: The boundary layer's thickness.
        n: The number of joints.
        required_fraction: The fraction of the intervals that must be inside.
        excitation_norm: The bound a on the excitation's ||tau_pe|| (0: none)."""
    return check_envelope(t, V, e_norm, chi, EnvelopeConstants.ForConstantDamping(
        Kd_min, Kd_max, lambda_min_M, lambda_max_M, epsilon, n), required_fraction,
        excitation_norm)


def check_envelope(t: np.ndarray, V: np.ndarray, e_norm: np.ndarray, chi: np.ndarray,
                   constants: EnvelopeConstants,
                   required_fraction: float = 0.99,
                   excitation_norm: float = 0.0) -> EnvelopeCheck:
    """The share of intervals (||e_tau|| <= chi) with V inside, and the worst violation.

    Args:
        t: The logged times [s] (T).
        V: V = s^T M s / 2 at them (T).
        e_norm: ||e_tau|| at them (T).
        chi: The RHS bound chi at them (T).
        constants: The envelope's constants.
        required_fraction: The fraction of the intervals that must be inside for ``ok``.
        excitation_norm: The bound a on the excitation's ||tau_pe|| (0: none)."""
    t, V, e_norm, chi = map(np.asarray, (t, V, e_norm, chi))
    lower, upper = envelope_bounds(V, np.diff(t), e_norm, chi, constants,
                                   excitation_norm)
    checked = (e_norm[:-1] <= chi[:-1]) & (e_norm[1:] <= chi[1:])
    slack = 1e-12 * np.maximum(V[:-1], 1e-30)            # round-off of V itself
    inside = (V[1:] <= upper + slack) & (V[1:] >= lower - slack)
    violation = np.where(checked, np.maximum(V[1:] - upper, lower - V[1:])
                         / np.maximum(upper, 1e-30), -np.inf)
    worst = int(np.argmax(violation)) if checked.any() else 0
    fraction = float(np.mean(inside[checked])) if checked.any() else float("nan")
    ok = checked.any() and fraction >= required_fraction
    reason = "" if ok else (
        "no interval with ||e_tau|| <= chi" if not checked.any() else
        f"V inside the envelope on {100 * fraction:.2f} % of the intervals "
        f"(required {100 * required_fraction:.0f} %); worst at t = {t[worst + 1]:.3f} s")
    return EnvelopeCheck(
        rate_slow=constants.rate_slow, rate_fast=constants.rate_fast,
        rate_low=float(constants.damping_low + constants.TanhRate(np.max(chi))),
        samples_checked=int(checked.sum()), fraction_inside=fraction,
        worst_violation=float(violation[worst]) if checked.any() else float("nan"),
        worst_time=float(t[worst + 1]), ok=bool(ok), reason=reason)
