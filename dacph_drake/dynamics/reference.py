"""Desired end-effector orientation alpha_d(t) = alpha(0) + sum_i a_i sin(2 pi t / T_i),
smooth and persistently exciting (the paper gives none; docs/equations.md)."""
import numpy as np

from dacph_drake.scenario import Reference


class OrientationReference:
    """alpha_d(t) of the module docstring, callable at t.

    Args:
        reference: The reference's amplitudes a_i and periods T_i.
        alpha0: alpha(0) [rad]."""
    def __init__(self, reference: Reference, alpha0: float):
        self._a = np.asarray(reference.amplitudes, float)
        self._w = 2 * np.pi / np.asarray(reference.periods, float)
        self._alpha0 = alpha0

    @property
    def kernel_arguments(self) -> np.ndarray:
        """[alpha(0), a (m), omega (m)] for kernels.loop.lhs_control."""
        return np.concatenate([[self._alpha0], self._a, self._w])

    def __call__(self, t: float):
        """(alpha_d, alpha_d_dot, alpha_d_ddot) at time t."""
        s, c = np.sin(self._w * t), np.cos(self._w * t)
        return (self._alpha0 + self._a @ s, self._a @ (self._w * c),
                -self._a @ (self._w**2 * s))
