"""RHS controller: decentralized integral control around the learned inverse
feed-forward (paper section "RHS Control and Learning", docs/equations.md E36-E38, E48)."""
from dataclasses import dataclass
from typing import Optional, Sequence, Tuple

import numpy as np
from pydrake.systems.framework import Context, LeafSystem

from dacph_drake.gain_rule import (c_lower_bound, certified_radius,
                                   integral_gains, lag_pole, separates_by_decay,
                                   stays_stable_if_wrong, well_damped_loop_gain,
                                   within_trust)
from dacph_drake.learning.identification import PortEvidence, PortSample
from dacph_drake.kernels.certificate import certified_gains
from dacph_drake.kernels.loop import integrator_samples
from dacph_drake.learning import Channels, PublishedModel
from dacph_drake.log_layout import RhsLog, RhsState
from dacph_drake.dynamics import ReducedModel
from dacph_drake.scenario import Rhs, Stress
from dacph_drake.systems.reduced_model_input import ReducedModelInput


@dataclass
class RhsTrial:
    """One trial's part of an RhsIntegrator.

    Attributes:
        model: The controller's model (p = M qdot without input ``reduced_model``).
        network: The evaluator of the learner's published vector (PublishedModel).
        Kd_max: lambda_max(K_d) of the LHS, for the gain rule (eq. 48).
        lambda_min_M: inf_q lambda_min(M), for the gain rule (eq. 48).
        B0: The nominal RHS's B0 (its diagonal, n).
        D0: The nominal RHS's D0 (its diagonal, n) [N m s].
        prior_set: The prior's range of B ([lower, upper], 2 x n x n) or None (gain floor).
    """
    model: ReducedModel
    network: PublishedModel
    Kd_max: float
    lambda_min_M: float
    B0: Sequence[float]
    D0: Sequence[float]
    prior_set: Optional[np.ndarray] = None


