"""Band-pass prefilter of the learner's port samples (Learner.band; equations.md E33)."""
from typing import Optional

import numpy as np
from pydrake.systems.framework import LeafSystem

from dacph_drake.learning.identification import BandPassCascade, PortSample
from dacph_drake.learning import Channels
from dacph_drake.learning.network_learner import PortSampleChannels
from dacph_drake.scenario import Learner


class RegressionFilter(LeafSystem):
    """Every ``period`` holds port_sample's [q, p, band-passed channels] (BandPassCascade)
    on ``filtered_sample``: one linear filter on every channel keeps tau = B u - D qdot + d
    while B(x), D(x) vary slowly, and removes d(t) outside the band.

    Args:
        settings: The learner's settings (its band and sections).
        num_joints: n.
        period: The sample period [s].
        trials: The number of trials of the batch.
        channels: The learner's channels (default: PortSample's [qdot, u, tau_obs])."""

    def __init__(self, *, settings: Learner, num_joints: int, period: float,
                 trials: int = 1, channels: Optional[Channels] = None):
        super().__init__()
        self._n, self._trials = num_joints, trials
        self._layout = PortSample(num_joints)
        self._channels = channels or PortSampleChannels(num_joints)
        self._cascade = BandPassCascade(settings.band[0], settings.band[1],
                                        settings.band_sections[0],
                                        settings.band_sections[1], period)
        self._width = self._channels.size * trials
        self._port_sample = self.DeclareVectorInputPort("port_sample",
                                                        self._layout.size * trials)
        self._sections = self.DeclareDiscreteState(self._cascade.num_sections
                                                   * self._width)
        self._filtered = self.DeclareDiscreteState(
            (2 * num_joints + self._channels.size) * trials)
        self.DeclareStateOutputPort("filtered_sample", self._filtered)
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._UpdateFilter)

    def _UpdateFilter(self, context, discrete_state):
        n, trials = self._n, self._trials
        samples = self._port_sample.Eval(context).reshape(trials, -1)
        channels = self._channels.Of(context.get_time(), samples).reshape(-1)
        sections = context.get_discrete_state(self._sections).get_value().reshape(
            -1, self._width)
        sections, filtered = self._cascade.Step(sections, channels)
        discrete_state.get_mutable_vector(self._sections).SetFromVector(
            sections.reshape(-1))
        discrete_state.get_mutable_vector(self._filtered).SetFromVector(
            np.concatenate([samples[:, :2 * n], filtered.reshape(trials, -1)],
                           axis=1).reshape(-1))
