"""Online learner of the RHS (paper's physics-informed network, SPEC section 6)."""
import numpy as np
import torch
from pydrake.systems.framework import LeafSystem

from dacph_drake.network import ExportedNetwork, RhsNetwork
from dacph_drake.reduced_model import ReducedOrderModel
from dacph_drake.scenario import Learner


class RhsLearner(LeafSystem):
    """The slowest loop. Every ``sample_period`` it appends (q, p, qdot, u, tau_obs)
    to a ring buffer of ``window`` samples (discrete state); every ``period`` it takes
    ``steps_per_update`` Adam steps on the buffer, minimizing the mean of
    ||tau_obs - (B_hat(x) u - D_hat(x) qdot)||^2, and publishes the weights.

    Outputs: ``weights`` (the exported parameter vector, held between updates; the
    fast loops evaluate it with numpy), ``beta_hat`` = 1 + RMS residual / RMS tau_obs
    over the window (an empirical multiplicative uncertainty of the learned RHS, used
    by the gain rule), ``learner_log`` = [loss, beta_hat, nominal_loss] where
    nominal_loss is the same loss of the nominal RHS (B0, D0) on the same window (the
    learner's loss relative to the prior it started from), and ``estimates`` =
    [vec(B_hat(x)), diag(D_hat(x))] at the current state, for the metrics.

    The torch module and Adam's moments live in this object, not in the Context:
    a diagram with a learner simulates one trajectory at a time (build one diagram
    per run, as the package's builders do)."""

    def __init__(self, model: ReducedOrderModel, settings: Learner, period: float,
                 sample_period: float, num_positions: int, B0, D0,
                 momentum_scale: float, seed: int):
        super().__init__()
        n = model.num_joints
        self._n, self._nq, self._model = n, num_positions, model
        self._settings = settings
        self._B0 = torch.as_tensor(np.diag(B0), dtype=torch.float64)
        self._D0 = torch.as_tensor(np.asarray(D0, float))
        torch.set_num_threads(1)
        self._net = RhsNetwork(n, settings.hidden, np.diag(B0), D0, momentum_scale, seed)
        self._optimizer = torch.optim.Adam(
            self._net.parameters(), lr=settings.learning_rate,
            betas=(settings.beta1, settings.beta2), eps=settings.eps)
        self.exported = ExportedNetwork(n, settings.hidden, momentum_scale)
        self.initial_weights = self._net.export()
        self._state = self.DeclareVectorInputPort("state", 2 * num_positions)
        self._u = self.DeclareVectorInputPort("u", n)
        self._tau_observed = self.DeclareVectorInputPort("tau_observed", n)
        # Buffer: window rows of (q, p, qdot, u, tau) and the number of samples taken.
        self._buffer = self.DeclareDiscreteState(settings.window * 5 * n + 1)
        self._weights = self.DeclareDiscreteState(self.initial_weights)
        self._stats = self.DeclareDiscreteState(np.array([np.nan, 1.0, np.nan]))
        self.DeclareStateOutputPort("weights", self._weights)
        self.DeclareVectorOutputPort(
            "beta_hat", 1, lambda c, o: o.SetFromVector(
                c.get_discrete_state(self._stats).get_value()[1:2]),
            prerequisites_of_calc={self.discrete_state_ticket(self._stats)})
        self.DeclareStateOutputPort("learner_log", self._stats)
        self.DeclareVectorOutputPort(
            "estimates", n * n + n, self._CalcEstimates,
            prerequisites_of_calc={self.discrete_state_ticket(self._weights),
                                   self._state.ticket()})
        self.DeclarePeriodicDiscreteUpdateEvent(sample_period, 0.0, self._UpdateSample)
        self.DeclarePeriodicDiscreteUpdateEvent(period, period, self._UpdateTraining)

    def _QPQdot(self, context):
        x = self._state.Eval(context)
        q, qdot = x[3:self._nq], x[self._nq + 3:]
        return q, self._model.Momentum(q, qdot), qdot

    def _UpdateSample(self, context, discrete_state):
        n, window = self._n, self._settings.window
        q, p, qdot = self._QPQdot(context)
        buffer = context.get_discrete_state(self._buffer).get_value().copy()
        count = int(buffer[-1])
        row = count % window
        buffer[row * 5 * n:(row + 1) * 5 * n] = np.concatenate(
            [q, p, qdot, self._u.Eval(context), self._tau_observed.Eval(context)])
        buffer[-1] = count + 1
        discrete_state.get_mutable_vector(self._buffer).SetFromVector(buffer)

    def _UpdateTraining(self, context, discrete_state):
        n, window = self._n, self._settings.window
        buffer = context.get_discrete_state(self._buffer).get_value()
        count = min(int(buffer[-1]), window)
        if count < 2 or self._settings.steps_per_update == 0:
            return
        data = torch.tensor(buffer[:count * 5 * n].reshape(count, 5, n))
        q, p, qdot, u, tau = data.unbind(dim=1)
        for _ in range(self._settings.steps_per_update):
            self._optimizer.zero_grad()
            loss = torch.mean(torch.sum((tau - self._net.predict(q, p, qdot, u))**2, 1))
            loss.backward()
            self._optimizer.step()
        with torch.no_grad():
            residual = torch.sum((tau - self._net.predict(q, p, qdot, u))**2, 1)
            loss = float(torch.mean(residual))
            beta = 1.0 + float(torch.sqrt(torch.mean(residual)
                                          / torch.clamp(torch.mean(torch.sum(tau**2, 1)),
                                                        min=1e-30)))
            nominal = tau - (u @ self._B0.T - self._D0 * qdot)
            nominal_loss = float(torch.mean(torch.sum(nominal**2, 1)))
        discrete_state.get_mutable_vector(self._weights).SetFromVector(self._net.export())
        discrete_state.get_mutable_vector(self._stats).SetFromVector(
            [loss, beta, nominal_loss])

    def _CalcEstimates(self, context, output):
        q, p, _ = self._QPQdot(context)
        B, D = self.exported.Evaluate(
            context.get_discrete_state(self._weights).get_value(), q, p)
        output.SetFromVector(np.concatenate([B.reshape(-1), D]))
