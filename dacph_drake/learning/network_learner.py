"""The paper's physics-informed network as a learning.PortLearner (``learner.model:
network``): identification.RhsIdentifier fits network.RhsNetwork (E33-E35) to the window
of port samples, band-passed (regularized mode) or raw (plain mode, the paper's). In
regularized mode a ChangeDetector pauses training after an abrupt change, at the start
(start_hold) and after an LHS model change; a fit needs min_window seconds of samples,
the first starts from the window's best constant B (warm_start), and with prior_fallback
(B0, D0) is published while the network does not beat it. The torch modules and Adam's
moments live in this object, not in the Context: one diagram per run."""
from typing import Sequence, Tuple

import numpy as np

from dacph_drake.learning.identification import ChangeDetector, NewestRows, RhsIdentifier
from dacph_drake.learning.protocol import Channels, LearnerTrial, PortLearner
from dacph_drake.log_layout import LearnerLog
from dacph_drake.learning.network import ExportedNetwork, NetworkStack
from dacph_drake.scenario import Learner


class PortSampleChannels(Channels):
    """Channels [qdot, u, tau_obs]: the filtered sample keeps PortSample's layout.

    Args:
        n: The number of joints."""

    def __init__(self, n: int):
        self.n = n
        self.size = 3 * n
        # Where the filtered sample [q, p, channels] holds [qdot, u, tau_obs].
        self.port_columns = np.arange(2 * n, 5 * n)

    def Of(self, t: float, samples: np.ndarray) -> np.ndarray:
        """Each trial's [qdot, u, tau_obs] (trials, size).

        Args:
            t: The sample's time [s].
            samples: Each trial's identification.PortSample (trials, 5 n)."""
        return samples[:, 2 * self.n:]


