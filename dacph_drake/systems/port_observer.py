"""Port observer (paper eq. for tau_breve, SPEC section 5)."""
import numpy as np
from pydrake.systems.framework import LeafSystem

from dacph_drake.identification import PortSample
from dacph_drake.reduced_model import ReducedOrderModel


class PortObserver(LeafSystem):
    """tau_obs = M(q) qddot + C'(q, qdot) qdot (+ seeded Gaussian measurement noise)
    from the measured joint angles, rates and accelerations, with the controller's
    own (nominal) reduced model.

    Two rates: every ``sample_period`` (the RHS period) it samples qdot and qddot and
    outputs ``tau_observed`` (held: a sample-and-hold measurement, one sample of
    delay); every ``model_period`` (the LHS period) it refreshes M and C' at the
    sampled state (they change on the seconds scale of the arm's motion; set
    model_period = sample_period for a refresh at every sample).

    Output ``port_sample`` (identification.PortSample) = [q, p = M q_dot, qdot, u,
    tau_obs] of the same instant: u is the input ``u`` as the plant received it when
    qddot was measured (the RHS integrator's output before its update at this
    sample), so tau_obs = B~ u - D~ qdot + d holds on every sample. With
    ``anti_alias_cutoff`` f > 0, [qdot, u, tau_obs] pass a first-order low-pass at f
    Hz at the sample rate (before the learner samples them at a lower rate).

    Inputs ``state`` (plant state), ``acceleration`` (plant generalized
    accelerations) and ``u`` (the RHS input, for port_sample)."""

    def __init__(self, model: ReducedOrderModel, num_positions: int,
                 sample_period: float, model_period: float, noise_std: float,
                 seed: int, *, anti_alias_cutoff: float = 0.0):
        super().__init__()
        n = model.num_joints
        self._n, self._model = n, model
        self._nq = num_positions
        self._rng = np.random.default_rng(seed)
        self._noise_std = noise_std
        self._layout = PortSample(n)
        self._anti_alias = (1.0 - np.exp(-2 * np.pi * anti_alias_cutoff * sample_period)
                            if anti_alias_cutoff > 0 else 1.0)
        self._state = self.DeclareVectorInputPort("state", 2 * num_positions)
        self._acceleration = self.DeclareVectorInputPort("acceleration", num_positions)
        self._u = self.DeclareVectorInputPort("u", n)
        self._tau_index = self.DeclareDiscreteState(n)
        self._model_index = self.DeclareDiscreteState(2 * n * n)
        self._sample_index = self.DeclareDiscreteState(self._layout.size)
        self.DeclareStateOutputPort("tau_observed", self._tau_index)
        self.DeclareStateOutputPort("port_sample", self._sample_index)
        self.DeclarePeriodicDiscreteUpdateEvent(sample_period, 0.0, self._UpdateSample)
        self.DeclarePeriodicDiscreteUpdateEvent(model_period, 0.0, self._UpdateModel)
        self.DeclareInitializationDiscreteUpdateEvent(self._UpdateModel)

    def _UpdateModel(self, context, discrete_state):
        x = self._state.Eval(context)
        r = self._model.Evaluate(x[3:self._nq], x[self._nq + 3:])
        discrete_state.get_mutable_vector(self._model_index).SetFromVector(
            np.concatenate([r.M.reshape(-1), r.C.reshape(-1)]))

    def _UpdateSample(self, context, discrete_state):
        n = self._n
        MC = context.get_discrete_state(self._model_index).get_value()
        M = MC[:n * n].reshape(n, n)
        x = self._state.Eval(context)
        qdot = x[self._nq + 3:]
        qddot = self._acceleration.Eval(context)[3:]
        tau = M @ qddot + MC[n * n:].reshape(n, n) @ qdot
        if self._noise_std > 0:
            tau = tau + self._noise_std * self._rng.standard_normal(n)
        discrete_state.get_mutable_vector(self._tau_index).SetFromVector(tau)
        if not self._u.HasValue(context):
            return
        L = self._layout
        sample = context.get_discrete_state(self._sample_index).get_value().copy()
        sample[L.q], sample[L.p] = x[3:self._nq], M @ qdot
        regressed = np.concatenate([qdot, self._u.Eval(context), tau])
        sample[L.regressed] += self._anti_alias * (regressed - sample[L.regressed])
        discrete_state.get_mutable_vector(self._sample_index).SetFromVector(sample)
