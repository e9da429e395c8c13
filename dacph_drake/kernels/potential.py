"""The null-space potential U(q), grad U and Hess U qdot as one compiled kernel
(reference: potential.BaseRepulsionPotential.Evaluate, which documents the model)."""
from typing import Tuple

import numpy as np
from numba import njit

RHO_FLOOR = 1e-4      # as potential._RHO_FLOOR


@njit(cache=True)
def _firas(rho, k, rho0):
    """f, f', f'' of f(rho) = k / 2 (1 / rho - 1 / rho0)^2 on rho < rho0, else 0."""
    rho = max(rho, RHO_FLOOR)
    if rho >= rho0:
        return 0.0, 0.0, 0.0
    a = 1.0 / rho - 1.0 / rho0
    return 0.5 * k * a * a, -k * a / rho**2, k / rho**4 + 2.0 * k * a / rho**3


@njit(cache=True)
def _chain(q, qdot, geometry):
    """(e, edot, O, Odot): link directions, joint positions and their rates (n x 2)."""
    n = q.shape[0]
    lengths = geometry[3:]
    # Scalar loops rather than array expressions (each of those compiles into a
    # kernel of its own).
    e = np.empty((n, 2))
    edot = np.empty((n, 2))
    phi, phidot = 0.0, 0.0
    for i in range(n):
        phi += q[i]
        phidot += qdot[i]
        e[i, 0], e[i, 1] = np.cos(phi), np.sin(phi)
        edot[i, 0], edot[i, 1] = -phidot * e[i, 1], phidot * e[i, 0]
    O = np.empty((n, 2))
    Odot = np.zeros((n, 2))
    O[0, 0], O[0, 1] = geometry[1], geometry[2]
    for i in range(1, n):
        for c in range(2):
            O[i, c] = O[i - 1, c] + lengths[i - 1] * e[i - 1, c]
            Odot[i, c] = Odot[i - 1, c] + lengths[i - 1] * edot[i - 1, c]
    return e, edot, O, Odot


@njit(cache=True)
def _box_distance(P0, P1, half, g):
    """(distance, h00, h01, h11) of (P0, P1) from the base square (inside: minus the depth),
    its gradient written to g and its curvature in a corner region (zero elsewhere)."""
    ex0, ex1 = abs(P0) - half, abs(P1) - half
    out0, out1 = max(ex0, 0.0), max(ex1, 0.0)
    dist = np.sqrt(out0 * out0 + out1 * out1)
    h00 = h01 = h11 = 0.0
    if dist == 0.0:          # inside: the gradient points to the nearest side
        g[0] = g[1] = 0.0
        if ex0 >= ex1:
            g[0], dist = np.sign(P0), ex0
        else:
            g[1], dist = np.sign(P1), ex1
    else:
        g[0], g[1] = np.sign(P0) * out0 / dist, np.sign(P1) * out1 / dist
        if ex0 > 0 and ex1 > 0:       # corner region: curvature of the distance
            h00, h01, h11 = ((1 - g[0] * g[0]) / dist, -g[0] * g[1] / dist,
                             (1 - g[1] * g[1]) / dist)
    return dist, h00, h01, h11


@njit(cache=True)
def min_clearance(q: np.ndarray, geometry: np.ndarray, link_of: np.ndarray,
                  fraction: np.ndarray, radius: np.ndarray) -> float:
    """min_j rho_j [m], rho_j = distance_j - radius[j] from the base (negative: inside it).

    Args:
        q: The joint angles (n) [rad].
        geometry: (half base size, shoulder x, shoulder y, link lengths (n)) [m].
        link_of: The link each sample point j lies on (points,).
        fraction: How far along its link point j lies (points,), in link lengths.
        radius: The half width of point j's link (points,) [m]."""
    e, _, O, _ = _chain(q, np.zeros_like(q), geometry)
    lengths, g, smallest = geometry[3:], np.empty(2), np.inf
    for j in range(link_of.shape[0]):
        link = link_of[j]
        reach = fraction[j] * lengths[link]
        dist = _box_distance(O[link, 0] + reach * e[link, 0],
                             O[link, 1] + reach * e[link, 1], geometry[0], g)[0]
        smallest = min(smallest, dist - radius[j])
    return smallest


@njit(cache=True)
def potential(q: np.ndarray, qdot: np.ndarray, geometry: np.ndarray,
              link_of: np.ndarray, fraction: np.ndarray, radius: np.ndarray,
              gains: np.ndarray) -> Tuple[float, np.ndarray, np.ndarray]:
    """The potential (U [J], grad U (n), Hess U qdot (n)) at (q, qdot).

    Args:
        q: The joint angles (n) [rad].
        qdot: The joint rates (n) [rad/s].
        geometry: (half base size, shoulder x, shoulder y, link lengths (n)) [m].
        link_of: The link each sample point j lies on (points,).
        fraction: How far along its link point j lies (points,), in link lengths.
        radius: The half width of point j's link (points,) [m].
        gains: (base_gain [J m^2], base_margin [m], fold_gain [J rad^2], fold_margin
            [rad])."""
    n = q.shape[0]
    lengths = geometry[3:]
    base_gain, base_margin, fold_gain, fold_margin = gains[0], gains[1], gains[2], gains[3]
    e, edot, O, Odot = _chain(q, qdot, geometry)
    U = 0.0
    grad = np.zeros(n)
    grad_dot = np.zeros(n)
    g = np.empty(2)
    for j in range(link_of.shape[0]):
        link = link_of[j]
        reach = fraction[j] * lengths[link]
        P0, P1 = O[link, 0] + reach * e[link, 0], O[link, 1] + reach * e[link, 1]
        Pd0, Pd1 = Odot[link, 0] + reach * edot[link, 0], Odot[link, 1] + reach * edot[link, 1]
        dist, h00, h01, h11 = _box_distance(P0, P1, geometry[0], g)
        rho = dist - radius[j]
        if rho >= base_margin:
            continue
        f, df, ddf = _firas(rho, base_gain, base_margin)
        gdot0 = h00 * Pd0 + h01 * Pd1
        gdot1 = h01 * Pd0 + h11 * Pd1
        rho_dot = g[0] * Pd0 + g[1] * Pd1
        U += f
        for i in range(link + 1):        # dP/dq_i = z x (P - O_i)
            r0, r1 = P0 - O[i, 0], P1 - O[i, 1]
            rd0, rd1 = Pd0 - Odot[i, 0], Pd1 - Odot[i, 1]
            Jg = r0 * g[1] - r1 * g[0]
            Jg_dot = rd0 * g[1] - rd1 * g[0] + r0 * gdot1 - r1 * gdot0
            grad[i] += df * Jg
            grad_dot[i] += ddf * rho_dot * Jg + df * Jg_dot
    for i in range(1, n):
        fold = np.pi - abs(q[i])
        if fold < fold_margin:
            f, df, ddf = _firas(fold, fold_gain, fold_margin)
            U += f
            grad[i] -= np.sign(q[i]) * df
            grad_dot[i] += ddf * qdot[i]
    return U, grad, grad_dot
