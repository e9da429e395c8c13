"""The ground truth's RHS matrices B~(x) and D~(x) by phase (docs/equations.md E19)."""
from typing import Tuple

import numpy as np

from dacph_drake.scenario import Phases, Uncertainty


def actuator_arguments(uncertainty: Uncertainty, n: int) -> np.ndarray:
    """kernels.loop.actuator_gains' [B_scale (n), (time, joint, gain) per fault].

    Args:
        uncertainty: The trial's true RHS (its B_scale and faults).
        n: The number of joints."""
    scale = uncertainty.B_scale if len(uncertainty.B_scale) else [1.0] * n
    faults = [[f.time, f.joint - 1, f.gain] for f in uncertainty.faults]
    return np.concatenate([np.asarray(scale, float),
                           np.asarray(faults, float).reshape(-1)])


class TrueRhsModel:
    """B~(q, p, t) = diag(g(t)) (B0 + Delta B), D~(p, t) = D0 + Delta D: linear terms from
    phases.linear_start, nonlinear ones from phases.nonlinear_start, gains g(t) from t = 0.

    Args:
        uncertainty: The trial's true RHS.
        phases: The trial's phases."""

    def __init__(self, uncertainty: Uncertainty, phases: Phases):
        u = uncertainty
        self._B0 = np.asarray(u.B0, float)           # diagonal
        self._D0 = np.asarray(u.D0, float)
        self._D_offset = u.linear_scale * np.asarray(u.D_offset, float)
        self._D_linear = u.linear_scale * np.asarray(u.D_linear, float)
        self._B_linear = u.linear_scale * np.asarray(u.B_linear, float)
        self._D_quadratic = u.nonlinear_scale * np.asarray(u.D_quadratic, float)
        self._B_quadratic = u.nonlinear_scale * np.asarray(u.B_quadratic, float)
        self._B_q1_squared = u.nonlinear_scale * np.asarray(u.B_q1_squared, float)
        self._linear_start = phases.linear_start
        self._nonlinear_start = phases.nonlinear_start
        self._actuator = actuator_arguments(u, len(self._B0))

    @property
    def kernel_arguments(self):
        """The arguments of kernels.loop.true_matrices after (t, q, p)."""
        return (self._B0, self._D0, self._D_offset, self._D_linear, self._B_linear,
                self._D_quadratic, self._B_quadratic, self._B_q1_squared,
                float(self._linear_start), float(self._nonlinear_start), self._actuator)

    def ActuatorGains(self, t: float) -> np.ndarray:
        """g(t) (n): B_scale times the gains of the faults whose time has come.

        Args:
            t: The time [s]."""
        n = len(self._B0)
        gains = self._actuator[:n].copy()
        for time, joint, gain in self._actuator[n:].reshape(-1, 3):
            if t >= time:
                gains[int(joint)] *= gain
        return gains

    def Matrices(self, t: float, q: np.ndarray, p: np.ndarray
                 ) -> Tuple[np.ndarray, np.ndarray]:
        """(B~ (n x n), diagonal of D~ (n)) at a time and state.

        Args:
            t: The time [s].
            q: The joint angles (n) [rad].
            p: The momentum (n)."""
        B, D = self._NominalScaleMatrices(t, q, p)
        return self.ActuatorGains(t)[:, None] * B, D

    def _NominalScaleMatrices(self, t: float, q: np.ndarray, p: np.ndarray):
        """(B0 + Delta B, diagonal of D~): B~ before the actuators' gains."""
        if t < self._linear_start:
            return np.diag(self._B0), self._D0.copy()
        B_diagonal = self._B0 + self._B_linear @ q
        D = self._D0 + self._D_offset + self._D_linear * p
        if t < self._nonlinear_start:
            return np.diag(B_diagonal), D
        pp = p * p
        D += self._D_quadratic * pp
        B = np.diag(B_diagonal + self._B_quadratic * pp)
        B += (q[0] * q[0]) * self._B_q1_squared
        return B, D
