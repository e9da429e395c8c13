"""The local Bayesian learner (``learner.model: local_bayes``): per joint i, the port row
tau_i = sum_j B_ij(x) u_j - D_i(x) qdot_i + d_i(t), every entry a local linear model
around the newest sample, X(x) = X + X_t (t - t_now) + X_p (p_i - p_now,i) for X in
{B_i1..B_in, D_i}, fitted by Bayesian linear regression with exponential forgetting to the
band-passed products of the port signals and those features (LocalBayesChannels: exact
when B moves) since the row's last restart. The filter's memory of earlier samples is
projected out (kernels.bayes.project_out): a change costs a restart, not a wait.

A row restarts when its newest residual jumps (learner.change_ratio, change_floor), when
its fit leaves the previous fit's prediction (a fit through an undetected switch can look
good), or when its gain or damping is credibly below zero; all rows restart when the LHS
model changes. An entry is published as learned where the data move it from the prior by
more than ``margin`` credible half-widths (no worse than the prior); else at the prior,
with the learned interval (or, while the row is undetermined, the prior's range)."""
from dataclasses import dataclass
from statistics import NormalDist
from typing import Optional, Sequence, Tuple

import numpy as np

from dacph_drake.learning.identification import BandPassCascade
from dacph_drake.kernels.bayes import fit_rows, row_design
from dacph_drake.learning.protocol import (Channels, LearnerTrial, PortEstimate,
                                   PortLearner)
from dacph_drake.log_layout import LearnerLog
from dacph_drake.quantiles import student_quantile
from dacph_drake.scenario import Learner, LocalBayes

# The correlation-time estimate's longest lag [samples] (kernels.bayes.fit_row): the
# band-passed residual's memory is the cascade's, well under 20 samples of 10 ms.
RESIDUAL_LAGS = 20
# The change test's history of each row's newest relative residuals (updates), and
# the fewest it needs before it tests.
HISTORY, MIN_HISTORY = 10, 3


class LocalBayesChannels(Channels):
    """The local model's channels (n^2 + 6 n per trial) of a sample at t [s]: [u_j, u_j t,
    u_j p_i (n^2, at i n + j), qdot_i, qdot_i t, qdot_i p_i, tau_i], the others n each.

    Args:
        n: The number of joints."""

    def __init__(self, n: int):
        self.n = n
        self.size = n * n + 6 * n
        # Where the filtered sample [q, p, channels] holds [qdot, u, tau_obs].
        self.port_columns = 2 * n + np.concatenate([
            np.arange(2 * n + n * n, 3 * n + n * n), np.arange(n),
            np.arange(5 * n + n * n, 6 * n + n * n)])

    def Of(self, t: float, samples: np.ndarray) -> np.ndarray:
        """Each trial's channels (trials, size; the layout above) from its port sample.

        Args:
            t: The sample's time [s].
            samples: Each trial's identification.PortSample (trials, 5 n)."""
        n = self.n
        p, qdot, u, tau = (samples[:, k * n:(k + 1) * n] for k in range(1, 5))
        return np.concatenate([u, t * u, (p[:, :, None] * u[:, None, :]).reshape(
            len(samples), n * n), qdot, t * qdot, qdot * p, tau], axis=1)


class LocalModelLayout:
    """The local model's published vector per trial, k = n^2 + n quantities [vec(B), D]:
    [t_ref, p_ref (n), value (k), drift (k) [1/s], slope (k) [per unit p_i], interval
    below, above (k each), set below, above (k each), learned (k)]. The estimate at (t, p)
    is value + drift (t - t_ref) + slope (p_i - p_ref,i); the interval (credible_level) and
    set (certificate_level) are [estimate - below, estimate + above]; learned: 1 learner's.

    Args:
        n: The number of joints."""

    def __init__(self, n: int):
        k = n * n + n
        self.n, self.quantities = n, k
        self.t_ref, self.p_ref = 0, slice(1, 1 + n)
        start = 1 + n
        names = ("value", "drift", "slope", "interval_below", "interval_above",
                 "set_below", "set_above", "learned")
        for index, name in enumerate(names):
            setattr(self, name, slice(start + index * k, start + (index + 1) * k))
        self.size = start + len(names) * k