class RhsIntegrator(LeafSystem):
    """Decentralized integral control around the learned inverse feed-forward. Every
    ``period`` h, at sample k (kernels.loop.integrator_samples):

        e_tau = tau_c^r(k-1) - tau_obs(k)
        u_I <- u_I + h K e_tau
        u    = B_hat^-1 (tau_c^r + D_hat qdot) + u_I
        chi  = max(||e_tau||, chi e^(-h / chi_window), chi_floor)

    (tau_obs(k) was formed at sample k-1, so it is compared with that instant's request:
    against the current one the integrator would wind up on the request's increment).
    With ``noisy_torque`` the logged e_tau, and the chi it sets, is that error low-passed
    at the loop's rate, e_tau <- e_tau + (1 - e^(-c h)) (e - e_tau): the loop removes no
    error faster than c, so what is faster is the observer's noise, and a chi that
    followed the noise would raise the LHS's robust gain chi / phi with it (LHS eq.
    "tau_c^r") until the two loops no longer separate.

    Every ``model_period`` it refreshes B_hat(x), D_hat(x) at x = (q, p = M qdot), the
    gains k_p = c / Re(lambda_hat_p) and c, filtered towards (1 + c_margin) c_min(beta)
    (eq. 48), beta = min(beta_hat, beta_max), never below c_min (gain_rule "well_damped":
    c = 1 / (4 period)), never above the best-damped rate g* / h of the loop with the
    command's known delay and lag (gain_rule.well_damped_loop_gain; 1 / (4 h) without
    them, which no target exceeds: stability before separation). An estimate failing DIC or leaving the trust band
    (``trust_ratio`` around ``trust_anchor``) is not adopted, unless on evidence: its port
    residual at most ``evidence_ratio`` times the in-use one and the loop stable were the
    in-use estimate true. B_hat stays within trust_ratio^2 of B0. With ``adoption``
    "certified_set" the set's certificate (kernels.certificate.certified_gains) replaces
    band and evidence: adopted only if some c in [c_min, 1 / (4 period)] certifies the
    loop for every B of the set, each mode within ``trust_ratio`` of the in-use set's
    range; c and K never fall below the loop's without learning (RhsTrial.prior_set).

    Inputs ``tau_request``, ``tau_observed``, ``q``, ``qdot``, ``weights``, ``beta_hat``,
    ``port_sample`` and ``reduced_model`` (both optional). The certificate knows the
    command's delay and the actuators' lag (``command_delay``; kernels.certificate):
    its radius is gain_rule.certified_radius, and with either the separation is the
    loop's decay rate (gain_rule.separates_by_decay). Outputs ``u``, ``chi`` and
    ``rhs_log`` (log_layout.RhsLog), each trial's stacked.

    Args:
        trials: Each trial's RhsTrial.
        settings: The RHS loop's settings (scenario.rhs).
        period: The integrator's period h [s].
        model_period: The model refresh's period [s].
        stress: Verification setting: B_hat scaled by B_hat_scale from stress.start on.
        channels: The learner's channels in ``port_sample`` (default: PortSample).
        command_delay: (samples by which u acts late, the actuators' time constant [s])
            (Sensing.KnownCommandDelay).
        noisy_torque: tau_obs carries measurement noise (learning.observation_noise)."""

    def __init__(self, *, trials: Sequence[RhsTrial], settings: Rhs, period: float,
                 model_period: float, stress: Stress = Stress(),
                 channels: Optional[Channels] = None,
                 command_delay: Tuple[int, float] = (0, 0.0),
                 noisy_torque: bool = False):
        super().__init__()
        n = trials[0].model.num_joints
        count = len(trials)
        self._n, self._trials = n, list(trials)
        self._published = trials[0].network.Stack([trial.network for trial in trials])
        self._certified_set = (settings.adoption == "certified_set"
                               and self._published.has_uncertainty)
        self._B0 = np.array([trial.B0 for trial in trials], float)
        self._Kd_max = np.array([trial.Kd_max for trial in trials], float)
        self._lambda_min_M = np.array([trial.lambda_min_M for trial in trials], float)
        self._settings = settings
        self._stress = stress
        self._constants = np.array([period, np.exp(-period / settings.chi_window),
                                    settings.chi_floor, float(noisy_torque)])
        self._c_step = min(1.0, model_period / settings.c_time_constant)
        self._period = period
        self._command_delay = (int(command_delay[0]), float(command_delay[1]))
        self._delay, self._pole = self._command_delay[0], lag_pole(period, command_delay[1])
        # lambda_LHS = 2 lambda_max(K_d) / inf lambda_min(M) (eq. 45), and the largest
        # rate a certified set may ask: the fastest well-damped one.
        self._lambda_lhs = 2.0 * self._Kd_max / self._lambda_min_M
        self._c_cap = well_damped_loop_gain(period, *command_delay) / period
        # The certificate with the delay and lag: its radius and how it separates.
        self._certified_radius = certified_radius(period, *command_delay)
        self._by_decay = separates_by_decay(*command_delay)
        # c's target at beta: the paper's (1 + c_margin) c_min(beta), or at least the
        # fastest well-damped rate (Rhs.gain_rule); at most that rate (without a delay
        # or a lag check_rhs_period keeps every target below it).
        self._c_floor = self._c_cap if settings.gain_rule == "well_damped" else 0.0
        # The rate and gains the loop without learning settles at: the prior B0
        # certified on the prior's set (RhsTrial.prior_set) at the rule's c; no
        # floor without one.
        self._no_learning_c, self._no_learning_gains = np.zeros(count), np.zeros((count, n))
        if self._certified_set and all(t.prior_set is not None for t in trials):
            prior_sets = np.stack([np.asarray(t.prior_set, float) for t in trials], axis=1)
            out, K = self._SetGains(prior_sets, self._B0, np.ones(count), None,
                                    self._no_learning_gains, self._no_learning_c)[:2]
            certified = out[:, 1] > 0.5
            self._no_learning_c = np.where(certified, out[:, 0], 0.0)
            self._no_learning_gains = np.where(certified[:, None], K, 0.0)
        network_size = self._published.size
        self._tau_request = self.DeclareVectorInputPort("tau_request", n * count)
        self._tau_observed = self.DeclareVectorInputPort("tau_observed", n * count)
        self._q = self.DeclareVectorInputPort("q", n * count)
        self._qdot = self.DeclareVectorInputPort("qdot", n * count)
        self._weights = self.DeclareVectorInputPort("weights", network_size * count)
        self._beta_hat = self.DeclareVectorInputPort("beta_hat", count)
        sample_size = (PortSample(n).size if channels is None
                       else 2 * n + channels.size)
        self._port_sample = self.DeclareVectorInputPort("port_sample",
                                                        sample_size * count)
        self._reduced_model = ReducedModelInput(self, n, [t.model for t in trials])
        self._evidence = PortEvidence(n, model_period, settings.evidence_window,
                                      None if channels is None else channels.port_columns)
        self._evidence_minimum = 0.5 * settings.evidence_window / model_period
        self._evidence_index = self.DeclareDiscreteState(self._evidence.size * count)
        # The fast and model groups (log_layout.RhsState), per trial; u is a group of
        # its own, so that its output port (read at every integrator stage by the
        # true RHS) reads the state without a Python call.
        self._layout = layout = RhsState(n)
        fast = np.zeros(layout.fast_size)
        fast[layout.chi] = settings.chi_initial
        self._fast = self.DeclareDiscreteState(np.tile(fast, count))
        self._u_index = self.DeclareDiscreteState(n * count)
        # The model group starts at the nominal RHS (B0, D0) with c = (1 + c_margin)
        # c_min(beta_hat = 1); an initialization event then refreshes it from the
        # input ports (the learner's weights at the initial state).
        ones = np.ones(count)
        c0 = self._CTarget(ones)
        models = np.zeros((count, layout.model_size))
        models[:, layout.B_inverse] = np.array([np.diag(1.0 / B0) for B0 in self._B0]
                                               ).reshape(count, -1)
        models[:, layout.D_hat] = [trial.D0 for trial in trials]
        models[:, layout.K] = integral_gains(np.array([np.diag(B0) for B0 in self._B0]),
                                             c0)[0]
        models[:, layout.c], models[:, layout.c_min] = c0, self._CBound(ones)
        if self._delay or self._pole:
            # c0's well-damped rate is the undelayed loop's: with a delay or a lag the
            # loop starts at the prior set's certified rate and gains, where certified.
            start = self._no_learning_c > 0
            models[start, layout.c] = self._no_learning_c[start]
            models[start, layout.K] = self._no_learning_gains[start]
        models[:, layout.dic_ok] = models[:, layout.trusted] = 1.0
        models[:, layout.set_slowest] = models[:, layout.set_fastest] = np.nan
        models[:, layout.mode_low], models[:, layout.mode_high] = 0.0, np.inf
        self._gains = self.DeclareDiscreteState(models.reshape(-1))
        fast_ticket = {self.discrete_state_ticket(self._fast)}
        chi = np.arange(count) * layout.fast_size + layout.chi
        self.DeclareStateOutputPort("u", self._u_index)
        self.DeclareVectorOutputPort("chi", count, lambda c, o: o.SetFromVector(
            c.get_discrete_state(self._fast).get_value()[chi]),
            prerequisites_of_calc=fast_ticket)
        self.DeclareVectorOutputPort(
            "rhs_log", RhsLog(n).size * count, self._CalcLog,
            prerequisites_of_calc={self.discrete_state_ticket(self._fast),
                                   self.discrete_state_ticket(self._gains)})
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._UpdateIntegrator)
        self.DeclarePeriodicDiscreteUpdateEvent(model_period, 0.0, self._UpdateModel)
        self.DeclareInitializationDiscreteUpdateEvent(self._UpdateModel)

    def _CBound(self, beta: np.ndarray) -> np.ndarray:
        """c_min(beta) of eq. (48) of each trial, with its LHS rates."""
        return c_lower_bound(self._settings.Td, self._Kd_max, self._lambda_min_M, beta)

    def _CTarget(self, beta: np.ndarray) -> np.ndarray:
        return np.minimum(np.maximum((1 + self._settings.c_margin) * self._CBound(beta),
                                     self._c_floor), self._c_cap)

    def GetModelGroup(self, context: Context) -> np.ndarray:
        """A copy of the trials' stacked model groups (log_layout.RhsState) in ``context``.

        Args:
            context: This system's context."""
        return context.get_discrete_state(self._gains).get_value().copy()

    def _Refresh(self, gains, weights, t, q, p, beta, B_hat_scale, evidence=None):
        """The trials' model groups after one refresh from ``gains`` at x = (q, p)."""
        L = self._layout
        gains = gains.copy()
        estimate = self._published.Estimate(weights, t, q, p)
        B_hat, D_hat = B_hat_scale * estimate.B, estimate.D
        k, paired, dic_ok = integral_gains(B_hat, gains[:, L.c])
        if self._certified_set:
            gains = self._Certify(gains, B_hat, D_hat, B_hat_scale * estimate.B_set,
                                  paired, dic_ok, beta)
            gains[:, L.dic_ok] = dic_ok
            return gains
        beta = np.minimum(beta, self._settings.beta_max)
        c_min = self._CBound(beta)
        c = gains[:, L.c]
        c = np.minimum(np.maximum(c + self._c_step * (self._CTarget(beta) - c), c_min),
                       self._c_cap)
        k, paired, dic_ok = integral_gains(B_hat, c)
        trusted = dic_ok & self._Accepts(gains, B_hat, D_hat, paired, k, dic_ok,
                                          evidence)
        if np.any(trusted):
            gains[trusted, L.B_inverse] = np.linalg.inv(B_hat[trusted]).reshape(
                np.count_nonzero(trusted), -1)
            gains[trusted, L.D_hat] = D_hat[trusted]
            gains[trusted, L.K] = k[trusted]
        kept = ~trusted   # keep B_hat^-1, D_hat; K follows c with the kept eigenvalues
        gains[kept, L.K] *= (c / gains[:, L.c])[kept, None]
        gains[:, L.c], gains[:, L.c_min] = c, c_min
        gains[:, L.dic_ok], gains[:, L.trusted] = dic_ok, trusted
        return gains

    def _SetGains(self, B_set, eigenvalues, beta, c, floor, c_floor):
        """certified_gains for each trial's set (2, trials, n, n) at
        beta = max(beta, 1 / slowest mode ratio) <= beta_max, c filtered from ``c`` (None:
        the target) and >= ``c_floor``, gains raised to ``floor`` where certified.
        Returns (out (trials, 4), K, c_min, mode_low, mode_high) (Gershgorin ranges)."""
        settings = self._settings
        lower, upper = np.minimum(B_set[0], B_set[1]), np.maximum(B_set[0], B_set[1])
        radius = _off_diagonal_bound(lower, upper)
        mode_low = np.diagonal(lower, axis1=1, axis2=2) - radius
        mode_high = np.diagonal(upper, axis1=1, axis2=2) + radius
        with np.errstate(divide="ignore", invalid="ignore"):
            slowest = np.min(mode_low / eigenvalues, axis=1)
        beta = np.minimum(np.maximum(beta, np.where(slowest > 0, 1.0 / slowest, np.inf)),
                          settings.beta_max)
        c_min = self._CBound(beta)
        target = self._CTarget(beta)
        if c is not None:
            target = c + self._c_step * (target - c)
        target = np.maximum(target, c_floor)
        out, K = np.empty((len(eigenvalues), 4)), np.empty(eigenvalues.shape)
        certified_gains(lower, upper, eigenvalues, floor, target, c_min,
                        settings.Td * self._lambda_lhs, self._period, self._c_cap,
                        self._certified_radius, out, K, self._delay, self._pole,
                        self._by_decay)
        return out, K, c_min, mode_low, mode_high

    def _Certify(self, gains, B_hat, D_hat, B_set, paired, dic_ok, beta):
        """Certified-set adoption: adopt with the set's c, or keep the estimate in use."""
        L, settings = self._layout, self._settings
        eigenvalues = np.where(dic_ok[:, None], paired.real, 1.0)
        out, K, c_min, mode_low, mode_high = self._SetGains(
            B_set, eigenvalues, beta, gains[:, L.c], self._no_learning_gains,
            self._no_learning_c)
        # The trust band around the set in use: each mode's estimate within
        # trust_ratio of the in-use set's range of it (a jump beyond it is taken
        # only through the prior's range, which the learner publishes after a
        # detected change).
        ratio = settings.trust_ratio
        within = np.all((eigenvalues <= gains[:, L.mode_high] * ratio)
                        & (eigenvalues >= gains[:, L.mode_low] / ratio), axis=1)
        adopted = dic_ok & (out[:, 1] > 0.5) & within
        if np.any(adopted):
            gains[adopted, L.B_inverse] = np.linalg.inv(B_hat[adopted]).reshape(
                np.count_nonzero(adopted), -1)
            gains[adopted, L.D_hat] = D_hat[adopted]
            gains[adopted, L.K] = K[adopted]
            gains[adopted, L.c] = out[adopted, 0]
            gains[adopted, L.c_min] = c_min[adopted]
            gains[adopted, L.certified] = 1.0
            gains[adopted, L.set_slowest] = out[adopted, 2]
            gains[adopted, L.set_fastest] = out[adopted, 3]
            gains[adopted, L.mode_low] = mode_low[adopted]
            gains[adopted, L.mode_high] = mode_high[adopted]
        # A candidate the set does not certify leaves the estimate in use, its c
        # and K as they were: they were certified on its own set.
        gains[:, L.trusted] = adopted
        return gains

    def _Accepts(self, gains, B_hat, D_hat, paired, k, dic_ok, evidence) -> np.ndarray:
        """Which DIC-passing estimates are adopted: in the trust band, or on evidence."""
        L, settings = self._layout, self._settings
        # Anchored at the estimate in use, the band could follow a learner that
        # drifts slowly: overall, the estimate stays within trust_ratio^2 of B0.
        bounded = dic_ok & within_trust(paired, self._B0, settings.trust_ratio**2)
        anchor = (self._B0 if settings.trust_anchor == "prior"
                  else gains[:, L.c, None] / gains[:, L.K])   # K_p = c / Re(lambda_p)
        accepted = bounded & within_trust(paired, anchor, settings.trust_ratio)
        if settings.evidence_ratio == 0 or evidence is None:
            return accepted
        for i in np.flatnonzero(bounded & ~accepted):
            if PortEvidence.Weight(evidence[i]) < self._evidence_minimum:
                continue
            in_use = np.linalg.inv(gains[i, L.B_inverse].reshape(B_hat[i].shape))
            accepted[i] = (self._evidence.Residual(evidence[i], B_hat[i], D_hat[i])
                           <= settings.evidence_ratio
                           * self._evidence.Residual(evidence[i], in_use,
                                                     gains[i, L.D_hat])
                           and stays_stable_if_wrong(in_use, k[i], self._period,
                                                     self._certified_radius,
                                                     *self._command_delay))
        return accepted

    def _UpdateModel(self, context, discrete_state):
        n, count = self._n, len(self._trials)
        betas = (self._beta_hat.Eval(context) if self._beta_hat.HasValue(context)
                 else np.ones(count))
        evidence = None
        if self._port_sample.HasValue(context):
            evidence = self._evidence.Update(
                context.get_discrete_state(self._evidence_index).get_value().reshape(
                    count, -1), self._port_sample.Eval(context).reshape(count, -1))
            discrete_state.get_mutable_vector(self._evidence_index).SetFromVector(
                evidence.reshape(-1))
        q = self._q.Eval(context).reshape(count, n)
        qdot = self._qdot.Eval(context).reshape(count, n)
        p = self._reduced_model.Momenta(context, q, qdot)
        B_hat_scale = (self._stress.B_hat_scale
                       if context.get_time() >= self._stress.start else 1.0)
        gains = self._Refresh(
            context.get_discrete_state(self._gains).get_value().reshape(count, -1),
            self._weights.Eval(context).reshape(count, -1), context.get_time(), q, p,
            betas, B_hat_scale, evidence)
        discrete_state.get_mutable_vector(self._gains).SetFromVector(gains.reshape(-1))

    def _UpdateIntegrator(self, context, discrete_state):
        fast, u = integrator_samples(
            len(self._trials), context.get_discrete_state(self._fast).get_value(),
            context.get_discrete_state(self._gains).get_value(),
            self._tau_request.Eval(context), self._tau_observed.Eval(context),
            self._qdot.Eval(context), self._constants)
        discrete_state.get_mutable_vector(self._fast).SetFromVector(fast)
        discrete_state.get_mutable_vector(self._u_index).SetFromVector(u)

    def _CalcLog(self, context, output):
        L, count = self._layout, len(self._trials)
        fast = context.get_discrete_state(self._fast).get_value().reshape(count, -1)
        gains = context.get_discrete_state(self._gains).get_value().reshape(count, -1)
        output.SetFromVector(np.concatenate([fast[:, L.fast_logged],
                                             gains[:, L.model_logged]], axis=1).reshape(-1))



def _off_diagonal_bound(lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """R_p = sum_{j != p} max(|lower_pj|, |upper_pj|) of each trial's box (trials, n)."""
    largest = np.maximum(np.abs(lower), np.abs(upper))
    return np.sum(largest, axis=-1) - np.diagonal(largest, axis1=-2, axis2=-1)
