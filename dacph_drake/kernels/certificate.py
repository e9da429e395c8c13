"""The discrete RHS loop's certificate on a credible set of B. Per mode the polynomial is
z^2 - z + mu, mu an eigenvalue of h K B; with K = c diag(1 / Re lambda_hat_p) and B in
the box [lower, upper], Gershgorin puts mu in

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
def _largest_radius(low, high, radius, scale) -> float:
    """The largest root radius over the stadiums (in units of h c) at h c = ``scale``."""
    worst = 0.0
    quarter = BOUNDARY_POINTS // 4
    for p in range(low.shape[0]):
        a, b, r = scale * low[p], scale * high[p], scale * radius[p]
        for k in range(BOUNDARY_POINTS):
            if k < quarter:                      # the left semicircle
                angle = np.pi / 2 + np.pi * k / (quarter - 1)
                mu = a + r * np.cos(angle) + 1j * r * np.sin(angle)
            elif k < 2 * quarter:                # the right semicircle
                angle = -np.pi / 2 + np.pi * (k - quarter) / (quarter - 1)
                mu = b + r * np.cos(angle) + 1j * r * np.sin(angle)
            else:                                # the upper and lower edges
                x = a + (b - a) * ((k - 2 * quarter) % quarter) / (quarter - 1)
                mu = x + 1j * r * (1.0 if k < 3 * quarter else -1.0)
            worst = max(worst, root_radius(mu))
    return worst


@njit(cache=True)
def _bisect(low, high, radius, period, good, bad, radius_bound) -> float:
    """The certified end of [good, bad] nearest ``bad`` (30 halvings)."""
    for _ in range(30):
        middle = 0.5 * (good + bad)
        if _largest_radius(low, high, radius, period * middle) > radius_bound:
            bad = middle
        else:
            good = middle
    return good


@njit(cache=True)
def _certified_rate(low, high, radius, period, c, c_low, c_cap, radius_bound) -> float:
    """The certified rate nearest ``c`` in [c_low, c_cap], or -1: the certified rates are an
    interval (the radius falls with c, then rises once the fast roots turn complex)."""
    if _largest_radius(low, high, radius, period * c) <= radius_bound:
        return c
    if _largest_radius(low, high, radius, period * c_low) <= radius_bound:
        return _bisect(low, high, radius, period, c_low, c, radius_bound)
    previous = c_low
    for k in range(1, 33):
        candidate = c_low * (c_cap / c_low) ** (k / 32.0)
        if _largest_radius(low, high, radius, period * candidate) <= radius_bound:
            c_a = _bisect(low, high, radius, period, candidate, previous, radius_bound)
            if c <= c_a:
                return c_a
            return _bisect(low, high, radius, period, c_a, c, radius_bound)
        previous = candidate
    return -1.0


@njit(cache=True)
def certified_gains(lower: np.ndarray, upper: np.ndarray, eigenvalues: np.ndarray,
                    floor: np.ndarray, c_target: np.ndarray, c_floor: np.ndarray,
                    rate: np.ndarray, period: float, c_cap: float, radius_bound: float,
                    out: np.ndarray, gains: np.ndarray) -> None:
    """Every trial's certified rate c (c_target moved into the certified interval within
    [max(c_floor, rate / slowest), c_cap]) and gains k_p = c / lambda_p, raised to ``floor``
    where the set certifies it (box_certificate).

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
        gains: Written per certified trial: k_p [1/s per unit of B] (trials, n)."""
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
        c_low = max(c_floor[i], rate[i] / slowest)
        if c_low > c_cap:
            continue
        c = _certified_rate(low, high, radius, period, min(max(c_target[i], c_low), c_cap),
                            c_low, c_cap, radius_bound)
        if c < 0.0:
            continue
        out[i, 0], out[i, 1] = c, 1.0
        raised = False
        for p in range(n):
            gains[i, p] = c / eigenvalues[i, p]
            if floor[i, p] > gains[i, p]:
                gains[i, p], raised = floor[i, p], True
        if raised:
            slowest_rate, largest = box_certificate(lower[i], upper[i], gains[i], period)
            if not (slowest_rate >= rate[i] and largest <= radius_bound):
                for p in range(n):
                    gains[i, p] = c / eigenvalues[i, p]


@njit(cache=True)
def box_certificate(lower: np.ndarray, upper: np.ndarray, gains: np.ndarray,
                    period: float) -> np.ndarray:
    """[min_p k_p (lower_pp - R_p) [1/s], largest root modulus] with given gains on a box of
    B: Gershgorin discs of h K B centred in h k_p [lower_pp, upper_pp], radius h k_p R_p.

    Args:
        lower: The box's lower bounds (n, n).
        upper: The box's upper bounds (n, n).
        gains: The integrator's gains k_p (n).
        period: The RHS period h [s]."""
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
    out[1] = _largest_radius(low, high, radius, period)
    return out
