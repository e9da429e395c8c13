"""External disturbance source d(t) (SPEC section 7; the paper leaves d(t) open)."""
import numpy as np
from pydrake.systems.framework import LeafSystem

from dacph_drake.scenario import Disturbance


class DisturbanceSource(LeafSystem):
    """Output ``disturbance``: d(t) = scale (d_LF + d_HF) for t >= start, else 0,
        d_LF = offset + amplitude * [sin(2 pi f_1 t), cos(2 pi f_2 t), sin, cos, ...]
        d_HF = a_HF sin(2 pi f_HF t) direction.
    A stateless output that depends on time only."""

    def __init__(self, settings: Disturbance, start: float):
        super().__init__()
        n = len(settings.lf_offset)
        self._start = start
        self._scale = settings.scale
        self._offset = np.asarray(settings.lf_offset, float)
        self._amplitude = np.asarray(settings.lf_amplitude, float)
        self._omega = 2 * np.pi * np.asarray(settings.lf_frequency, float)
        self._quadrature = (np.arange(n) % 2) * np.pi / 2      # sin, cos, sin, ...
        self._hf = settings.hf_amplitude * np.asarray(settings.hf_direction, float)
        self._hf_omega = 2 * np.pi * settings.hf_frequency
        self.DeclareVectorOutputPort("disturbance", n, self._CalcDisturbance,
                                     prerequisites_of_calc={self.time_ticket()})

    def Evaluate(self, t: float) -> np.ndarray:
        if t < self._start:
            return np.zeros_like(self._offset)
        lf = self._offset + self._amplitude * np.sin(self._omega * t + self._quadrature)
        return self._scale * (lf + self._hf * np.sin(self._hf_omega * t))

    def _CalcDisturbance(self, context, output):
        output.SetFromVector(self.Evaluate(context.get_time()))
