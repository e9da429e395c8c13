"""The discrete RHS loop's certificate on a credible set of B. Per mode the polynomial is
z^2 - z + mu, mu an eigenvalue of h K B; with the command d samples late it is
(z - 1) z^(d+1) + mu, and with a first-order actuator lag of pole a = exp(-h / lag) too
(gain_rule.delayed_loop_matrix: the observer measures the lag's output averaged
over the sample, (1 - b) u + b s, b = (1 - a) / ln(1 / a))

    (z - 1)(z - a) z^(d+1) + mu ((1 - b) z + b - a).

With K = c diag(1 / Re lambda_hat_p) and B in the box [lower, upper], Gershgorin puts mu
in

    S_p = {mu : dist(mu, h c [lower_pp, upper_pp] / lambda_p) <= h c R_p / lambda_p},
    R_p = sum_{j != p} max(|lower_pj|, |upper_pj|).

Certified at c: every S_p has Re(mu) / h >= Td lambda_LHS (eq. 45) and every root within
the radius bound (at BOUNDARY_POINTS on S_p's boundary: |z| is subharmonic in mu)."""
import numpy as np
from numba import njit

BOUNDARY_POINTS = 48


@njit(cache=True)
def root_radius(mu: complex) -> float:
    """The largest root modulus max |z| of z^2 - z + mu.

    Args:
        mu: The loop gain (an eigenvalue of h K B)."""
    disc = np.sqrt(1.0 - 4.0 * mu + 0j)
    return max(abs(0.5 * (1.0 + disc)), abs(0.5 * (1.0 - disc)))


@njit(cache=True)
def lag_weight(pole: float) -> float:
    """b = (1 - a) / ln(1 / a): the weight of the lag's state s(k) in its output averaged
    over a sample under a held command u, (1 - b) u + b s(k) (0 without a lag).

    Args:
        pole: a = exp(-h / lag) (0: none)."""
    return (1.0 - pole) / np.log(1.0 / pole) if pole > 0.0 else 0.0


@njit(cache=True)
def _mode_polynomial(mu: complex, delay: int, pole: float) -> np.ndarray:
    """The mode's polynomial (the module's), monic: its coefficient of z^k at [k]."""
    if pole > 0.0:
        m = delay + 3
        a = np.zeros(m + 1, np.complex128)
        b = lag_weight(pole)
        a[m], a[m - 1], a[m - 2] = 1.0, -(1.0 + pole), pole
        a[1] += mu * (1.0 - b)
        a[0] += mu * (b - pole)
    else:
        m = delay + 2
        a = np.zeros(m + 1, np.complex128)
        a[m], a[m - 1] = 1.0, -1.0
        a[0] += mu
    return a


@njit(cache=True)
def roots_within(mu: complex, delay: int, pole: float, bound: float) -> bool:
    """Whether every root of the mode's polynomial (the module's) has |z| < bound: the
    Schur-Cohn recursion on the polynomial of w = z / bound (a polynomial is Schur
    stable iff |a_0| < |a_m| and (conj(a_m) p(w) - a_0 p*(w)) / w is).

    Args:
        mu: The loop gain (an eigenvalue of h K B).
        delay: The samples by which the command is late.
        pole: a = exp(-h / lag) of the actuators' lag (0: none).
        bound: The radius the roots must stay within."""
    a = _mode_polynomial(mu, delay, pole)
    m = a.shape[0] - 1
    scale = 1.0
    for k in range(m, -1, -1):               # w = z / bound
        a[k] *= scale
        scale /= bound
    while m > 0:
        if not abs(a[0]) < abs(a[m]):
            return False
        lead, constant = np.conj(a[m]), a[0]
        reduced = np.empty(m, np.complex128)
        for k in range(1, m + 1):
            reduced[k - 1] = lead * a[k] - constant * np.conj(a[m - k])
        a, m = reduced, m - 1
    return True


@njit(cache=True)
def mode_radius(mu: complex, delay: int, pole: float) -> float:
    """The largest root modulus of the mode's polynomial (the module's): root_radius
    without delay or lag, else its roots by the Durand-Kerner iteration (to round-off).

    Args:
        mu: The loop gain (an eigenvalue of h K B).
        delay: The samples by which the command is late.
        pole: a = exp(-h / lag) of the actuators' lag (0: none)."""
    if delay == 0 and pole == 0.0:
        return root_radius(mu)
    a = _mode_polynomial(mu, delay, pole)
    m = a.shape[0] - 1
    roots = np.empty(m, np.complex128)
    for j in range(m):
        roots[j] = (0.4 + 0.9j) ** j
    for _ in range(1000):
        change = 0.0
        for j in range(m):
            value = a[m]
            for k in range(m - 1, -1, -1):
                value = value * roots[j] + a[k]
            denominator = 1.0 + 0j
            for i in range(m):
                if i != j:
                    denominator *= roots[j] - roots[i]
            step = value / denominator
            roots[j] -= step
            change = max(change, abs(step))
        if change < 1e-15:
            break
    return np.max(np.abs(roots))