class LocalModel:
    """Evaluates a batch's published local models (LocalModelLayout).

    Args:
        n: The number of joints."""
    has_uncertainty = True

    def __init__(self, n: int):
        self.n = n
        self.layout = LocalModelLayout(n)
        self.size = self.layout.size
        # Row i's momentum for every quantity: B_ij reads p_i, D_i reads p_i.
        self._row = np.concatenate([np.repeat(np.arange(n), n), np.arange(n)])

    def Stack(self, models: Sequence["LocalModel"]) -> "LocalModel":
        """learning.PublishedModel.Stack: this one, which serves any batch of its n.

        Args:
            models: The batch's trials' models."""
        return self

    def Estimate(self, published: np.ndarray, t: float, q: np.ndarray, p: np.ndarray
                 ) -> PortEstimate:
        """Every trial's estimate, a PortEstimate, at its state (PublishedModel.Estimate).

        Args:
            published: Each trial's published vector (trials, size).
            t: The time [s].
            q: Each trial's joint angles (trials, n) [rad] (unused).
            p: Each trial's momenta (trials, n)."""
        L, n = self.layout, self.n
        trials = published.shape[0]
        point = (published[:, L.value] + published[:, L.drift]
                 * (t - published[:, L.t_ref, None])
                 + published[:, L.slope] * (p - published[:, L.p_ref])[:, self._row])
        point[:, n * n:] = np.maximum(point[:, n * n:], 0.0)
        interval = np.stack([point - published[:, L.interval_below],
                             point + published[:, L.interval_above]])
        credible = np.stack([point - published[:, L.set_below],
                             point + published[:, L.set_above]])
        return PortEstimate(
            B=point[:, :n * n].reshape(trials, n, n), D=point[:, n * n:],
            B_set=credible[:, :, :n * n].reshape(2, trials, n, n),
            B_interval=interval[:, :, :n * n].reshape(2, trials, n, n),
            D_interval=interval[:, :, n * n:])


def free_response(cascade: BandPassCascade, length: int) -> np.ndarray:
    """The cascade's zero-input output (length, sections), column s from unit state e_s.

    Args:
        cascade: The band-pass cascade.
        length: The number of samples."""
    sections = cascade.num_sections
    state = np.eye(sections)               # one column per unit state
    out = np.empty((length, sections))
    for k in range(length):
        state, out[k] = cascade.Step(state, np.zeros(sections))
    return out


def prior_range(bayes: LocalBayes, B0: Sequence[float], D0: Sequence[float]
                ) -> np.ndarray:
    """The prior's range [lower, upper] (2, n^2 + n) of [vec(B), diag(D)] (LocalBayes).

    Args:
        bayes: The local Bayesian learner's settings.
        B0: The prior's B0 (its diagonal, n).
        D0: The prior's D0 (its diagonal, n)."""
    B0, D0 = np.asarray(B0, float), np.asarray(D0, float)
    n = len(B0)
    coupling = entry_coupling(bayes, n) * np.sqrt(B0[:, None] * B0[None, :])
    low, high = bayes.gain_range
    bounds = np.empty((2, n * n + n))
    bounds[0, :n * n] = np.where(np.eye(n) > 0, low * B0[:, None], -coupling).reshape(-1)
    bounds[1, :n * n] = np.where(np.eye(n) > 0, high * B0[:, None], coupling).reshape(-1)
    bounds[:, n * n:] = np.outer(bayes.damping_range, D0)
    return bounds


def entry_coupling(bayes: LocalBayes, n: int) -> float:
    """The prior's bound (and sd) of one |B_ij| / sqrt(B0_i B0_j): bayes.coupling bounds a
    row's total, shared by its n - 1 entries, so the Gershgorin radius does not grow.

    Args:
        bayes: The local Bayesian learner's settings.
        n: The number of joints."""
    return bayes.coupling / max(n - 1, 1)


