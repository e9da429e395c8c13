"""External disturbance d(t) (left open by the paper; docs/equations.md)."""
from typing import Sequence

import numpy as np
from pydrake.systems.framework import LeafSystem

from dacph_drake.kernels.loop import disturbance
from dacph_drake.scenario import Disturbance


class DisturbanceSource(LeafSystem):
    """d(t) = scale (d_LF + d_HF) for t >= start, else 0, per trial, with
        d_LF = offset + amplitude * [sin(2 pi f_1 t), cos(2 pi f_2 t), sin, cos, ...]
        d_HF = a_HF sin(2 pi f_HF t) direction.

    Outputs ``disturbance_model`` (d(t)'s parameters, for the kernel), ``disturbance``.

    Args:
        settings: Each trial's disturbance d(t) (scenario.disturbance).
        starts: Each trial's start time of d(t) [s]."""

    def __init__(self, *, settings: Sequence[Disturbance], starts: Sequence[float]):
        super().__init__()
        self._models = [_Parameters(disturbance, start)
                        for disturbance, start in zip(settings, starts, strict=True)]
        n = len(settings[0].lf_offset)
        self._model = np.concatenate(self._models)
        self.DeclareVectorOutputPort("disturbance", n * len(self._models),
                                     self._CalcDisturbance,
                                     prerequisites_of_calc={self.time_ticket()})
        self.DeclareVectorOutputPort(
            "disturbance_model", len(self._model),
            lambda context, output: output.SetFromVector(self._model),
            prerequisites_of_calc={self.nothing_ticket()})

    def Evaluate(self, t: float) -> np.ndarray:
        """The trials' d(t) [N m], stacked (n per trial).

        Args:
            t: The time [s]."""
        return np.concatenate([disturbance(t, model) for model in self._models])

    def _CalcDisturbance(self, context, output):
        output.SetFromVector(self.Evaluate(context.get_time()))


def _Parameters(settings: Disturbance, start: float) -> np.ndarray:
    """d(t)'s parameter vector (kernels.loop.disturbance) of one trial."""
    n = len(settings.lf_offset)
    return np.concatenate([
        [start, settings.scale, 2 * np.pi * settings.hf_frequency],
        settings.lf_offset, settings.lf_amplitude,
        2 * np.pi * np.asarray(settings.lf_frequency, float),
        (np.arange(n) % 2) * np.pi / 2,                    # sin, cos, sin, ...
        settings.hf_amplitude * np.asarray(settings.hf_direction, float)])
