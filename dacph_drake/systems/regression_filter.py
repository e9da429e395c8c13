"""Band-pass prefilter of the learner's port samples (Learner.band; a project extension, docs/equations.md E33)."""
import numpy as np
from pydrake.systems.framework import LeafSystem

from dacph_drake.identification import BandPassCascade, PortSample
from dacph_drake.scenario import Learner


class RegressionFilter(LeafSystem):
    """Every ``period`` it passes the [qdot, u, tau_obs] part of the input
    ``port_sample`` through identification.BandPassCascade (settings.band,
    settings.band_sections) and holds [q, p, filtered qdot, u, tau_obs] on the
    output ``filtered_sample``.

    The same linear filter on every signal keeps the port relation
    tau = B u - D qdot + d for the filtered signals while B(x), D(x) vary slowly
    against the filter's memory, and removes d(t) where it lies outside the band.
    q and p pass unfiltered: they are the network's features. For a batch of
    ``trials`` trials every port carries the trials' samples stacked, each
    filtered alone (the cascade acts entry by entry).

    Args:
        settings: The learner's settings (its band and sections).
        num_joints: n.
        period: The sample period [s] (periods.learner_sample).
        trials: The number of trials of the batch.
    """

    def __init__(self, *, settings: Learner, num_joints: int, period: float,
                 trials: int = 1):
        super().__init__()
        self._layout = PortSample(num_joints)
        self._cascade = BandPassCascade(settings.band[0], settings.band[1],
                                        settings.band_sections[0],
                                        settings.band_sections[1], period)
        size = self._layout.size
        self._regressed = np.concatenate([
            np.arange(size)[self._layout.regressed] + size * i for i in range(trials)])
        width = 3 * num_joints * trials
        self._port_sample = self.DeclareVectorInputPort("port_sample", size * trials)
        self._sections = self.DeclareDiscreteState(self._cascade.num_sections * width)
        self._filtered = self.DeclareDiscreteState(size * trials)
        self._width = width
        self.DeclareStateOutputPort("filtered_sample", self._filtered)
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._UpdateFilter)

    def _UpdateFilter(self, context, discrete_state):
        sample = self._port_sample.Eval(context).copy()
        sections = context.get_discrete_state(self._sections).get_value().reshape(
            -1, self._width)
        sections, sample[self._regressed] = self._cascade.Step(sections,
                                                               sample[self._regressed])
        discrete_state.get_mutable_vector(self._sections).SetFromVector(
            sections.reshape(-1))
        discrete_state.get_mutable_vector(self._filtered).SetFromVector(sample)