@njit(cache=True)
def _stadium_point(low, high, radius, scale, p, k) -> complex:
    """The k-th of BOUNDARY_POINTS on mode p's stadium (in units of h c) at h c =
    ``scale``: the left and right semicircles, then the upper and lower edges."""
    quarter = BOUNDARY_POINTS // 4
    a, b, r = scale * low[p], scale * high[p], scale * radius[p]
    if k < quarter:
        angle = np.pi / 2 + np.pi * k / (quarter - 1)
        return a + r * np.cos(angle) + 1j * r * np.sin(angle)
    if k < 2 * quarter:
        angle = -np.pi / 2 + np.pi * (k - quarter) / (quarter - 1)
        return b + r * np.cos(angle) + 1j * r * np.sin(angle)
    x = a + (b - a) * ((k - 2 * quarter) % quarter) / (quarter - 1)
    return x + 1j * r * (1.0 if k < 3 * quarter else -1.0)


@njit(cache=True)
def _exceeds(low, high, radius, scale, bound, delay, pole) -> bool:
    """Whether some root over the stadiums at h c = ``scale`` has |z| > ``bound`` (|z| is
    subharmonic in mu, so the boundary decides)."""
    for p in range(low.shape[0]):
        for k in range(BOUNDARY_POINTS):
            mu = _stadium_point(low, high, radius, scale, p, k)
            if delay == 0 and pole == 0.0:
                if root_radius(mu) > bound:
                    return True
            elif not roots_within(mu, delay, pole, bound):
                return True
    return False


@njit(cache=True)
def _largest_radius(low, high, radius, scale, delay, pole) -> float:
    """The largest root radius over the stadiums (in units of h c) at h c = ``scale``."""
    worst = 0.0
    for p in range(low.shape[0]):
        for k in range(BOUNDARY_POINTS):
            worst = max(worst, mode_radius(
                _stadium_point(low, high, radius, scale, p, k), delay, pole))
    return worst


@njit(cache=True)
def _bisect(low, high, radius, period, good, bad, radius_bound, delay, pole) -> float:
    """The certified end of [good, bad] nearest ``bad`` (30 halvings)."""
    for _ in range(30):
        middle = 0.5 * (good + bad)
        if _exceeds(low, high, radius, period * middle, radius_bound, delay, pole):
            bad = middle
        else:
            good = middle
    return good


@njit(cache=True)
def _certified_rate(low, high, radius, period, c, c_low, c_cap, radius_bound, delay,
                    pole) -> float:
    """The certified rate nearest ``c`` in [c_low, c_cap], or -1: the certified rates are an
    interval (the radius falls with c, then rises once the fast roots turn complex)."""
    if not _exceeds(low, high, radius, period * c, radius_bound, delay, pole):
        return c
    if not _exceeds(low, high, radius, period * c_low, radius_bound, delay, pole):
        return _bisect(low, high, radius, period, c_low, c, radius_bound, delay, pole)
    previous = c_low
    for k in range(1, 33):
        candidate = c_low * (c_cap / c_low) ** (k / 32.0)
        if not _exceeds(low, high, radius, period * candidate, radius_bound, delay,
                        pole):
            c_a = _bisect(low, high, radius, period, candidate, previous, radius_bound,
                          delay, pole)
            if c <= c_a:
                return c_a
            return _bisect(low, high, radius, period, c_a, c, radius_bound, delay, pole)
        previous = candidate
    return -1.0


