"""Port observer (paper eq. for tau_breve, SPEC section 5)."""
import numpy as np
from pydrake.systems.framework import LeafSystem

from dacph_drake.identification import PortSample
from dacph_drake.kernels.loop import observed_port_torque


class PortObserver(LeafSystem):
    """tau_obs = M(q) qddot + C'(q, qdot) qdot (+ seeded Gaussian measurement noise)
    from the measured joint rates, over each sample interval [t_k-1, t_k] of length
    h = ``sample_period`` (the RHS period):

        qddot = (qdot(t_k) - qdot(t_k-1)) / h,   qdot_mid = (qdot(t_k) + qdot(t_k-1)) / 2
        tau_obs(k) = M qddot + C' qdot_mid

    the port torque at the interval's midpoint (second-order accurate: the mean
    of the port torque over the interval, during which the plant received the held
    u(k-1)). M and C' are input ``reduced_model`` = [vec(M), vec(C')], the LHS
    controller's evaluation of the controller's (nominal) reduced model at its last
    sample (they change on the seconds scale of the arm's motion). Output
    ``tau_observed`` is held until the next sample: the RHS integrator reads it one
    sample later, as it would read a sample-and-hold sensor.

    Output ``port_sample`` (identification.PortSample) = [q, p = M qdot_mid,
    qdot_mid, u, tau_obs] of the same interval: u is the input ``u`` held over it
    (the RHS integrator's output before its update at this sample), so
    tau_obs = B~ u - D~ qdot + d holds on every sample. With ``anti_alias_cutoff``
    f > 0, [qdot, u, tau_obs] pass a first-order low-pass at f Hz at the sample rate
    (before the learner samples them at a lower rate).

    Inputs ``state`` (plant state), ``reduced_model`` and ``u``."""

    def __init__(self, *, num_joints: int, num_positions: int, sample_period: float,
                 noise_std: float, seed: int, anti_alias_cutoff: float = 0.0):
        super().__init__()
        n = num_joints
        self._n, self._nq, self._h = n, num_positions, sample_period
        self._rng = np.random.default_rng(seed)
        self._noise_std = noise_std
        self._layout = PortSample(n)
        self._anti_alias = (1.0 - np.exp(-2 * np.pi * anti_alias_cutoff * sample_period)
                            if anti_alias_cutoff > 0 else 1.0)
        self._state = self.DeclareVectorInputPort("state", 2 * num_positions)
        self._reduced_model = self.DeclareVectorInputPort("reduced_model", 2 * n * n)
        self._u = self.DeclareVectorInputPort("u", n)
        self._tau_index = self.DeclareDiscreteState(n)
        self._previous_qdot = self.DeclareDiscreteState(n)
        self._sample_index = self.DeclareDiscreteState(self._layout.size)
        self.DeclareStateOutputPort("tau_observed", self._tau_index)
        self.DeclareStateOutputPort("port_sample", self._sample_index)
        self.DeclarePeriodicDiscreteUpdateEvent(sample_period, 0.0, self._UpdateSample)
        self.DeclareInitializationDiscreteUpdateEvent(self._InitializeRates)

    def _InitializeRates(self, context, discrete_state):
        discrete_state.get_mutable_vector(self._previous_qdot).SetFromVector(
            self._state.Eval(context)[self._nq + 3:])

    def _UpdateSample(self, context, discrete_state):
        x = self._state.Eval(context)
        qdot = x[self._nq + 3:]
        tau, p, qdot_mid = observed_port_torque(
            qdot, context.get_discrete_state(self._previous_qdot).get_value(),
            self._reduced_model.Eval(context), self._h)
        if self._noise_std > 0:
            tau = tau + self._noise_std * self._rng.standard_normal(self._n)
        discrete_state.get_mutable_vector(self._tau_index).SetFromVector(tau)
        discrete_state.get_mutable_vector(self._previous_qdot).SetFromVector(qdot)
        if not self._u.HasValue(context):
            return
        L = self._layout
        sample = context.get_discrete_state(self._sample_index).get_value().copy()
        sample[L.q], sample[L.p] = x[3:self._nq], p
        regressed = np.concatenate([qdot_mid, self._u.Eval(context), tau])
        sample[L.regressed] += self._anti_alias * (regressed - sample[L.regressed])
        discrete_state.get_mutable_vector(self._sample_index).SetFromVector(sample)
