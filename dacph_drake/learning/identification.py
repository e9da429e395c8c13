"""Online identification of the RHS (paper section "RHS Control and Learning"), free of
Drake: the regression, its band-pass prefilter and change detector. A port sample
[q, p, qdot, u, tau_obs] (PortSample) is one instant of the port relation (tau_breve)
tau_obs = B~(x) u - D~(x) qdot + d(t), x = (q, p), fitted by RhsNetwork's B_hat, D_hat."""
from dataclasses import dataclass
from typing import Optional, Sequence, Tuple

import numpy as np
import torch

from dacph_drake.learning.network import RhsNetwork, StackedRhsNetworks, port_torque
from dacph_drake.scenario import Learner


class PortSample:
    """Port sample columns [q, p, qdot, u, tau_obs] (n each); ``regressed``: the last three.

    Args:
        n: The number of joints."""

    def __init__(self, n: int):
        self.q, self.p = slice(0, n), slice(n, 2 * n)
        self.qdot, self.u, self.tau = slice(2 * n, 3 * n), slice(3 * n, 4 * n), \
            slice(4 * n, 5 * n)
        self.regressed = slice(2 * n, 5 * n)
        self.size = 5 * n


class BandPassCascade:
    """First-order sections sampled at h, high-pass then low-pass: low-pass y_k = y_(k-1) +
    a (x_k - y_(k-1)), a = 1 - exp(-2 pi f h); high-pass x_k - (x's low-pass at f). Its
    state, one row per section (the low-pass memory), can live in a Drake Context.

    Args:
        low: The high-pass sections' corner frequency f [Hz].
        high: The low-pass sections' corner frequency f [Hz].
        high_sections: The number of high-pass sections.
        low_sections: The number of low-pass sections.
        period: The sample period h [s]."""

    def __init__(self, low: float, high: float, high_sections: int, low_sections: int,
                 period: float):
        gain = lambda f: 1.0 - np.exp(-2 * np.pi * f * period)     # noqa: E731
        self.gains = np.array([gain(low)] * high_sections + [gain(high)] * low_sections)
        self.is_high_pass = np.arange(len(self.gains)) < high_sections

    @property
    def num_sections(self) -> int:
        return len(self.gains)

    def Step(self, state: np.ndarray, x: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
        """Filters one input sample: (next state, output).

        Args:
            state: The cascade's state (num_sections, len(x)).
            x: The input sample."""
        state = state.copy()
        y = np.asarray(x, float)
        for i, (a, high) in enumerate(zip(self.gains, self.is_high_pass)):
            state[i] += a * (y - state[i])
            y = y - state[i] if high else state[i]
        return state, y

    def Filter(self, x: np.ndarray) -> np.ndarray:
        """Filters a sequence from a zero state (the output has x's shape).

        Args:
            x: The sequence, one sample per row."""
        state = np.zeros((self.num_sections, x.shape[1]))
        out = np.empty_like(x, dtype=float)
        for k, row in enumerate(x):
            state, out[k] = self.Step(state, row)
        return out


class PortEvidence:
    """Port samples' second moments G <- a G + z z^T, z = [qdot, u, tau_obs], a =
    exp(-h/window), as a vector [vec(G) (3n x 3n), sum of weights] that can live in a Drake
    Context: Residual(B, D) then needs no samples kept.

    Args:
        n: The number of joints.
        sample_period: The sample period h [s].
        window: The forgetting's time constant [s].
        columns: Where [qdot, u, tau_obs] lie in a sample (None: PortSample.regressed)."""

    def __init__(self, n: int, sample_period: float, window: float,
                 columns: Optional[np.ndarray] = None):
        self.n = n
        self.decay = float(np.exp(-sample_period / window))
        self.size = 9 * n * n + 1
        self._columns = PortSample(n).regressed if columns is None else columns

    def Update(self, state: np.ndarray, sample: np.ndarray) -> np.ndarray:
        """The statistics after one more port sample (state's shape).

        Args:
            state: The statistics (size), or each trial's stacked (trials, size).
            sample: The PortSample, or each trial's stacked (trials, PortSample size)."""
        m = 3 * self.n
        z = np.asarray(sample, float)[..., self._columns]
        out = self.decay * state
        out[..., :m * m] += (z[..., :, None] * z[..., None, :]).reshape(
            z.shape[:-1] + (m * m,))
        out[..., m * m] += 1.0
        return out

    def Residual(self, state: np.ndarray, B: np.ndarray, D: np.ndarray) -> float:
        """The weighted residual sum_k w_k ||tau_k - (B u_k - D qdot_k)||^2 per unit weight.

        Args:
            state: The statistics (size).
            B: The input matrix (n x n).
            D: The damping's diagonal (n)."""
        n, m = self.n, 3 * self.n
        A = np.hstack([np.diag(D), -B, np.eye(n)])        # residual = A z
        G = state[:m * m].reshape(m, m)
        return float(np.trace(A @ G @ A.T)) / max(state[m * m], 1e-300)

    @staticmethod
    def Weight(state: np.ndarray) -> float:
        """The samples' total weight (in samples).

        Args:
            state: The statistics (size)."""
        return float(state[-1])


@dataclass
class FitStatistics:
    """The fit of the current network on the weighted window (per trial for a batch).

    Attributes:
        loss: sum w ||r||^2, r the residual of the port relation.
        nominal_loss: The same for (B0, D0).
        beta_hat: 1 + RMS residual / RMS tau (the gain rule's uncertainty estimate)."""
    loss: float
    nominal_loss: float
    beta_hat: float


class RhsIdentifier:
    """The learner's regression on windows of port samples (rows [t, PortSample]): Adam on

        plain (the paper): mean ||tau - (B_hat(x) u - D_hat(x) qdot)||^2,
        regularized: [sum_k w_k ||r_k||^2
                      + rho (sum_k w_k sum_ij E_ij (B_hat_ij(x_k) - B0_ij)^2
                             + E_q sum_k w_k ||D_hat(x_k) - D0||^2)] / (E_u + E_q),
        w_k = exp(-(t - t_k) / forgetting) (0 before window_start), sum_k w_k = 1,
        E_u = sum w ||u||^2 / n,  E_q = sum w ||qdot||^2 / n,
        E_ij = E_u ("pooled") or max(E_i, E_j), E_j = sum w u_j^2 ("per_input").

    The prior holds at (B0, D0) what the window does not inform; dividing by E_u + E_q
    makes rho dimensionless and the loss O(1) for Adam. ForTrials: one network per trial.

    Args:
        n: The number of joints.
        settings: The learner's settings.
        B0: The prior B (n x n).
        D0: The prior diag D (n).
        seed: The seed of the network's initial weights.
        coupling: The network's coupling scale F (coupling_factors; None: all ones)."""

    def __init__(self, n: int, settings: Learner, B0: np.ndarray, D0: np.ndarray,
                 seed: int, coupling: Optional[np.ndarray] = None):
        self._Build(n, settings, [B0], [D0], [seed], [coupling])

    @classmethod
    def ForTrials(cls, n: int, settings: Learner, B0s: Sequence[np.ndarray],
                  D0s: Sequence[np.ndarray], seeds: Sequence[int],
                  couplings: Sequence[Optional[np.ndarray]]) -> "RhsIdentifier":
        """An identifier of one network per trial.

        Args:
            n: The number of joints.
            settings: The learner's settings.
            B0s: Each trial's prior B (n x n).
            D0s: Each trial's prior diag D (n).
            seeds: Each trial's seed of its network's initial weights.
            couplings: Each trial's coupling scale F (None: all ones)."""
        self = object.__new__(cls)
        self._Build(n, settings, B0s, D0s, seeds, couplings)
        return self

    def _Build(self, n, settings, B0s, D0s, seeds, couplings):
        self.n = n
        self._settings = settings
        self._regularized = settings.mode == "regularized"
        self._layout = PortSample(n)
        torch.set_num_threads(1)
        self.network = StackedRhsNetworks([
            RhsNetwork(n, settings.hidden, B0, D0, settings.momentum_scale, seed,
                       coupling) for B0, D0, seed, coupling in zip(B0s, D0s, seeds,
                                                                   couplings)])
        flat = self.network.flat
        # Adam's moments and step counts, per trial and parameter.
        self._m, self._v = torch.zeros_like(flat), torch.zeros_like(flat)
        self._steps = torch.zeros_like(flat)
        self._B0 = torch.as_tensor(np.array([np.asarray(B0, float) for B0 in B0s]))
        self._D0 = torch.as_tensor(np.array([np.asarray(D0, float) for D0 in D0s]))

    def _Split(self, rows: np.ndarray):
        data = torch.tensor(rows)
        L = self._layout
        sample = data[..., 1:]
        return (data[..., 0], sample[..., L.q], sample[..., L.p], sample[..., L.qdot],
                sample[..., L.u], sample[..., L.tau])

    def Weights(self, times: torch.Tensor, t_now: float, window_starts: Sequence[float]
                ) -> torch.Tensor:
        """The samples' weights (trials, samples), sum 1 per trial (uniform in plain mode).

        Args:
            times: The samples' times (trials, samples) [s].
            t_now: The current time [s].
            window_starts: Each trial's window start [s] (zero weight before it)."""
        if not self._regularized:
            w = torch.ones_like(times)
        else:
            w = torch.exp((times - t_now) / self._settings.forgetting)
            starts = torch.as_tensor(np.asarray(window_starts, float))[:, None]
            w = torch.where(times >= starts, w, torch.zeros_like(w))
        return w / torch.clamp(w.sum(-1, keepdim=True), min=1e-300)

    def _Losses(self, w, q, p, qdot, u, tau, trials):
        """The loss of each trial of ``trials`` (None: all) on its window."""
        B, D = self.network(q, p, trials)
        residual = tau - port_torque(B, D, u, qdot)
        data = torch.sum(w * torch.sum(residual**2, -1), -1)
        if not self._regularized:
            return data
        B0, D0 = ((self._B0, self._D0) if trials is None
                  else (self._B0[trials], self._D0[trials]))
        B0, D0 = B0[:, None], D0[:, None]
        E_u = torch.sum(w * torch.sum(u**2, -1), -1) / self.n
        E_q = torch.sum(w * torch.sum(qdot**2, -1), -1) / self.n
        if self._settings.prior_scale == "per_input":
            E_input = torch.sum(w[..., None] * u**2, 1)
            E_entry = torch.maximum(E_input[:, :, None], E_input[:, None, :])
            prior_B = torch.sum(w * torch.sum(E_entry[:, None] * (B - B0)**2, (2, 3)), -1)
        else:
            prior_B = E_u * torch.sum(w * torch.sum((B - B0)**2, (2, 3)), -1)
        prior = prior_B + E_q * torch.sum(w * torch.sum((D - D0)**2, -1), -1)
        return (data + self._settings.prior_weight * prior) / torch.clamp(
            E_u + E_q, min=1e-300)

    def ConstantFit(self, rows: np.ndarray, t_now: float, window_start: float,
                    trial: int = 0) -> np.ndarray:
        """The constant B (n x n) best fitting a trial's window with the current D_hat(x):
        row i by weighted ridge least squares of tau_i + D_hat_i qdot_i on u, B_ij held to
        B0_ij with weight rho E_ij / F_ij^2, as in training (the network steps B_ij by F_ij
        times its own). D is left to Adam: on heavy joints it is hardly in the data.

        Args:
            rows: Trial ``trial``'s window (samples, 1 + PortSample size).
            t_now: The current time [s].
            window_start: The window's start [s] (zero weight before it).
            trial: The trial."""
        times, q, p, qdot, u, tau = self._Split(rows[None])
        w = self.Weights(times, t_now, [window_start])[0].numpy()
        with torch.no_grad():
            D = self.network(q, p, [trial])[1][0].numpy()
        q, p, qdot, u, tau = (x[0].numpy() for x in (q, p, qdot, u, tau))
        n, rho = self.n, self._settings.prior_weight
        E_input = w @ u**2                                   # E_j, per input
        E_u = E_input.sum() / n
        B0 = self._B0[trial].numpy()
        coupling = self.network.coupling[trial].numpy()
        normal = u.T @ (w[:, None] * u)
        B = np.empty((n, n))
        target = tau + D * qdot
        for i in range(n):
            E_B = (np.maximum(E_input[i], E_input) if self._settings.prior_scale
                   == "per_input" else np.full(n, E_u))
            prior = rho * E_B / coupling[i]**2
            B[i] = np.linalg.solve(normal + np.diag(prior),
                                   u.T @ (w * target[:, i]) + prior * B0[i])
        return B

    def WarmStart(self, rows: np.ndarray, t_now: float, window_start: float,
                  trial: int = 0) -> None:
        """Restarts a trial's B_hat at its window's ConstantFit, and Adam's moments of that
        layer only (fresh moments make Adam's next steps about lr, which would kick D_hat).

        Args:
            rows: The trial's window (samples, 1 + PortSample size).
            t_now: The current time [s].
            window_start: The window's start [s].
            trial: The trial."""
        self.network.set_constant_B(trial, self.ConstantFit(rows, t_now, window_start,
                                                            trial))
        head = self.network.head_B_columns
        self._m[trial, head] = self._v[trial, head] = self._steps[trial, head] = 0.0

    def Fit(self, rows: np.ndarray, t_now: float, window_start: float = -np.inf) -> bool:
        """FitTrials of a batch of one: whether its steps were kept.

        Args:
            rows: The window (samples, 1 + PortSample size).
            t_now: The current time [s].
            window_start: The window's start [s]."""
        return bool(self.FitTrials(rows[None], t_now, [window_start], np.array([True]))[0])

    def FitTrials(self, rows: np.ndarray, t_now: float, window_starts: Sequence[float],
                  fitting: np.ndarray) -> np.ndarray:
        """Takes settings.steps_per_update Adam steps of some trials and returns whose were
        kept: in regularized mode with step_guard G > 0 a trial's are undone if they raise
        its loss over G times its loss before (Adam's moments keep the gradients seen).

        Args:
            rows: The trials' windows (trials, samples, width).
            t_now: The current time [s].
            window_starts: Each trial's window start [s].
            fitting: Which trials to fit (a mask, (trials,))."""
        trials = np.flatnonzero(fitting)
        kept = np.zeros(len(fitting), bool)
        if not len(trials):
            return kept
        times, q, p, qdot, u, tau = self._Split(rows[trials])
        w = self.Weights(times, t_now, np.asarray(window_starts, float)[trials])
        guard = self._settings.step_guard if self._regularized else 0.0
        every = len(trials) == len(fitting)
        index = None if every else torch.as_tensor(trials)
        flat = self.network.flat
        before = flat.detach()[trials].clone() if guard else None
        loss_before = None
        for _ in range(self._settings.steps_per_update):
            flat.grad = None
            losses = self._Losses(w, q, p, qdot, u, tau, index)
            loss_before = losses.detach() if loss_before is None else loss_before
            torch.sum(losses).backward()
            self._AdamStep(trials, every)
        kept[trials] = True
        if not guard or loss_before is None:
            return kept
        with torch.no_grad():
            undone = (self._Losses(w, q, p, qdot, u, tau, index)
                      > guard * loss_before).numpy()
            if np.any(undone):
                flat[trials[undone]] = before[undone]
        kept[trials[undone]] = False
        return kept

    def _AdamStep(self, trials: np.ndarray, every: bool) -> None:
        """One torch.optim.Adam step of ``trials`` (``every``: all), moments per trial."""
        s, flat = self._settings, self.network.flat
        rows = slice(None) if every else torch.as_tensor(trials)
        with torch.no_grad():
            g = flat.grad[rows]
            steps = self._steps[rows] + 1.0
            m = s.beta1 * self._m[rows] + (1 - s.beta1) * g
            v = s.beta2 * self._v[rows] + (1 - s.beta2) * g * g
            self._steps[rows], self._m[rows], self._v[rows] = steps, m, v
            denominator = torch.sqrt(v) / torch.sqrt(1 - s.beta2**steps) + s.eps
            flat[rows] -= (s.learning_rate / (1 - s.beta1**steps)) * m / denominator

    def Statistics(self, rows: np.ndarray, t_now: float,
                   window_start: float = -np.inf) -> FitStatistics:
        """FitStatistics of a batch of one (StatisticsOfTrials), as floats.

        Args:
            rows: The window (samples, 1 + PortSample size).
            t_now: The current time [s].
            window_start: The window's start [s]."""
        stats = self.StatisticsOfTrials(rows[None], t_now, [window_start])
        return FitStatistics(*(float(x[0]) for x in (stats.loss, stats.nominal_loss,
                                                     stats.beta_hat)))

    def StatisticsOfTrials(self, rows: np.ndarray, t_now: float,
                           window_starts: Sequence[float]) -> FitStatistics:
        """FitStatistics (fields (trials,)) of each trial on its window, recency-weighted in
        regularized mode, samples before a change included (they show the stale misfit).

        Args:
            rows: The trials' windows (trials, samples, width).
            t_now: The current time [s].
            window_starts: Each trial's window start [s]."""
        times, q, p, qdot, u, tau = self._Split(rows)
        w = self.Weights(times, t_now, window_starts)
        with torch.no_grad():
            residual = tau - port_torque(*self.network(q, p), u, qdot)
            nominal = tau - port_torque(self._B0[:, None], self._D0[:, None], u, qdot)
            loss = torch.sum(w * torch.sum(residual**2, -1), -1).numpy()
            nominal_loss = torch.sum(w * torch.sum(nominal**2, -1), -1).numpy()
            signal = torch.sum(w * torch.sum(tau**2, -1), -1).numpy()
        return FitStatistics(loss=loss, nominal_loss=nominal_loss,
                             beta_hat=1.0 + np.sqrt(loss / np.maximum(signal, 1e-300)))

    def RelativeResiduals(self, rows: np.ndarray) -> np.ndarray:
        """Each trial's relative residual sqrt(sum ||r||^2 / sum ||tau||^2) (trials,).

        Args:
            rows: The trials' rows (trials, samples, width)."""
        _, q, p, qdot, u, tau = self._Split(rows)
        with torch.no_grad():
            residual = tau - port_torque(*self.network(q, p), u, qdot)
            return torch.sqrt(torch.sum(residual**2, (1, 2)) / torch.clamp(
                torch.sum(tau**2, (1, 2)), min=1e-300)).numpy()

    def Estimate(self, q: np.ndarray, p: np.ndarray, trial: int = 0
                 ) -> Tuple[np.ndarray, np.ndarray]:
        """A trial's estimate (B_hat (n x n), diag D_hat (n,)) at one state.

        Args:
            q: The joint angles (n) [rad].
            p: The port's momentum (n).
            trial: The trial."""
        with torch.no_grad():
            B, D = self.network(torch.as_tensor(q)[None, None],
                                torch.as_tensor(p)[None, None], [trial])
        return B[0, 0].numpy(), D[0, 0].numpy()

    def Export(self) -> np.ndarray:
        """Each trial's exported parameters (trials, size)."""
        return self.network.export()


class ChangeDetector:
    """Flags an abrupt change of the port relation; state (for a Drake Context) [hold_until,
    window_start, count, the last HISTORY relative residuals]. Nothing while t < hold_until;
    a change if MIN_HISTORY residuals are known and e_new > max(ratio median(history),
    floor) (Changed); else e_new joins the history.

    Args:
        ratio: The jump over the history's median that is a change.
        floor: The smallest residual that is a change.
        hold: How long training pauses after a change [s]."""

    HISTORY = 30
    MIN_HISTORY = 5

    def __init__(self, ratio: float, floor: float, hold: float):
        self._ratio, self._floor, self._hold = ratio, floor, hold

    @classmethod
    def InitialState(cls, hold_until: float = -np.inf) -> np.ndarray:
        """The state at the start: no history.

        Args:
            hold_until: When > 0, as if a change had been detected at t = 0 [s]."""
        return np.concatenate([[hold_until, hold_until, 0.0], np.zeros(cls.HISTORY)])

    @staticmethod
    def Holding(state: np.ndarray, t: float) -> bool:
        """Whether training holds at time t after a change: t < hold_until.

        Args:
            state: The detector's state.
            t: The time [s]."""
        return t < state[0]

    @staticmethod
    def WindowStart(state: np.ndarray) -> float:
        """window_start [s], the start of the window after the last change.

        Args:
            state: The detector's state."""
        return float(state[1])

    def Changed(self, state: np.ndarray, t: float) -> np.ndarray:
        """The state after a change at t: hold_until = window_start = t + hold, no history.

        Args:
            state: The detector's state.
            t: The change's time [s]."""
        state = state.copy()
        state[0] = state[1] = t + self._hold
        state[2] = 0.0
        return state

    def Update(self, state: np.ndarray, t: float, e_new: float) -> np.ndarray:
        """The state after the newest samples' relative residual (class docstring).

        Args:
            state: The detector's state.
            t: The time [s].
            e_new: The newest samples' relative residual."""
        state = state.copy()
        if t < state[0] or not np.isfinite(e_new):
            return state
        count = int(state[2])
        known = state[3:3 + min(count, self.HISTORY)]
        if (count >= self.MIN_HISTORY and e_new > self._ratio * np.median(known)
                and e_new > self._floor):
            return self.Changed(state, t)
        else:
            state[3 + count % self.HISTORY] = e_new
            state[2] = count + 1
        return state


def NewestRows(rows: np.ndarray, t_now: float, period: float) -> np.ndarray:
    """The rows sampled in the last ``period`` before t_now (along the next-to-last axis).

    Args:
        rows: A batch's windows (trials, samples, width) or one; the time in column 0.
        t_now: The current time [s].
        period: How far back to take the rows [s]."""
    times = rows.reshape((-1,) + rows.shape[-2:])[0, :, 0]       # the first window's
    return rows[..., times > t_now - period + 1e-12, :]