@njit(cache=True)
def certified_gains(lower: np.ndarray, upper: np.ndarray, eigenvalues: np.ndarray,
                    floor: np.ndarray, c_target: np.ndarray, c_floor: np.ndarray,
                    rate: np.ndarray, period: float, c_cap: float, radius_bound: float,
                    out: np.ndarray, gains: np.ndarray, delay: int = 0,
                    pole: float = 0.0, by_decay: bool = False) -> None:
    """Every trial's certified rate c (c_target moved into the certified interval within
    [max(c_floor, rate / slowest), c_cap]) and gains k_p = c / lambda_p, raised to ``floor``
    where the set certifies it (box_certificate). ``by_decay``: the separation is the
    loop's decay rate instead, -ln(radius) / h >= rate (a radius bound exp(-h rate)
    beside ``radius_bound``), searched from a quarter of rate / slowest (at gains up to
    the best-damped one a mode decays at most 4 ln 2 = 2.8 times as fast as its
    k lambda without a delay or lag, and less with those tried; a rate below is not
    tried, which is conservative) up to c_cap / slowest, where the set's slowest mode
    is best damped (with a lag the radius rises steeply below the best-damped gain and
    slowly above it, so the set's modes are best kept at or above it).

    Args:
        lower: Each trial's set's lower bounds (trials, n, n).
        upper: Each trial's set's upper bounds (trials, n, n).
        eigenvalues: Re lambda_p of each trial's estimate's paired eigenvalues (trials, n).
        floor: The gains without learning [1/s per unit of B] (trials, n; 0: none).
        c_target: The rate the gain rule asks of each trial [1/s] (trials).
        c_floor: The least rate each trial may run [1/s] (trials).
        rate: Td lambda_LHS of each trial [1/s] (trials).
        period: The RHS period h [s].
        c_cap: The largest rate any trial may run [1/s].
        radius_bound: The largest spectral radius allowed.
        out: Written: [c, certified (1/0), slowest min_p (lower_pp - R_p) / lambda_p,
            fastest max_p (upper_pp + R_p) / lambda_p] (trials, 4).
        gains: Written per certified trial: k_p [1/s per unit of B] (trials, n).
        delay: The samples by which the command is late.
        pole: a = exp(-h / lag) of the actuators' lag (0: none).
        by_decay: Judge the separation by the loop's decay rate (with a delay or lag)."""
    trials, n = lower.shape[0], lower.shape[1]
    low, high, radius = np.empty(n), np.empty(n), np.empty(n)
    for i in range(trials):
        slowest, fastest = np.inf, 0.0
        for p in range(n):
            R = 0.0
            for j in range(n):
                if j != p:
                    R += max(abs(lower[i, p, j]), abs(upper[i, p, j]))
            low[p] = lower[i, p, p] / eigenvalues[i, p]
            high[p] = upper[i, p, p] / eigenvalues[i, p]
            radius[p] = R / eigenvalues[i, p]
            slowest = min(slowest, low[p] - radius[p])
            fastest = max(fastest, high[p] + radius[p])
        out[i, 2], out[i, 3] = slowest, fastest
        out[i, 0], out[i, 1] = c_target[i], 0.0
        if not slowest > 0.0:
            continue
        bound, cap = radius_bound, c_cap
        if by_decay:
            c_low = max(c_floor[i], 0.25 * rate[i] / slowest)
            bound = min(radius_bound, np.exp(-period * rate[i]))
            cap = c_cap / min(slowest, 1.0)
        else:
            c_low = max(c_floor[i], rate[i] / slowest)
        if c_low > cap:
            continue
        c = _certified_rate(low, high, radius, period, min(max(c_target[i], c_low), cap),
                            c_low, cap, bound, delay, pole)
        if c < 0.0:
            continue
        out[i, 0], out[i, 1] = c, 1.0
        raised = False
        for p in range(n):
            gains[i, p] = c / eigenvalues[i, p]
            if floor[i, p] > gains[i, p]:
                gains[i, p], raised = floor[i, p], True
        if raised:
            slowest_rate, largest = box_certificate(lower[i], upper[i], gains[i], period,
                                                    delay, pole)
            if not ((by_decay or slowest_rate >= rate[i]) and largest <= bound):
                for p in range(n):
                    gains[i, p] = c / eigenvalues[i, p]


@njit(cache=True)
def box_certificate(lower: np.ndarray, upper: np.ndarray, gains: np.ndarray,
                    period: float, delay: int = 0, pole: float = 0.0) -> np.ndarray:
    """[min_p k_p (lower_pp - R_p) [1/s], largest root modulus] with given gains on a box of
    B: Gershgorin discs of h K B centred in h k_p [lower_pp, upper_pp], radius h k_p R_p.

    Args:
        lower: The box's lower bounds (n, n).
        upper: The box's upper bounds (n, n).
        gains: The integrator's gains k_p (n).
        period: The RHS period h [s].
        delay: The samples by which the command is late.
        pole: a = exp(-h / lag) of the actuators' lag (0: none)."""
    n = lower.shape[0]
    low, high, radius = np.empty(n), np.empty(n), np.empty(n)
    slowest = np.inf
    for p in range(n):
        R = 0.0
        for j in range(n):
            if j != p:
                R += max(abs(lower[p, j]), abs(upper[p, j]))
        low[p] = gains[p] * lower[p, p]
        high[p] = gains[p] * upper[p, p]
        radius[p] = gains[p] * R
        slowest = min(slowest, low[p] - radius[p])
    out = np.empty(2)
    out[0] = slowest
    out[1] = _largest_radius(low, high, radius, period, delay, pole)
    return out
