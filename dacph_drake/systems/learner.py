"""Online learner of the RHS (paper's physics-informed network, docs/equations.md E33-E35)."""
import numpy as np
from pydrake.systems.framework import LeafSystem

from dacph_drake.identification import (ChangeDetector, NewestRows, PortSample,
                                        RhsIdentifier)
from dacph_drake.log_layout import LearnerLog
from dacph_drake.network import ExportedNetwork
from dacph_drake.dynamics import ReducedModel
from dacph_drake.scenario import Learner
from dacph_drake.systems.reduced_model_input import ReducedModelInput


class RhsLearner(LeafSystem):
    """The slowest loop. Every ``sample_period`` it appends the input
    ``port_sample`` (identification.PortSample: the observer's consistent
    [q, p, qdot, u, tau_obs], band-passed by a RegressionFilter in regularized mode)
    with its time to a ring buffer of ``settings.window`` samples; every ``period``
    it fits the network on the buffer (identification.RhsIdentifier: the paper's
    loss in plain mode, the prior-regularized, recency-weighted one in regularized
    mode) and publishes the weights. In regularized mode a ChangeDetector watches the
    relative residual of the newest samples and pauses training after an abrupt
    change (settings.change_*), for settings.start_hold seconds from the start and
    after the LHS model changed (input ``model_epoch``, declared with
    ``watch_model``: settings.model_change);
    a fit needs settings.min_window seconds of samples in the window, and the first
    fit of the run starts from the window's best constant B (settings.warm_start,
    RhsIdentifier.WarmStart). With settings.prior_fallback the published weights
    are the prior's (B_hat = B0, D_hat = D0) whenever the network does not beat
    them on the samples since the last change (_NetworkPublished).

    Outputs: ``weights`` (the exported parameter vector, held between updates; the
    fast loops evaluate it with numpy), ``beta_hat`` (FitStatistics.beta_hat, used
    by the gain rule), ``learner_log`` (log_layout.LearnerLog: loss, beta_hat,
    nominal loss of (B0, D0) on the same samples, and whether training is paused)
    and ``estimates`` = [vec(B_hat(x)), diag(D_hat(x))] at the current plant state
    (p = M qdot with the LHS's M, input ``reduced_model``, as the integrator forms
    it), for the metrics. With ``learning`` False the network keeps its initial weights
    (B_hat = B0, D_hat = D0): the dac-nominal ablation. The network's coupling
    scale (settings.coupling, network.coupling_factors) reads the joints' inertias
    diag M(q0) of ``model`` at the start configuration ``q0``.

    The torch module and Adam's moments live in this object, not in the Context:
    a diagram with a learner simulates one trajectory at a time (build one diagram
    per run, as the package's builders do)."""

    def __init__(self, *, model: ReducedModel, settings: Learner, period: float,
                 sample_period: float, B0, D0, seed: int, q0,
                 learning: bool = True, watch_model: bool = False):
        super().__init__()
        n = model.num_joints
        self._n, self._model = n, model
        self._period = period
        self._settings = settings
        self._learning = learning and settings.steps_per_update > 0
        self._regularized = settings.mode == "regularized"
        # Samples the window must hold before a fit (settings.min_window), at least 2.
        self._min_samples = max(2, int(round(settings.min_window / sample_period)))
        self._network = ExportedNetwork.ForLearner(settings, model, q0)
        self._identifier = RhsIdentifier(n, settings, np.diag(B0), D0, seed,
                                         self._network.coupling)
        self._detector = ChangeDetector(settings.change_ratio, settings.change_floor,
                                        settings.change_hold)
        initial_weights = self._prior_weights = self._identifier.Export()
        width = 1 + PortSample(n).size
        self._row_width = width
        self._q = self.DeclareVectorInputPort("q", n)
        self._qdot = self.DeclareVectorInputPort("qdot", n)
        self._port_sample = self.DeclareVectorInputPort("port_sample", width - 1)
        self._reduced_model = ReducedModelInput(self, n, model)
        self._buffer = self.DeclareDiscreteState(settings.window * width)
        self._count = self.DeclareDiscreteState(1)
        self._detector_state = self.DeclareDiscreteState(ChangeDetector.InitialState(
            settings.start_hold if self._regularized and settings.start_hold > 0
            else -np.inf))
        self._weights = self.DeclareDiscreteState(initial_weights)
        # The window start of the warm start (settings.warm_start), -inf before it.
        self._warm_started = self.DeclareDiscreteState([-np.inf])
        # The LHS model's epoch at the last check (settings.model_change).
        self._model_epoch = self._last_epoch = None
        if watch_model:
            self._model_epoch = self.DeclareVectorInputPort("model_epoch", 1)
            self._last_epoch = self.DeclareDiscreteState(1)
        log = LearnerLog()
        initial_log = np.zeros(log.size)
        initial_log[[log.loss, log.nominal_loss]] = np.nan
        initial_log[log.beta_hat] = 1.0
        self._log = self.DeclareDiscreteState(initial_log)
        self.DeclareStateOutputPort("weights", self._weights)
        self.DeclareVectorOutputPort(
            "beta_hat", 1, lambda c, o: o.SetFromVector(
                c.get_discrete_state(self._log).get_value()[log.beta_hat:log.beta_hat + 1]),
            prerequisites_of_calc={self.discrete_state_ticket(self._log)})
        self.DeclareStateOutputPort("learner_log", self._log)
        self.DeclareVectorOutputPort(
            "estimates", n * n + n, self._CalcEstimates,
            prerequisites_of_calc={self.discrete_state_ticket(self._weights),
                                   self._q.ticket(), self._qdot.ticket(),
                                   self._reduced_model.port.ticket()})
        self.DeclarePeriodicDiscreteUpdateEvent(sample_period, 0.0, self._UpdateSample)
        self.DeclarePeriodicDiscreteUpdateEvent(period, period, self._UpdateTraining)

    def _UpdateSample(self, context, discrete_state):
        width, window = self._row_width, self._settings.window
        count = int(context.get_discrete_state(self._count).get_value()[0])
        buffer = context.get_discrete_state(self._buffer).get_value().copy()
        row = count % window
        buffer[row * width:(row + 1) * width] = np.concatenate(
            [[context.get_time()], self._port_sample.Eval(context)])
        discrete_state.get_mutable_vector(self._buffer).SetFromVector(buffer)
        discrete_state.get_mutable_vector(self._count).SetFromVector([count + 1])

    def _UpdateTraining(self, context, discrete_state):
        count = int(context.get_discrete_state(self._count).get_value()[0])
        if count < 2:
            return
        t = context.get_time()
        rows = context.get_discrete_state(self._buffer).get_value().reshape(
            -1, self._row_width)[:min(count, self._settings.window)]
        detector = context.get_discrete_state(self._detector_state).get_value()
        detector = self._ModelChange(context, discrete_state, detector, t)
        if self._regularized and self._learning:
            newest = NewestRows(rows, t, self._period)
            if newest is not None:
                detector = self._detector.Update(
                    detector, t, self._identifier.RelativeResidual(newest))
            discrete_state.get_mutable_vector(self._detector_state).SetFromVector(detector)
        holding = ChangeDetector.Holding(detector, t)
        window_start = ChangeDetector.WindowStart(detector)
        fitted = (self._learning and not holding
                  and np.count_nonzero(rows[:, 0] >= window_start) >= self._min_samples)
        if fitted:
            warm_started = context.get_discrete_state(self._warm_started).get_value()[0]
            if (self._regularized and self._settings.warm_start
                    and warm_started == -np.inf):
                self._identifier.WarmStart(rows, t, window_start)
                discrete_state.get_mutable_vector(self._warm_started).SetFromVector(
                    [window_start])
            self._identifier.Fit(rows, t, window_start)
        stats = self._identifier.Statistics(rows, t)
        published = self._learning and self._NetworkPublished(rows, t, window_start,
                                                               fitted)
        if self._learning:
            discrete_state.get_mutable_vector(self._weights).SetFromVector(
                self._identifier.Export() if published else self._prior_weights)
        log = LearnerLog()
        values = np.zeros(log.size)
        values[[log.loss, log.beta_hat, log.nominal_loss, log.holding,
                log.network_published]] = [stats.loss, stats.beta_hat,
                                           stats.nominal_loss, float(holding),
                                           float(published)]
        discrete_state.get_mutable_vector(self._log).SetFromVector(values)

    def _NetworkPublished(self, rows, t, window_start, fitted) -> bool:
        """Whether the network's weights, not the prior's, are published this update.
        Always, unless settings.prior_fallback: then only when this update fitted
        (not holding after a change, min_window seconds of samples since it) and the
        network explains the samples since the change at least as well as (B0, D0)
        do, FitStatistics.loss <= nominal_loss; the prior otherwise. After a
        change the frozen network describes the old relation, and a refit on the
        first window after it can be further off than the prior."""
        if not self._settings.prior_fallback:
            return True
        if not fitted:
            return False
        current = self._identifier.Statistics(rows, t, window_start)
        return current.loss <= current.nominal_loss

    def _ModelChange(self, context, discrete_state, detector, t):
        """The detector state after checking whether the LHS model changed since the
        last check (input ``model_epoch``, InertialIdentifier's); if so, a change at
        t (ChangeDetector.Changed)."""
        if (self._model_epoch is None or not self._model_epoch.HasValue(context)
                or not (self._regularized and self._settings.model_change)):
            return detector
        epoch = self._model_epoch.Eval(context)
        if not np.array_equal(epoch, context.get_discrete_state(
                self._last_epoch).get_value()):
            discrete_state.get_mutable_vector(self._last_epoch).SetFromVector(epoch)
            detector = self._detector.Changed(detector, t)
            discrete_state.get_mutable_vector(self._detector_state).SetFromVector(detector)
        return detector

    def _CalcEstimates(self, context, output):
        q, qdot = self._q.Eval(context), self._qdot.Eval(context)
        B, D = self._network.Evaluate(
            context.get_discrete_state(self._weights).get_value(), q,
            self._reduced_model.Momentum(context, q, qdot))
        output.SetFromVector(np.concatenate([B.reshape(-1), D]))
