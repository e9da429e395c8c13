"""Online learner of the RHS (paper's physics-informed network, docs/equations.md E33-E35)."""
from dataclasses import dataclass
from typing import Sequence

import numpy as np
from pydrake.systems.framework import LeafSystem

from dacph_drake.identification import (ChangeDetector, NewestRows, PortSample,
                                        RhsIdentifier)
from dacph_drake.log_layout import LearnerLog
from dacph_drake.network import ExportedNetwork, NetworkStack
from dacph_drake.dynamics import ReducedModel
from dacph_drake.scenario import Learner
from dacph_drake.systems.reduced_model_input import ReducedModelInput


@dataclass
class LearnerTrial:
    """One trial's part of an RhsLearner.

    Attributes:
        model: The controller's model (its network's coupling scale reads
            diag M(q0); p = M qdot where input ``reduced_model`` is not connected).
        B0: The prior's B0 (its diagonal, n).
        D0: The prior's D0 (its diagonal, n) [N m s].
        seed: The network's seed.
        q0: The start configuration [rad] (n).
    """
    model: ReducedModel
    B0: Sequence[float]
    D0: Sequence[float]
    seed: int
    q0: Sequence[float]


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
    them on the samples since the last change or on the last period's
    (_NetworkPublished).

    Outputs: ``weights`` (the exported parameter vector, held between updates; the
    fast loops evaluate it compiled), ``beta_hat`` (FitStatistics.beta_hat, used
    by the gain rule), ``learner_log`` (log_layout.LearnerLog: loss, beta_hat,
    nominal loss of (B0, D0) on the same samples, and whether training is paused)
    and ``estimates`` = [vec(B_hat(x)), diag(D_hat(x))] at the current plant state
    (p = M qdot with the LHS's M, input ``reduced_model``, as the integrator forms
    it), for the metrics. With ``learning`` False the network keeps its initial weights
    (B_hat = B0, D_hat = D0): the dac-nominal ablation. The network's coupling
    scale (settings.coupling, network.coupling_factors) reads the joints' inertias
    diag M(q0) of ``model`` at the start configuration ``q0``.

    For a batch (``trials``: each trial's LearnerTrial; one: a single run) every
    port carries the trials' signals stacked, and each trial has a network, Adam
    moments, window and change detector of its own: its updates are its solo
    run's (to round-off), whatever the other trials do. One torch forward and
    backward pass fits every trial that fits this update
    (RhsIdentifier.FitTrials).

    The torch modules and Adam's moments live in this object, not in the Context:
    a diagram with a learner simulates one trajectory at a time (build one diagram
    per run, as the package's builders do).

    Args:
        trials: Each trial's LearnerTrial (model, prior, seed, q0).
        settings: The learner's settings (scenario.learner).
        period: The training period [s] (periods.learner).
        sample_period: The sampling period [s] (periods.learner_sample).
        learning: False keeps the initial weights (the dac-nominal ablation).
        watch_model: Declare input ``model_epoch`` (an InertialIdentifier's).
    """

    def __init__(self, *, trials: Sequence[LearnerTrial], settings: Learner,
                 period: float, sample_period: float, learning: bool = True,
                 watch_model: bool = False):
        super().__init__()
        n = trials[0].model.num_joints
        count = len(trials)
        self._n, self._trials = n, count
        self._period = period
        self._settings = settings
        self._learning = learning and settings.steps_per_update > 0
        self._regularized = settings.mode == "regularized"
        # Samples the window must hold before a fit (settings.min_window), at least 2.
        self._min_samples = max(2, int(round(settings.min_window / sample_period)))
        self._networks = [ExportedNetwork.ForLearner(settings, trial.model, trial.q0)
                          for trial in trials]
        self._network_stack = NetworkStack(self._networks)
        self._identifier = RhsIdentifier.ForTrials(
            n, settings, [np.diag(trial.B0) for trial in trials],
            [trial.D0 for trial in trials], [trial.seed for trial in trials],
            [network.coupling for network in self._networks])
        self._detector = ChangeDetector(settings.change_ratio, settings.change_floor,
                                        settings.change_hold)
        self._prior_weights = self._identifier.Export()
        width = 1 + PortSample(n).size
        self._row_width = width
        self._q = self.DeclareVectorInputPort("q", n * count)
        self._qdot = self.DeclareVectorInputPort("qdot", n * count)
        self._port_sample = self.DeclareVectorInputPort("port_sample", (width - 1) * count)
        self._reduced_model = ReducedModelInput(self, n, [t.model for t in trials])
        self._buffer = self.DeclareDiscreteState(settings.window * width * count)
        self._count = self.DeclareDiscreteState(1)
        self._detector_state = self.DeclareDiscreteState(np.tile(
            ChangeDetector.InitialState(settings.start_hold if self._regularized
                                        and settings.start_hold > 0 else -np.inf),
            count))
        self._weights = self.DeclareDiscreteState(self._prior_weights.reshape(-1))
        # The window start of the warm start (settings.warm_start), -inf before it.
        self._warm_started = self.DeclareDiscreteState(np.full(count, -np.inf))
        # The LHS model's epoch at the last check (settings.model_change).
        self._model_epoch = self._last_epoch = None
        if watch_model:
            self._model_epoch = self.DeclareVectorInputPort("model_epoch", count)
            self._last_epoch = self.DeclareDiscreteState(count)
        log = LearnerLog()
        initial_log = np.zeros(log.size)
        initial_log[[log.loss, log.nominal_loss]] = np.nan
        initial_log[log.beta_hat] = 1.0
        self._log = self.DeclareDiscreteState(np.tile(initial_log, count))
        beta_hat = np.arange(count) * log.size + log.beta_hat
        self.DeclareStateOutputPort("weights", self._weights)
        self.DeclareVectorOutputPort(
            "beta_hat", count, lambda c, o: o.SetFromVector(
                c.get_discrete_state(self._log).get_value()[beta_hat]),
            prerequisites_of_calc={self.discrete_state_ticket(self._log)})
        self.DeclareStateOutputPort("learner_log", self._log)
        self.DeclareVectorOutputPort(
            "estimates", (n * n + n) * count, self._CalcEstimates,
            prerequisites_of_calc={self.discrete_state_ticket(self._weights),
                                   self._q.ticket(), self._qdot.ticket(),
                                   self._reduced_model.port.ticket()})
        self.DeclarePeriodicDiscreteUpdateEvent(sample_period, 0.0, self._UpdateSample)
        self.DeclarePeriodicDiscreteUpdateEvent(period, period, self._UpdateTraining)

    def _UpdateSample(self, context, discrete_state):
        width, window, count = self._row_width, self._settings.window, self._trials
        samples = int(context.get_discrete_state(self._count).get_value()[0])
        buffer = context.get_discrete_state(self._buffer).get_value().copy().reshape(
            count, window, width)
        buffer[:, samples % window, 0] = context.get_time()
        buffer[:, samples % window, 1:] = self._port_sample.Eval(context).reshape(count, -1)
        discrete_state.get_mutable_vector(self._buffer).SetFromVector(buffer.reshape(-1))
        discrete_state.get_mutable_vector(self._count).SetFromVector([samples + 1])

    def _UpdateTraining(self, context, discrete_state):
        samples = int(context.get_discrete_state(self._count).get_value()[0])
        if samples < 2:
            return
        t, count, settings = context.get_time(), self._trials, self._settings
        rows = context.get_discrete_state(self._buffer).get_value().reshape(
            count, settings.window, self._row_width)[:, :min(samples, settings.window)]
        detectors = context.get_discrete_state(self._detector_state).get_value(
            ).reshape(count, -1).copy()
        for i in np.flatnonzero(self._ModelChanges(context, discrete_state)):
            detectors[i] = self._detector.Changed(detectors[i], t)
        if self._regularized and self._learning:
            newest = NewestRows(rows, t, self._period)
            if newest.shape[1]:
                residuals = self._identifier.RelativeResiduals(newest)
                for i in range(count):
                    detectors[i] = self._detector.Update(detectors[i], t, residuals[i])
        holding = np.array([ChangeDetector.Holding(d, t) for d in detectors])
        window_starts = np.array([ChangeDetector.WindowStart(d) for d in detectors])
        fitted = (self._learning & ~holding
                  & (np.count_nonzero(rows[:, :, 0] >= window_starts[:, None], axis=1)
                     >= self._min_samples))
        warm_started = context.get_discrete_state(self._warm_started).get_value().copy()
        if self._regularized and settings.warm_start:
            for i in np.flatnonzero(fitted & (warm_started == -np.inf)):
                self._identifier.WarmStart(rows[i], t, window_starts[i], i)
                warm_started[i] = window_starts[i]
        self._identifier.FitTrials(rows, t, window_starts, fitted)
        stats = self._identifier.StatisticsOfTrials(rows, t, np.full(count, -np.inf))
        published = self._NetworkPublished(rows, t, window_starts, fitted)
        log = LearnerLog()
        logs = np.zeros((count, log.size))
        logs[:, log.loss], logs[:, log.beta_hat] = stats.loss, stats.beta_hat
        logs[:, log.nominal_loss], logs[:, log.holding] = stats.nominal_loss, holding
        logs[:, log.network_published] = published
        discrete_state.get_mutable_vector(self._detector_state).SetFromVector(
            detectors.reshape(-1))
        discrete_state.get_mutable_vector(self._warm_started).SetFromVector(warm_started)
        if self._learning:
            discrete_state.get_mutable_vector(self._weights).SetFromVector(np.where(
                published[:, None], self._identifier.Export(), self._prior_weights
            ).reshape(-1))
        discrete_state.get_mutable_vector(self._log).SetFromVector(logs.reshape(-1))

    def _NetworkPublished(self, rows, t, window_starts, fitted) -> np.ndarray:
        """Whether each trial's network weights, not the prior's, are published this
        update. Always (while learning), unless settings.prior_fallback: then only
        when this update fitted (not holding after a change, min_window seconds of
        samples since it) and the network explains the samples since the change,
        and those of the last period, at least as well as (B0, D0) do
        (FitStatistics.loss <= nominal_loss on each); the prior otherwise. After a
        change the frozen network describes the old relation, and a refit on the
        first window after it can be further off than the prior; a change not yet
        detected shows first in the newest samples."""
        count = self._trials
        if not self._learning:
            return np.zeros(count, bool)
        if not self._settings.prior_fallback:
            return np.ones(count, bool)
        since_change = self._identifier.StatisticsOfTrials(rows, t, window_starts)
        newest = self._identifier.StatisticsOfTrials(
            rows, t, np.full(count, t - self._period + 1e-12))
        return (fitted & (since_change.loss <= since_change.nominal_loss)
                & (newest.loss <= newest.nominal_loss))

    def _ModelChanges(self, context, discrete_state) -> np.ndarray:
        """Whether each trial's LHS model changed since the last check (input
        ``model_epoch``, InertialIdentifier's; False where not watched), the
        epochs seen recorded."""
        if (self._model_epoch is None or not self._model_epoch.HasValue(context)
                or not (self._regularized and self._settings.model_change)):
            return np.zeros(self._trials, bool)
        epoch = self._model_epoch.Eval(context)
        changed = epoch != context.get_discrete_state(self._last_epoch).get_value()
        if np.any(changed):
            discrete_state.get_mutable_vector(self._last_epoch).SetFromVector(epoch)
        return changed

    def _CalcEstimates(self, context, output):
        n, count = self._n, self._trials
        q = self._q.Eval(context).reshape(count, n)
        qdot = self._qdot.Eval(context).reshape(count, n)
        p = self._reduced_model.Momenta(context, q, qdot)
        B, D = self._network_stack.Evaluate(
            context.get_discrete_state(self._weights).get_value().reshape(count, -1),
            q, p)
        output.SetFromVector(np.concatenate([B.reshape(count, -1), D], axis=1).reshape(-1))