def physical_claims(point: np.ndarray, lower: np.ndarray, upper: np.ndarray,
                    bayes: LocalBayes, B0: Sequence[float], D0: Sequence[float],
                    error_sd: Optional[np.ndarray] = None
                    ) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """What the published estimates say about the physical B~, D~: (estimate, lower, upper),
    each (T, n^2 + n). The port is tau_obs = p_dot + dH/dq of the LHS model: with M_hat =
    (I + E) M~ the learner sees (I + E) B~ and (I + E) D~ (port data cannot tell gain from
    inertia), so B~ = (I + E)^-1 B ~ (I - E) B. With E's entries of sd e_ik (``error_sd``,
    and bayes.model_error in quadrature) each half-width grows in quadrature by
    z sqrt(sum_k e_ik^2 B_kj^2) (B_ij) or z sqrt(sum_k e_ik^2 D_k^2) (D_i: damping leaks
    across joints through E), z the normal quantile of credible_level; an entry within
    bayes.margin half-widths of the prior is claimed at the prior.

    Args:
        point: The published estimates [vec(B), diag(D)] (T, n^2 + n).
        lower: Their intervals' lower ends (T, n^2 + n).
        upper: Their intervals' upper ends (T, n^2 + n).
        bayes: The learner's settings.
        B0: The prior's B0 (its diagonal, n).
        D0: The prior's D0 (its diagonal, n).
        error_sd: E's sd per entry at each sample (T, n, n); None: 0."""
    n = len(B0)
    z = NormalDist().inv_cdf(0.5 + 0.5 * bayes.credible_level)
    prior = np.concatenate([np.diag(np.asarray(B0, float)).reshape(-1),
                            np.asarray(D0, float)])[None, :]
    B = point[:, :n * n].reshape(-1, n, n)
    D = np.maximum(np.abs(point[:, n * n:]), prior[:, n * n:])
    variance = (0.0 if error_sd is None else np.asarray(error_sd, float) ** 2) \
        + np.full((len(point), n, n), bayes.model_error ** 2)
    widening = z ** 2 * np.concatenate([
        np.einsum("tik,tkj->tij", variance, B ** 2).reshape(-1, n * n),
        np.einsum("tik,tk->ti", variance, D ** 2)], axis=1)
    below = np.sqrt((point - lower) ** 2 + widening)
    above = np.sqrt((upper - point) ** 2 + widening)
    determined = np.abs(point - prior) > bayes.margin * np.maximum(below, above)
    estimate = np.where(determined, point, prior)
    low = np.minimum(point - below, estimate)
    low[:, n * n:] = np.maximum(low[:, n * n:], 0.0)         # D~ >= 0
    return estimate, low, np.maximum(point + above, estimate)


class _RowState:
    """One row's state: [window start [s], residuals seen, last HISTORY relative residuals,
    previous fit's time [s] (-inf: none), its p_i, [const, drift, slope] per entry, sd,
    the prior's residuals seen, its last HISTORY relative residuals]."""

    def __init__(self, n: int):
        self.fit_time, self.fit_momentum = 2 + HISTORY, 3 + HISTORY
        self.fit = slice(4 + HISTORY, 4 + HISTORY + 3 * (n + 1))
        self.fit_spread = slice(self.fit.stop, self.fit.stop + 3 * (n + 1))
        self.prior_seen = self.fit_spread.stop
        self.prior_history = slice(self.prior_seen + 1, self.prior_seen + 1 + HISTORY)
        self.size = self.prior_history.stop


@dataclass
class _Prior:
    """One trial's prior per row: mean and sd of [const, drift, slope], scales, ranges."""
    mean: np.ndarray
    sd: np.ndarray
    scale: np.ndarray
    range: np.ndarray


