"""Online learner of the RHS (paper section "RHS Control and Learning"; learning/)."""
from typing import Sequence

import numpy as np
from pydrake.systems.framework import LeafSystem

from dacph_drake.learning import LearnerTrial, make_port_learner
from dacph_drake.log_layout import LearnerLog
from dacph_drake.scenario import Learner
from dacph_drake.systems.reduced_model_input import ReducedModelInput


class RhsLearner(LeafSystem):
    """The slowest loop, learning the port relation online: every ``sample_period``
    ``port_sample`` joins a ring buffer of ``settings.window`` samples, fitted every
    ``period`` (learning.make_port_learner). With ``watch_model`` a new ``model_epoch`` is
    a change (settings.model_change); a kinematic mismatch (``identification_log``) zeroes
    the log's ``physical``. Outputs ``weights`` (held), ``beta_hat``, ``learner_log``,
    ``estimates`` [vec(B_hat(x)), diag(D_hat(x))] and ``estimate_bounds`` (credible [lower,
    upper]) at the current state, each stacking the trials'.

    Args:
        trials: Each trial's LearnerTrial.
        settings: The learner's settings (scenario.learner).
        period: The training period [s].
        sample_period: The sampling period [s].
        learning: False publishes the prior (B0, D0) throughout (the dac-nominal ablation).
        watch_model: Declare inputs ``model_epoch`` and ``identification_log``."""

    def __init__(self, *, trials: Sequence[LearnerTrial], settings: Learner,
                 period: float, sample_period: float, learning: bool = True,
                 watch_model: bool = False):
        super().__init__()
        n = len(trials[0].B0)
        count = len(trials)
        self._n, self._trials = n, count
        self._settings = settings
        self._learning = learning
        self.learner = make_port_learner(settings, trials, period, sample_period)
        self.model = self.learner.model
        self._band_passed = type(self.learner).BandPassed(settings)
        sample_size = (2 * n + self.learner.channels.size if self._band_passed else 5 * n)
        self._row_width = 1 + sample_size
        self._q = self.DeclareVectorInputPort("q", n * count)
        self._qdot = self.DeclareVectorInputPort("qdot", n * count)
        self._port_sample = self.DeclareVectorInputPort("port_sample", sample_size * count)
        self._reduced_model = ReducedModelInput(self, n, [t.model for t in trials])
        self._buffer = self.DeclareDiscreteState(settings.window * self._row_width * count)
        self._count = self.DeclareDiscreteState(1)
        self._state = self.DeclareDiscreteState(self.learner.InitialState().reshape(-1))
        self._weights = self.DeclareDiscreteState(self.learner.Prior().reshape(-1))
        # The LHS model's epoch at the last check (settings.model_change).
        self._model_epoch = self._last_epoch = None
        self._identification = None
        if watch_model:
            self._model_epoch = self.DeclareVectorInputPort("model_epoch", count)
            self._last_epoch = self.DeclareDiscreteState(count)
            self._identification = self.DeclareVectorInputPort("identification_log",
                                                               3 * count)
        log = LearnerLog()
        initial_log = np.zeros(log.size)
        initial_log[[log.loss, log.nominal_loss]] = np.nan
        initial_log[log.beta_hat] = 1.0
        initial_log[log.undetermined] = initial_log[log.physical] = 1.0
        self._log = self.DeclareDiscreteState(np.tile(initial_log, count))
        beta_hat = np.arange(count) * log.size + log.beta_hat
        self.DeclareStateOutputPort("weights", self._weights)
        self.DeclareVectorOutputPort(
            "beta_hat", count, lambda c, o: o.SetFromVector(
                c.get_discrete_state(self._log).get_value()[beta_hat]),
            prerequisites_of_calc={self.discrete_state_ticket(self._log)})
        self.DeclareStateOutputPort("learner_log", self._log)
        tickets = {self.discrete_state_ticket(self._weights), self._q.ticket(),
                   self._qdot.ticket(), self._reduced_model.port.ticket(),
                   self.time_ticket()}
        self.DeclareVectorOutputPort("estimates", (n * n + n) * count,
                                     self._CalcEstimates, prerequisites_of_calc=tickets)
        self.DeclareVectorOutputPort("estimate_bounds", 2 * (n * n + n) * count,
                                     self._CalcEstimateBounds,
                                     prerequisites_of_calc=tickets)
        self.DeclarePeriodicDiscreteUpdateEvent(sample_period, 0.0, self._UpdateSample)
        self.DeclarePeriodicDiscreteUpdateEvent(period, period, self._UpdateTraining)

    def _UpdateSample(self, context, discrete_state):
        width, window, count = self._row_width, self._settings.window, self._trials
        samples = int(context.get_discrete_state(self._count).get_value()[0])
        buffer = discrete_state.get_mutable_vector(self._buffer).get_mutable_value(
            ).reshape(count, window, width)
        buffer[:, samples % window, 0] = context.get_time()
        buffer[:, samples % window, 1:] = self._port_sample.Eval(context).reshape(count, -1)
        discrete_state.get_mutable_vector(self._count).SetFromVector([samples + 1])

    def _UpdateTraining(self, context, discrete_state):
        samples = int(context.get_discrete_state(self._count).get_value()[0])
        if samples < 2:
            return
        window, count = self._settings.window, self._trials
        held = min(samples, window)
        order = (np.arange(samples - held, samples) % window)
        rows = context.get_discrete_state(self._buffer).get_value().reshape(
            count, window, self._row_width)[:, order]
        state = context.get_discrete_state(self._state).get_value().reshape(count, -1)
        published, logs, state = self.learner.Update(
            context.get_time(), rows, state, self._ModelChanges(context, discrete_state),
            self._learning)
        logs[:, LearnerLog().physical] = 1.0
        if self._identification is not None and self._identification.HasValue(context):
            mismatch = self._identification.Eval(context).reshape(count, 3)[:, 2]
            logs[:, LearnerLog().physical] = mismatch < 0.5
        discrete_state.get_mutable_vector(self._state).SetFromVector(state.reshape(-1))
        discrete_state.get_mutable_vector(self._weights).SetFromVector(
            published.reshape(-1))
        discrete_state.get_mutable_vector(self._log).SetFromVector(logs.reshape(-1))

    def _ModelChanges(self, context, discrete_state) -> np.ndarray:
        """Whether each trial's LHS model epoch changed since the last check (recorded)."""
        if (self._model_epoch is None or not self._model_epoch.HasValue(context)
                or not (self._band_passed and self._settings.model_change)):
            return np.zeros(self._trials, bool)
        epoch = self._model_epoch.Eval(context)
        changed = epoch != context.get_discrete_state(self._last_epoch).get_value()
        if np.any(changed):
            discrete_state.get_mutable_vector(self._last_epoch).SetFromVector(epoch)
        return changed

    def _Estimate(self, context):
        n, count = self._n, self._trials
        q = self._q.Eval(context).reshape(count, n)
        qdot = self._qdot.Eval(context).reshape(count, n)
        p = self._reduced_model.Momenta(context, q, qdot)
        return self.model.Estimate(
            context.get_discrete_state(self._weights).get_value().reshape(count, -1),
            context.get_time(), q, p)

    def _CalcEstimates(self, context, output):
        estimate, count = self._Estimate(context), self._trials
        output.SetFromVector(np.concatenate([estimate.B.reshape(count, -1), estimate.D],
                                            axis=1).reshape(-1))

    def _CalcEstimateBounds(self, context, output):
        estimate, count = self._Estimate(context), self._trials
        bounds = [np.concatenate([estimate.B_interval[k].reshape(count, -1),
                                  estimate.D_interval[k]], axis=1) for k in range(2)]
        output.SetFromVector(np.concatenate(bounds, axis=1).reshape(-1))
