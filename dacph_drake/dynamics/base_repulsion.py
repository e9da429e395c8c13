"""Null-space artificial potential field U(q) (Khatib 1985, docs/equations.md E24):

U(q) = sum_points f(rho_j(q); k_b, rho_b) + sum_{k>=2} f(pi - |q_k|; k_f, rho_f),
f(rho; k, rho0) = k / 2 (1 / rho - 1 / rho0)^2 for rho < rho0, else 0 (FIRAS),

rho_j the j-th link point's clearance from the base square less the link's half width:
the first term keeps links off the base, the second each elbow from folding."""
from typing import Tuple

import numpy as np

from dacph_drake.scenario.planar_arm import RobotParams
from dacph_drake.kernels.potential import min_clearance
from dacph_drake.scenario import Potential

_RHO_FLOOR = 1e-4      # clearances are clamped here (inside the base U is finite)


def _firas(rho, k, rho0):
    """f, f', f'' of f(rho) = k / 2 (1 / rho - 1 / rho0)^2 on rho < rho0, else 0."""
    rho = np.maximum(rho, _RHO_FLOOR)
    active = rho < rho0
    a = np.where(active, 1 / rho - 1 / rho0, 0.0)
    return (0.5 * k * a**2, -k * a / rho**2,
            np.where(active, k / rho**4 + 2 * k * a / rho**3, 0.0))


class BaseRepulsionPotential:
    """The planar arm's null-space potential U(q) of the module docstring.

    Args:
        robot: The arm (the controller's nominal arm).
        settings: The potential's gains and margins."""
    def __init__(self, robot: RobotParams, settings: Potential):
        self._n = robot.num_links
        self._half_size = robot.base.size / 2
        self._shoulder = np.array([robot.base.shoulder_offset, 0.0])
        self._lengths = np.array([link.length for link in robot.links])
        fractions = np.arange(1, settings.points_per_link + 1) / settings.points_per_link
        # Point j sits a fraction along link link_of[j]; the first link's points start
        # away from the shoulder, which lies on the base's side by construction.
        self._link_of = np.repeat(np.arange(self._n), len(fractions))
        self._fraction = np.tile(fractions, self._n)
        self._radius = np.array([robot.links[k].width / 2 for k in self._link_of])
        self._s = settings
        self._geometry = self.kernel_arguments[:4]

    @property
    def kernel_arguments(self):
        """(geometry, link_of, fraction, radius, gains) for kernels.potential.potential."""
        s = self._s
        return (np.concatenate([[self._half_size], self._shoulder, self._lengths]),
                self._link_of, self._fraction.astype(float), self._radius,
                np.array([s.base_gain, s.base_margin, s.fold_gain, s.fold_margin], float))

    def _Points(self, q, qdot):
        """Sample points P, Pdot (m x 2), joints O, Odot (n x 2), in the base frame."""
        phi, phidot = np.cumsum(q), np.cumsum(qdot)
        e = np.stack([np.cos(phi), np.sin(phi)], axis=1)
        edot = phidot[:, None] * np.stack([-e[:, 1], e[:, 0]], axis=1)
        L = self._lengths[:, None]
        O = self._shoulder + np.vstack([np.zeros(2), np.cumsum(L * e, 0)[:-1]])
        Odot = np.vstack([np.zeros(2), np.cumsum(L * edot, 0)[:-1]])
        reach = (self._fraction * self._lengths[self._link_of])[:, None]
        P = O[self._link_of] + reach * e[self._link_of]
        Pdot = Odot[self._link_of] + reach * edot[self._link_of]
        return P, Pdot, O, Odot

    def _Clearance(self, P):
        """rho (m), d rho / dP, d2 rho / dP2 to the base square (rho <= 0 inside it)."""
        excess = np.abs(P) - self._half_size
        outside = np.maximum(excess, 0.0)
        dist = np.linalg.norm(outside, axis=1)
        inside = dist == 0.0
        safe = np.where(inside, 1.0, dist)
        grad = np.sign(P) * outside / safe[:, None]
        corner = np.all(excess > 0, axis=1)[:, None, None]
        hess = np.where(corner, (np.eye(2) - grad[:, :, None] * grad[:, None, :])
                        / safe[:, None, None], 0.0)
        if np.any(inside):
            rows = np.flatnonzero(inside)
            axis = np.argmax(excess[rows], axis=1)
            grad[rows] = 0.0
            grad[rows, axis] = np.sign(P[rows, axis])
            dist[rows] = excess[rows, axis]
        return dist - self._radius, grad, hess

    def Evaluate(self, q: np.ndarray, qdot: np.ndarray
                 ) -> Tuple[float, np.ndarray, np.ndarray]:
        """(U [J], grad U (n), d/dt grad U = Hess U qdot (n)) at (q, qdot).

        Args:
            q: The joint angles (n) [rad].
            qdot: The joint rates (n) [rad/s]."""
        n, s = self._n, self._s
        grad, grad_dot = np.zeros(n), np.zeros(n)
        P, Pdot, O, Odot = self._Points(q, qdot)
        rho, g, h = self._Clearance(P)
        active = np.flatnonzero(rho < s.base_margin)
        U = 0.0
        if active.size:
            f, df, ddf = _firas(rho[active], s.base_gain, s.base_margin)
            g, h, P, Pdot = g[active], h[active], P[active], Pdot[active]
            # dP_j/dq_i = z x (P_j - O_i) for the joints i at or before P_j's link.
            acts = np.arange(n)[None, :] <= self._link_of[active][:, None]
            R = (P[:, None, :] - O[None]) * acts[..., None]             # (m, n, 2)
            Rdot = (Pdot[:, None, :] - Odot[None]) * acts[..., None]
            Jg = R[..., 0] * g[:, None, 1] - R[..., 1] * g[:, None, 0]  # d rho / dq
            gdot = np.einsum("mcd,md->mc", h, Pdot)
            Jg_dot = (Rdot[..., 0] * g[:, None, 1] - Rdot[..., 1] * g[:, None, 0]
                      + R[..., 0] * gdot[:, None, 1] - R[..., 1] * gdot[:, None, 0])
            rho_dot = np.sum(g * Pdot, axis=1)
            U = float(np.sum(f))
            grad = df @ Jg
            grad_dot = (ddf * rho_dot) @ Jg + df @ Jg_dot
        if n > 1:
            fold = np.pi - np.abs(q[1:])
            if np.any(fold < s.fold_margin):
                f, df, ddf = _firas(fold, s.fold_gain, s.fold_margin)
                U += float(np.sum(f))
                grad[1:] -= np.sign(q[1:]) * df
                grad_dot[1:] += ddf * qdot[1:]
        return U, grad, grad_dot

    def MinClearance(self, q: np.ndarray) -> float:
        """The sample points' smallest clearance [m] from the base (< 0: inside).

        Args:
            q: The joint angles (n) [rad]."""
        return min_clearance(np.asarray(q, float), *self._geometry)