class NetworkLearner(PortLearner):
    """A batch's network learner; per trial a ChangeDetector state and warm-start time.

    Args:
        settings: The learner's settings.
        trials: Each trial's LearnerTrial.
        period: The training period [s].
        sample_period: The sampling period [s]."""

    @staticmethod
    def BandPassed(settings: Learner) -> bool:
        """It learns from band-passed samples in regularized mode (raw in plain mode).

        Args:
            settings: The learner's settings."""
        return settings.mode == "regularized"

    @staticmethod
    def Published(settings: Learner, trial: LearnerTrial) -> ExportedNetwork:
        """The evaluator of a trial's published weights (RhsIntegrator reads it).

        Args:
            settings: The learner's settings.
            trial: The trial."""
        return ExportedNetwork.ForLearner(settings, trial.model, trial.q0)

    @staticmethod
    def PriorSet(settings: Learner, B0: Sequence[float], D0: Sequence[float]) -> None:
        """None: a point estimate has no credible set.

        Args:
            settings: The learner's settings.
            B0: The prior's B0 (its diagonal, n).
            D0: The prior's D0 (its diagonal, n)."""
        return None

    def __init__(self, settings: Learner, trials: Sequence[LearnerTrial], period: float,
                 sample_period: float):
        n = len(trials[0].B0)
        self._n, self._trials = n, len(trials)
        self._period = period
        self._settings = settings
        self._regularized = self.BandPassed(settings)
        self._min_samples = max(2, int(round(settings.min_window / sample_period)))
        networks = [ExportedNetwork.ForLearner(settings, trial.model, trial.q0)
                    for trial in trials]
        self.model = NetworkStack(networks)
        self.channels = PortSampleChannels(n)
        self._identifier = RhsIdentifier.ForTrials(
            n, settings, [np.diag(trial.B0) for trial in trials],
            [trial.D0 for trial in trials], [trial.seed for trial in trials],
            [network.coupling for network in networks])
        self._detector = ChangeDetector(settings.change_ratio, settings.change_floor,
                                        settings.change_hold)
        self._prior = self._identifier.Export()
        self._detector_size = len(ChangeDetector.InitialState())
        self.state_size = self._detector_size + 1

    def InitialState(self) -> np.ndarray:
        """The detectors holding for start_hold s (regularized mode), no warm start yet."""
        hold = (self._settings.start_hold if self._regularized
                and self._settings.start_hold > 0 else -np.inf)
        return np.tile(np.concatenate([ChangeDetector.InitialState(hold), [-np.inf]]),
                       (self._trials, 1))

    def Prior(self) -> np.ndarray:
        """The networks' initial weights: B_hat = B0, D_hat = D0 (PortLearner.Prior)."""
        return self._prior.copy()

    def Update(self, t: float, rows: np.ndarray, state: np.ndarray,
               model_changed: np.ndarray, learning: bool
               ) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
        """PortLearner.Update: detects changes, fits and publishes (published, logs, state).

        Args:
            t: The time [s].
            rows: Each trial's buffered samples, oldest first [t, q, p, channels].
            state: Each trial's state (trials, state_size).
            model_changed: Whether each trial's LHS model changed since the last update.
            learning: False publishes the prior, B0 and D0 (the dac-nominal ablation)."""
        count, settings = self._trials, self._settings
        learning = learning and settings.steps_per_update > 0
        detectors = state[:, :self._detector_size].copy()
        warm_started = state[:, self._detector_size].copy()
        if self._regularized and settings.model_change:
            for i in np.flatnonzero(model_changed):
                detectors[i] = self._detector.Changed(detectors[i], t)
        if self._regularized and learning:
            newest = NewestRows(rows, t, self._period)
            if newest.shape[1]:
                residuals = self._identifier.RelativeResiduals(newest)
                for i in range(count):
                    detectors[i] = self._detector.Update(detectors[i], t, residuals[i])
        holding = np.array([ChangeDetector.Holding(d, t) for d in detectors])
        window_starts = np.array([ChangeDetector.WindowStart(d) for d in detectors])
        fitted = (learning & ~holding
                  & (np.count_nonzero(rows[:, :, 0] >= window_starts[:, None], axis=1)
                     >= self._min_samples))
        if self._regularized and settings.warm_start:
            for i in np.flatnonzero(fitted & (warm_started == -np.inf)):
                self._identifier.WarmStart(rows[i], t, window_starts[i], i)
                warm_started[i] = window_starts[i]
        self._identifier.FitTrials(rows, t, window_starts, fitted)
        stats = self._identifier.StatisticsOfTrials(rows, t, np.full(count, -np.inf))
        published = self._NetworkPublished(rows, t, window_starts, fitted, learning)
        layout = LearnerLog()
        logs = np.zeros((count, layout.size))
        logs[:, layout.loss], logs[:, layout.beta_hat] = stats.loss, stats.beta_hat
        logs[:, layout.nominal_loss], logs[:, layout.holding] = stats.nominal_loss, holding
        logs[:, layout.network_published] = published
        logs[:, layout.undetermined] = np.where(published, 0.0, 1.0)
        weights = (np.where(published[:, None], self._identifier.Export(), self._prior)
                   if learning else self._prior.copy())
        return weights, logs, np.concatenate([detectors, warm_started[:, None]], axis=1)

    def _NetworkPublished(self, rows, t, window_starts, fitted, learning) -> np.ndarray:
        """Whether each trial publishes its network: while learning, unless prior_fallback;
        then if fitted now and no worse than (B0, D0) since the change and last period."""
        count = self._trials
        if not learning:
            return np.zeros(count, bool)
        if not self._settings.prior_fallback:
            return np.ones(count, bool)
        since_change = self._identifier.StatisticsOfTrials(rows, t, window_starts)
        newest = self._identifier.StatisticsOfTrials(
            rows, t, np.full(count, t - self._period + 1e-12))
        return (fitted & (since_change.loss <= since_change.nominal_loss)
                & (newest.loss <= newest.nominal_loss))
