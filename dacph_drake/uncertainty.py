"""The ground truth's RHS matrices B~(x) and D~(x) by phase (docs/equations.md E19, SPEC settings)."""
import numpy as np

from dacph_drake.scenario import Phases, Uncertainty


class TrueRhsModel:
    """B~(q, p, t) = B0 + Delta B and D~(p, t) = D0 + Delta D, with the linear terms on
    from phases.linear_start and the nonlinear terms from phases.nonlinear_start."""

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

    @property
    def kernel_arguments(self):
        """The arguments of kernels.loop.true_matrices after (t, q, p)."""
        return (self._B0, self._D0, self._D_offset, self._D_linear, self._B_linear,
                self._D_quadratic, self._B_quadratic, self._B_q1_squared,
                float(self._linear_start), float(self._nonlinear_start))

    def Matrices(self, t: float, q: np.ndarray, p: np.ndarray):
        """(B~, diagonal of D~) at time t and state (q, p)."""
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
