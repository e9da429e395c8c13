"""The LHS Lyapunov check (paper section "LHS Model-Based Control" and "Stability
Analysis"): V = s^T M(q) s / 2 along a run against the exponential envelope.

The paper's bounds, with r_slow = 2 lambda_min(K_d) / sup lambda_max(M) and
r_fast = 2 lambda_max(K_d) / inf lambda_min(M), hold for the discontinuous term
-chi s / ||s|| whenever ||e_tau|| <= chi. The controller uses the smooth
-chi tanh(s / epsilon); per component s_i (1 - tanh(|s_i| / epsilon)) <= kappa epsilon
with kappa = max_x x (1 - tanh x) = 0.2785, so over each logged interval where
||e_tau|| <= chi at both ends:

    upper:  Vdot <= -r_slow V + delta,          delta = n kappa chi epsilon
    lower:  Vdot >= -r_low V - e^2 / (2 lambda_max(K_d)),
            r_low = (3 lambda_max(K_d) + 2 chi / epsilon) / inf lambda_min(M)

(the lower rate adds the tanh slope chi / epsilon and Young's inequality on
s^T e_tau to r_fast). Integrated over the interval [t_k, t_k+1] these give
V_k e^(-r dt) +- (delta / r)(1 - e^(-r dt)), the envelope checked here.

A DAC loop with the learner's excitation (scenario.excitation) adds the known input
tau_pe, ||tau_pe|| <= a, to the s dynamics. Young's inequality
s^T tau_pe <= lambda_min(K_d) ||s||^2 / 2 + a^2 / (2 lambda_min(K_d)) then gives

    upper:  Vdot <= -(r_slow / 2) V + delta + a^2 / (2 lambda_min(K_d))

and in the lower bound ||e_tau|| becomes ||e_tau|| + a.
"""
from dataclasses import asdict, dataclass

import numpy as np

KAPPA = 0.2785          # max_x x (1 - tanh x)


@dataclass
class EnvelopeCheck:
    rate_slow: float                # the paper's upper-bound rate [1/s]
    rate_fast: float                # the paper's lower-bound rate [1/s]
    rate_low: float                 # lower-bound rate with the tanh and e_tau terms
    samples_checked: int            # intervals with ||e_tau|| <= chi at both ends
    fraction_inside: float
    worst_violation: float          # max (V - bound) / bound over the intervals
    worst_time: float
    ok: bool
    reason: str

    def as_dict(self):
        return asdict(self)


def envelope_bounds(V: np.ndarray, dt: np.ndarray, e_norm: np.ndarray, chi: np.ndarray,
                    Kd_min: float, Kd_max: float, lambda_min_M: float,
                    lambda_max_M: float, epsilon: float, n: int,
                    excitation_norm: float = 0.0):
    """(lower, upper) bound for V[1:] from V[:-1] over the steps dt (module
    docstring); ``excitation_norm`` is a, the bound on ||tau_pe||."""
    a = excitation_norm
    r_slow = 2 * Kd_min / lambda_max_M / (2 if a > 0 else 1)
    r_low = (3 * Kd_max + 2 * chi[:-1] / epsilon) / lambda_min_M
    delta = n * KAPPA * chi[:-1] * epsilon + a**2 / (2 * Kd_min)
    e2 = (np.maximum(e_norm[:-1], e_norm[1:]) + a) ** 2 / (2 * Kd_max)
    decay_slow, decay_low = np.exp(-r_slow * dt), np.exp(-r_low * dt)
    upper = V[:-1] * decay_slow + delta / r_slow * (1 - decay_slow)
    lower = V[:-1] * decay_low - e2 / r_low * (1 - decay_low)
    return lower, upper


def check_lyapunov_envelope(t, V, e_norm, chi, Kd_min: float, Kd_max: float,
                            lambda_min_M: float, lambda_max_M: float, epsilon: float,
                            n: int, required_fraction: float = 0.99,
                            excitation_norm: float = 0.0) -> EnvelopeCheck:
    """Fraction of the logged intervals (where ||e_tau|| <= chi) on which V stays
    inside the envelope, and the worst relative violation; ``ok`` when the fraction
    reaches ``required_fraction``. ``excitation_norm``: the bound a on the
    excitation's ||tau_pe|| (0 without excitation)."""
    t, V, e_norm, chi = map(np.asarray, (t, V, e_norm, chi))
    lower, upper = envelope_bounds(V, np.diff(t), e_norm, chi, Kd_min, Kd_max,
                                   lambda_min_M, lambda_max_M, epsilon, n,
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
        rate_slow=2 * Kd_min / lambda_max_M, rate_fast=2 * Kd_max / lambda_min_M,
        rate_low=float((3 * Kd_max + 2 * np.max(chi) / epsilon) / lambda_min_M),
        samples_checked=int(checked.sum()), fraction_inside=fraction,
        worst_violation=float(violation[worst]) if checked.any() else float("nan"),
        worst_time=float(t[worst + 1]), ok=bool(ok), reason=reason)