class LocalBayesLearner(PortLearner):
    """The local Bayesian learner of a batch; its state: a _RowState per trial and row.

    Args:
        settings: The learner's settings (``bayes``, band, forgetting, window, changes).
        trials: Each trial's LearnerTrial.
        period: The training period [s].
        sample_period: The sampling period [s]."""

    def __init__(self, settings: Learner, trials: Sequence[LearnerTrial], period: float,
                 sample_period: float):
        n = len(trials[0].B0)
        self.n, self._trials = n, len(trials)
        self._settings, self._bayes = settings, settings.bayes
        self._period = period
        self.channels = LocalBayesChannels(n)
        self.model = LocalModel(n)
        self._row_state = _RowState(n)
        self.state_size = n * self._row_state.size
        self._layout = self.model.layout
        cascade = BandPassCascade(settings.band[0], settings.band[1],
                                  settings.band_sections[0], settings.band_sections[1],
                                  sample_period)
        self._free_response = free_response(cascade, settings.window + 1)
        self._minimum = max(2, int(round(self._bayes.min_window / sample_period)))
        # A band of width f sampled every h carries one independent sample per
        # 1 / (2 f h) (kernels.bayes.fit_row's min_tau).
        self._min_tau = 1.0 / (2.0 * (settings.band[1] - settings.band[0]) * sample_period)
        self._priors = [self._MakePrior(trial) for trial in trials]
        standard = NormalDist()
        self._z_interval = standard.inv_cdf(0.5 + self._bayes.credible_level / 2)
        self._z_set = standard.inv_cdf(0.5 + self._bayes.certificate_level / 2)
        self._prior_vectors = np.array([self._PriorVector(prior) for prior in self._priors])

    @staticmethod
    def BandPassed(settings: Learner) -> bool:
        """It learns from band-passed samples (a RegressionFilter before it).

        Args:
            settings: The learner's settings."""
        return True

    @staticmethod
    def Published(settings: Learner, trial: LearnerTrial) -> LocalModel:
        """The evaluator of a trial's published vector (RhsIntegrator reads it).

        Args:
            settings: The learner's settings.
            trial: The trial."""
        return LocalModel(len(trial.B0))

    @staticmethod
    def PriorSet(settings: Learner, B0: Sequence[float], D0: Sequence[float]) -> np.ndarray:
        """prior_range's B (2 x n x n): the credible set before any learning.

        Args:
            settings: The learner's settings.
            B0: The prior's B0 (its diagonal, n).
            D0: The prior's D0 (its diagonal, n)."""
        n = len(B0)
        return prior_range(settings.bayes, B0, D0)[:, :n * n].reshape(2, n, n)

    def _MakePrior(self, trial: LearnerTrial) -> _Prior:
        """The prior of one trial's rows from B0, D0 and the bayes section."""
        n, bayes = self.n, self._bayes
        B0, D0 = np.asarray(trial.B0, float), np.asarray(trial.D0, float)
        damping = np.where(D0 > 0, D0, max(np.max(D0), 1e-3))
        scale = np.empty((n, n + 1))
        scale[:, :n] = np.sqrt(B0[:, None] * B0[None, :])
        scale[:, n] = damping
        mean = np.zeros((n, n + 1, 3))
        mean[:, :n, 0] = np.diag(B0)
        mean[:, n, 0] = D0
        low, high = bayes.gain_range
        constant = np.where(np.eye(n, n + 1) > 0, 0.5 * (high - low),
                            entry_coupling(bayes, n))
        constant[:, n] = 0.5 * (bayes.damping_range[1] - bayes.damping_range[0])
        sd = np.stack([constant, np.full((n, n + 1), bayes.drift),
                       np.full((n, n + 1), bayes.momentum_slope
                               / self._settings.momentum_scale)], axis=2) * scale[:, :, None]
        return _Prior(mean=mean.reshape(n, -1), sd=sd.reshape(n, -1), scale=scale,
                      range=prior_range(bayes, B0, D0))

    def _PriorVector(self, prior: _Prior) -> np.ndarray:
        """The prior's published vector: (B0, D0), no drift or slope, its range around."""
        L, n = self._layout, self.n
        out = np.zeros(self.model.size)
        value = np.concatenate([prior.mean.reshape(n, n + 1, 3)[:, :n, 0].reshape(-1),
                                prior.mean.reshape(n, n + 1, 3)[:, n, 0]])
        out[L.value] = value
        out[L.interval_below] = out[L.set_below] = value - prior.range[0]
        out[L.interval_above] = out[L.set_above] = prior.range[1] - value
        return out

    def InitialState(self) -> np.ndarray:
        """Every row's window starts with the run; its change test has seen nothing."""
        state = np.zeros((self._trials, self.n, self._row_state.size))
        state[:, :, 0] = state[:, :, self._row_state.fit_time] = -np.inf
        return state.reshape(self._trials, -1)

    def Prior(self) -> np.ndarray:
        """Each trial's published prior (PortLearner.Prior)."""
        return self._prior_vectors.copy()

    def Update(self, t: float, rows: np.ndarray, state: np.ndarray,
               model_changed: np.ndarray, learning: bool
               ) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
        """PortLearner.Update: fits each trial's rows; (published, log rows, state).

        Args:
            t: The time [s].
            rows: Each trial's buffered samples, oldest first [t, q, p, channels].
            state: Each trial's state (trials, state_size).
            model_changed: Whether each trial's LHS model changed since the last update.
            learning: False publishes the prior (the dac-nominal ablation)."""
        published = self._prior_vectors.copy()
        logs = np.zeros((self._trials, LearnerLog().size))
        state = state.reshape(self._trials, self.n, -1).copy()
        watch = self._settings.model_change
        for trial in range(self._trials):
            if watch and model_changed[trial]:
                self._Restart(state[trial], np.ones(self.n, bool), t)
            fitted, determined = self._priors[trial].mean, np.zeros(self.n, bool)
            if learning:
                published[trial], fitted, determined, restarts = self._Fit(
                    trial, t, rows[trial], state[trial])
                logs[trial, LearnerLog().restarts] = restarts
            logs[trial] = self._Log(trial, t, rows[trial], published[trial], fitted,
                                    determined, logs[trial])
        return published, logs, state.reshape(self._trials, -1)

    def _Fit(self, trial: int, t: float, rows: np.ndarray, state: np.ndarray
             ) -> Tuple[np.ndarray, np.ndarray, np.ndarray, int]:
        """One trial's fit: (published, fitted coefficients, determined rows, restarts)."""
        n, bayes = self.n, self._bayes
        prior = self._priors[trial]
        P = 3 * (n + 1)
        mean, variance = np.empty((n, P)), np.empty((n, P))
        statistics, determined = np.empty((n, 6)), np.zeros(n, np.bool_)
        times = rows[:, 0]
        starts = state[:, 0].copy()
        fit_rows(times, rows[:, 1:], starts, n, prior.mean, prior.sd,
                 self._free_response, bayes.forgetting, RESIDUAL_LAGS, self._min_tau,
                 bayes.floor, bayes.change_floor / self._z_interval, self._period,
                 self._minimum, bayes.min_dof, mean, variance,
                 statistics, determined)
        # A short window predicts its newest samples poorly whatever holds: only
        # windows of half the forgetting time add to the history, and a row its
        # window does not determine is tested once it spans the forgetting time
        # (it may hold a change it cannot resolve).
        span = t - np.maximum(state[:, 0], times[0])
        changed = np.zeros(n, bool)
        for i in range(n):
            if determined[i] or span[i] >= bayes.forgetting:
                changed[i] = self._Changed(state[i], statistics[i, 3], statistics[i, 4],
                                           span[i] >= 0.5 * bayes.forgetting)
            elif span[i] >= 0.5 * bayes.forgetting:
                self._Remember(state[i], statistics[i, 4])
        changed |= self._PriorResidualJumped(state, t, rows, prior)
        sd = self._EntrySd(trial, t, times, starts, variance)
        changed |= determined & (self._Jumped(state, t, rows[-1], mean, variance, sd)
                                 | self._Unphysical(mean, sd, statistics[:, 1]))
        self._Restart(state, changed, t)
        determined &= ~changed
        # A row's first fit since its restart waits one update: published only if
        # the next one confirms it (the jump test), since a window that holds an
        # undetected switch fits it with wrong coefficients and a small residual.
        confirmed = determined & np.isfinite(state[:, self._row_state.fit_time])
        self._RememberFits(state, t, rows[-1], mean, variance, sd, determined)
        determined = confirmed
        dof = np.maximum(statistics[:, 1], bayes.min_dof)
        fitted = np.where(determined[:, None], mean, prior.mean)
        return (self._Publish(trial, t, rows[-1], mean, sd, determined, dof), fitted,
                determined,
                int(np.count_nonzero(changed)))

    def _Changed(self, row: np.ndarray, surprise: float, relative: float,
                 remember: bool) -> bool:
        """One row's change test (``row`` in place): a residual above bayes.inconsistency,
        or above change_floor and change_ratio predictive sd or times the recent median."""
        if not np.isfinite(relative):
            return False
        if relative > self._bayes.inconsistency:
            return True
        count = int(row[1])
        known = row[2:2 + min(count, HISTORY)]
        ratio = self._settings.change_ratio
        if relative > self._bayes.change_floor and (
                surprise > ratio
                or (count >= MIN_HISTORY and relative > ratio * np.median(known))):
            return True
        if remember:
            self._Remember(row, relative)
        return False

    def _PriorResidualJumped(self, state, t, rows, prior) -> np.ndarray:
        """Which rows' port relation changed by the prior's residual on the newest samples,
        which moves only with the port ((B0, D0) is fixed); tested for every row, determined
        or not: a jump by change_ratio over its recent median, above change_floor, restarts
        the row and a history at the new level (``state`` in place)."""
        S, n = self._row_state, self.n
        newest = rows[rows[:, 0] > t - self._period + 1e-9, 1:]
        jumped = np.zeros(n, bool)
        if len(newest) == 0:
            return jumped
        ratio, floor = self._settings.change_ratio, self._bayes.change_floor
        for i in range(n):
            A = row_design(newest, i, n, t, newest[-1, n + i])
            y = newest[:, 2 * n + 5 * n + n * n + i]
            signal = np.sum(y * y)
            if not signal > 0.0:
                continue
            relative = float(np.sqrt(np.sum((y - A @ prior.mean[i]) ** 2) / signal))
            row = state[i]
            count = int(row[S.prior_seen])
            known = row[S.prior_history][:min(count, HISTORY)]
            jumped[i] = (count >= MIN_HISTORY and relative > floor
                         and relative > ratio * np.median(known))
            if jumped[i]:
                row[S.prior_seen] = 0.0
            count = int(row[S.prior_seen])
            row[S.prior_history.start + count % HISTORY] = relative
            row[S.prior_seen] = count + 1
        return jumped

    def _EntrySd(self, trial, t, times, starts, variance) -> np.ndarray:
        """Each row's entries' sd (n, n + 1): the posterior's and the local model's error,
        curvature / 2 x the weighted mean of (t_k - t_now)^2 (times the entry's scale)."""
        n, bayes = self.n, self._bayes
        scale = self._priors[trial].scale
        sd = np.empty((n, n + 1))
        for i in range(n):
            inside = times >= starts[i] - 1e-9
            w = np.exp((times[inside] - t) / bayes.forgetting)
            spread = np.sum(w * (times[inside] - t) ** 2) / max(np.sum(w), 1e-300)
            curvature = 0.5 * bayes.curvature * spread * scale[i]
            sd[i] = np.sqrt(variance[i].reshape(n + 1, 3)[:, 0] + curvature ** 2)
        return sd

    def _Jumped(self, state, t, newest, mean, variance, sd) -> np.ndarray:
        """Rows whose fit left the previous one's prediction by the set's quantile of sd."""
        S, n = self._row_state, self.n
        p = newest[1 + n:1 + 2 * n]
        previous = state[:, S.fit_time]
        jumped = np.zeros(n, bool)
        for i in np.flatnonzero(np.isfinite(previous)):
            theta = state[i, S.fit].reshape(n + 1, 3)
            spread = state[i, S.fit_spread].reshape(n + 1, 3)
            dt, dp = t - previous[i], p[i] - state[i, S.fit_momentum]
            predicted = theta[:, 0] + theta[:, 1] * dt + theta[:, 2] * dp
            predictive = (spread[:, 0] ** 2 + (spread[:, 1] * dt) ** 2
                          + (spread[:, 2] * dp) ** 2 + sd[i] ** 2)
            value = mean[i].reshape(n + 1, 3)[:, 0]
            jumped[i] = np.any(np.abs(value - predicted) > self._z_set * np.sqrt(predictive))
        return jumped

    def _Unphysical(self, mean, sd, dof) -> np.ndarray:
        """Rows whose fit puts B_ii or D_i credibly below zero: a transient."""
        n = self.n
        constant = mean.reshape(n, n + 1, 3)[:, :, 0]
        quantile = np.array([student_quantile(self._z_interval, max(d, self._bayes.min_dof))
                             for d in dof])[:, None]
        upper = constant + quantile * sd
        rows = np.arange(n)
        return (upper[rows, rows] < 0.0) | (upper[:, n] < 0.0)

    def _RememberFits(self, state, t, newest, mean, variance, sd, determined) -> None:
        """Keeps each determined row's fit, sd, time and momentum for the next jump test."""
        S, n = self._row_state, self.n
        state[:, S.fit_time] = np.where(determined, t, -np.inf)
        state[:, S.fit_momentum] = newest[1 + n:1 + 2 * n]
        state[:, S.fit] = mean
        spread = np.sqrt(variance).reshape(n, n + 1, 3).copy()
        spread[:, :, 0] = sd
        state[:, S.fit_spread] = spread.reshape(n, -1)

    def _Restart(self, state, rows, t) -> None:
        state[rows, 0] = t + 1e-9
        state[rows, 1] = 0.0
        state[rows, self._row_state.fit_time] = -np.inf

    @staticmethod
    def _Remember(row: np.ndarray, relative: float) -> None:
        if np.isfinite(relative):
            count = int(row[1])
            row[2 + count % HISTORY] = relative
            row[1] = count + 1

    def _Publish(self, trial, t, newest, mean, sd, determined, dof):
        """The published vector (Student's t at each row's dof); damping < 0: prior's."""
        L, n, bayes = self._layout, self.n, self._bayes
        prior = self._priors[trial]
        out = self._prior_vectors[trial].copy()
        out[L.t_ref] = t
        out[L.p_ref] = newest[1 + n:1 + 2 * n]
        for i in np.flatnonzero(determined):
            entries = np.concatenate([i * n + np.arange(n), [n * n + i]])
            theta = mean[i].reshape(n + 1, 3)
            prior_value = prior.mean[i].reshape(n + 1, 3)[:, 0]
            z_interval = student_quantile(self._z_interval, dof[i])
            z_set = student_quantile(self._z_set, dof[i])
            learned = (np.abs(theta[:, 0] - prior_value) > bayes.margin * z_interval * sd[i])
            negative_damping = theta[n, 0] < 0.0
            learned[n] &= not negative_damping
            value = np.where(learned, theta[:, 0], prior_value)
            out[L.value][entries] = value
            out[L.drift][entries] = np.where(learned, theta[:, 1], 0.0)
            out[L.slope][entries] = np.where(learned, theta[:, 2], 0.0)
            out[L.learned][entries] = learned
            for z, below, above in ((z_interval, L.interval_below, L.interval_above),
                                    (z_set, L.set_below, L.set_above)):
                out[below][entries] = np.maximum(value - (theta[:, 0] - z * sd[i]), 0.0)
                out[above][entries] = np.maximum(theta[:, 0] + z * sd[i] - value, 0.0)
            if negative_damping:        # not a damping the port can have: its range
                for ends in (L.interval_below, L.interval_above, L.set_below, L.set_above):
                    out[ends][n * n + i] = self._prior_vectors[trial][ends][n * n + i]
        # D >= 0: a published damping below zero is zero, and so is its interval.
        D = slice(L.value.start + n * n, L.value.stop)
        below_zero = out[D] < 0
        out[D] = np.maximum(out[D], 0.0)
        for below in (L.interval_below, L.set_below):
            d_below = slice(below.start + n * n, below.stop)
            out[d_below] = np.minimum(out[d_below], out[D])
        out[L.interval_above.start + n * n:L.interval_above.stop][below_zero] = 0.0
        return out

    def _Log(self, trial, t, rows, published, fitted, determined, log):
        """The trial's LearnerLog row."""
        n, layout = self.n, LearnerLog()
        times = rows[:, 0]
        w = np.exp((times - t) / self._bayes.forgetting)
        w /= np.sum(w)
        samples = rows[:, 1:]
        loss = nominal = signal = 0.0
        prior = self._priors[trial].mean
        for i in range(n):
            A = row_design(samples, i, n, t, samples[-1, n + i])
            y = samples[:, 2 * n + 5 * n + n * n + i]
            loss += np.sum(w * (y - A @ fitted[i]) ** 2)
            nominal += np.sum(w * (y - A @ prior[i]) ** 2)
            signal += np.sum(w * y ** 2)
        learned = published[self._layout.learned]
        log[layout.loss], log[layout.nominal_loss] = loss, nominal
        log[layout.beta_hat] = 1.0 + np.sqrt(loss / max(signal, 1e-300))
        log[layout.network_published] = float(np.any(learned > 0.5))
        log[layout.undetermined] = float(np.mean(learned < 0.5))
        log[layout.holding] = float(not np.any(determined))
        return log
