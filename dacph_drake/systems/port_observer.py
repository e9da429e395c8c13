"""Port observer (docs/equations.md E32)."""
from typing import Sequence

import numpy as np
from pydrake.systems.framework import LeafSystem

from dacph_drake.learning.identification import PortSample
from dacph_drake.kernels.loop import observer_samples


class PortObserver(LeafSystem):
    """Port torque observer over each sample interval, h = ``sample_period`` (E32):

        qddot = (qdot(t_k) - qdot(t_k-1)) / h,   qdot_mid = (qdot(t_k) + qdot(t_k-1)) / 2
        tau_obs(k) = M qddot + C' qdot_mid + b qdot_mid   (+ seeded Gaussian noise)

    held until the next sample; M, C' from input ``reduced_model``, so tau_obs =
    B~ u - D~ qdot + d. Output ``port_sample`` = [q, p, qdot_mid, u, tau_obs].

    Args:
        num_joints: n.
        sample_period: The observer's period h [s].
        noise_std: The standard deviation of the measurement noise on tau_obs [N m].
        seeds: Each trial's noise seed (one per stacked trial).
        anti_alias_cutoff: Cutoff [Hz] of a low-pass on [qdot, u, tau_obs] (0: none).
        joint_damping: b (n) [N m s/rad] (none: zero)."""

    def __init__(self, *, num_joints: int, sample_period: float, noise_std: float,
                 seeds: Sequence[int], anti_alias_cutoff: float = 0.0,
                 joint_damping: Sequence[float] = ()):
        super().__init__()
        n, trials = num_joints, len(seeds)
        self._n, self._trials = n, trials
        self._rngs = [np.random.default_rng(seed) for seed in seeds]
        self._noise_std = noise_std
        self._layout = PortSample(n)
        self._anti_alias = (1.0 - np.exp(-2 * np.pi * anti_alias_cutoff * sample_period)
                            if anti_alias_cutoff > 0 else 1.0)
        self._q = self.DeclareVectorInputPort("q", n * trials)
        self._qdot = self.DeclareVectorInputPort("qdot", n * trials)
        self._reduced_model = self.DeclareVectorInputPort("reduced_model",
                                                          2 * n * n * trials)
        self._u = self.DeclareVectorInputPort("u", n * trials)
        self._constants = np.concatenate([
            [sample_period, self._anti_alias],
            np.asarray(joint_damping, float) if len(joint_damping) else np.zeros(n)])
        self._no_noise, self._no_u = np.zeros(n * trials), np.zeros(n * trials)
        self._tau_index = self.DeclareDiscreteState(n * trials)
        # Memory: per trial [qdot(k-1) (n), port_sample (5 n)].
        width = n + self._layout.size
        self._memory_index = self.DeclareDiscreteState(width * trials)
        self._rates = np.concatenate([np.arange(n) + width * i for i in range(trials)])
        self._samples = np.concatenate([np.arange(n, width) + width * i
                                        for i in range(trials)])
        self.DeclareStateOutputPort("tau_observed", self._tau_index)
        self.DeclareVectorOutputPort(
            "port_sample", self._layout.size * trials,
            lambda context, output: output.SetFromVector(
                context.get_discrete_state(self._memory_index).get_value()[
                    self._samples]),
            prerequisites_of_calc={self.discrete_state_ticket(self._memory_index)})
        self.DeclarePeriodicDiscreteUpdateEvent(sample_period, 0.0, self._UpdateSample)
        self.DeclareInitializationDiscreteUpdateEvent(self._InitializeRates)

    def _InitializeRates(self, context, discrete_state):
        discrete_state.get_mutable_vector(self._memory_index).get_mutable_value()[
            self._rates] = self._qdot.Eval(context)

    def _UpdateSample(self, context, discrete_state):
        n, trials = self._n, self._trials
        noise = (self._noise_std * np.concatenate([rng.standard_normal(n)
                                                   for rng in self._rngs])
                 if self._noise_std > 0 else self._no_noise)
        tau, memory = observer_samples(
            trials, self._q.Eval(context), self._qdot.Eval(context),
            context.get_discrete_state(self._memory_index).get_value(),
            self._reduced_model.Eval(context),
            self._u.Eval(context) if self._u.HasValue(context) else self._no_u,
            noise, self._constants)
        discrete_state.get_mutable_vector(self._tau_index).SetFromVector(tau)
        discrete_state.get_mutable_vector(self._memory_index).SetFromVector(memory)
