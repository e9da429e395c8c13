"""Identification of the bodies' inertial parameters from momentum conservation (a
project extension for the LHS's "parametric uncertainties (e.g., misidentified mass
or inertia)", docs/equations.md E8-E9)."""
from typing import Optional, Sequence

import numpy as np
from pydrake.multibody.plant import MultibodyPlant
from pydrake.systems.framework import LeafSystem

from dacph_drake.dynamics.inertial_parameters import (
    MASS, PER_BODY, compensated_information, identify_parameters, mass_anchor,
    momentum_misfit, prior_scales)
from dacph_drake.dynamics.model_error import ModelErrorEnsemble
from dacph_drake.dynamics.plant import ArmCoordinates
from dacph_drake.dynamics.sensor_noise import StateNoise, base_rate_columns
from dacph_drake.dynamics.tree_stack import TreeStack, positive_definite
from dacph_drake.scenario import InertiaIdentification


class InertialIdentifier(LeafSystem):
    """Identifies the bodies' inertial parameters pi every ``period`` h from the measured
    state (inputs ``base_pose``, ``base_velocity``, ``q``, ``qdot``):

        A <- A + Y(x)^T Y(x),      Y(x) pi = [L; P] (the momentum, linear in pi)
        pi_hat = argmin pi^T A pi + r (pi - pi0)^T S^-2 (pi - pi0),
                 subject to pi0^T S^-2 pi = pi0^T S^-2 pi0

    (r = ``settings.prior_weight``). From rest L = P = 0 and Y(x) pi~ = 0: the samples
    determine pi up to a common factor, fixed by the prior or a measured mass
    (``settings.anchor``); no actuator model enters. A momentum misfit above
    ``settings.fit_tolerance`` reports the kinematics mismatched (latched;
    ``settings.on_mismatch`` "nominal": the LHS returns to the prior).

    Every ``error_period`` it measures the LHS model's inertia error E = M_hat M~^-1 - I
    (dynamics.model_error.ModelErrorEnsemble): output ``model_error``, E's sd per entry.

    With noisy sensors (``noise``, dynamics.sensor_noise) the noise's expected share of
    A, Sigma = sum_k sum_j sigma_j^2 Y(x_k, e_j)^T Y(x_k, e_j) over the noisy rates j,
    accumulates beside it, pi_hat is identified from compensated_information(A, Sigma),
    and it replaces the nominal only where the draws (which read the noise again) put
    E's sd below ``settings.nominal_tolerance`` in every entry, checked every
    ``error_period``; elsewhere the LHS keeps the nominal and E's sd is that tolerance.
    pi_hat (and the misfit logged) is then computed at the update before each check,
    its only reader, and at the window's last.

    Outputs ``identification_log`` = [total mass [kg], momentum misfit, mismatch (0/1)],
    ``inertial_parameters`` (pi0 until ``settings.start``, then pi_hat until
    ``settings.duration``; an estimate with mass <= 0 or an indefinite M is not used) and
    ``model_epoch``, counting estimates that changed M(q) by more than
    ``settings.change_threshold`` relative to sqrt(M_ii M_jj) (the learner takes a new
    epoch as a change of the port). Ports stack the trials; each is identified alone.

    Args:
        plants: Each trial's controller plant (its kinematic tree and layout).
        settings: The identification's settings (scenario.inertia).
        period: The sample period [s].
        error_period: The period of E's measurement [s].
        seeds: Each trial's seed (its draws of plausible models).
        priors: Each trial's prior pi0, or None for the plant's own inertias.
        measured_masses: Each trial's measured (total, base) mass [kg] of its ground truth
            (the anchor when settings.anchor_mass is 0).
        noise: The noise on each reading of the measured state (the draws that measure E
            read it too; ModelErrorEnsemble)."""

    def __init__(self, *, plants: Sequence[MultibodyPlant],
                 settings: InertiaIdentification, period: float,
                 error_period: float, seeds: Sequence[int],
                 priors: Optional[Sequence[np.ndarray]] = None,
                 measured_masses: Optional[Sequence[Sequence[float]]] = None,
                 noise: StateNoise = StateNoise()):
        super().__init__()
        priors = [None] * len(plants) if priors is None else priors
        self._trees = TreeStack(plants)
        self.parameters = self._trees.parameters
        self._priors = np.array([
            self.parameters.FromContext(plant.CreateDefaultContext()) if prior is None
            else np.asarray(prior, float) for plant, prior in zip(plants, priors,
                                                                  strict=True)])
        self._scales = np.array([prior_scales(self.parameters, prior)
                                 for prior in self._priors])
        self._settings, self._period = settings, period
        self._error_period = error_period
        count, size = len(plants), self.parameters.size
        self._anchor, self._anchor_value = self._Anchor(settings, measured_masses, count)
        c = ArmCoordinates.FromPlant(plants[0])
        self._base_pose = self.DeclareVectorInputPort("base_pose", len(c.base_q) * count)
        self._base_velocity = self.DeclareVectorInputPort("base_velocity",
                                                          len(c.base_v) * count)
        self._q = self.DeclareVectorInputPort("q", c.num_joints * count)
        self._qdot = self.DeclareVectorInputPort("qdot", c.num_joints * count)
        self._information = self.DeclareDiscreteState(size * size * count)
        self._noise, self._rate_columns = noise, base_rate_columns(len(c.base_v))
        # The noise's expected share of the information (TreeStack.AddNoiseInformation).
        self._noise_information = (self.DeclareDiscreteState(size * size * count)
                                   if noise.Any() else None)
        # With noisy sensors: each trial's latest identified parameters, and those the
        # draws last put within the nominal's error (else the nominal): the candidates.
        self._identified = (self.DeclareDiscreteState(self._priors.reshape(-1))
                            if noise.Any() else None)
        self._approved = (self.DeclareDiscreteState(self._priors.reshape(-1))
                          if noise.Any() else None)
        self._estimate = self.DeclareDiscreteState(self._priors.reshape(-1))
        # Per trial [number of the model, the estimate that began it].
        self._epoch = self.DeclareDiscreteState(np.concatenate(
            [np.zeros((count, 1)), self._priors], axis=1).reshape(-1))
        # Per trial [identified total mass, momentum misfit, mismatch].
        self._status = self.DeclareDiscreteState(np.concatenate([
            [float(np.sum(prior[MASS::PER_BODY])), 0.0, 0.0] for prior in self._priors]))
        self.DeclareStateOutputPort("inertial_parameters", self._estimate)
        self.DeclareStateOutputPort("identification_log", self._status)
        epochs = np.arange(count) * (1 + size)
        self.DeclareVectorOutputPort(
            "model_epoch", count, lambda context, output: output.SetFromVector(
                context.get_discrete_state(self._epoch).get_value()[epochs]),
            prerequisites_of_calc={self.discrete_state_ticket(self._epoch)})
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._UpdateEstimate)
        self._ensemble = ModelErrorEnsemble(
            plants=plants, settings=settings, priors=self._priors, scales=self._scales,
            anchor=self._anchor, anchor_values=self._anchor_value, seeds=seeds,
            noise=noise, period=period)
        self._ensemble_information = (self.DeclareDiscreteState(
            size * size * self._ensemble.members) if self._ensemble.own_information
            else None)
        self._ensemble_bias = (self.DeclareDiscreteState(
            self._ensemble.InitialBias().reshape(-1)) if noise.Any() else None)
        n = c.num_joints
        self._model_error = self.DeclareDiscreteState(
            np.full(count * n * n, settings.nominal_tolerance))
        self.DeclareStateOutputPort("model_error", self._model_error)
        self.DeclarePeriodicDiscreteUpdateEvent(error_period, 0.0, self._UpdateModelError)

    def _UpdateEstimate(self, context, discrete_state):
        t, settings = context.get_time(), self._settings
        if t > self._WindowEnd():
            return              # the estimate is kept (settings.duration)
        count, size = len(self._priors), self.parameters.size
        base_pose, base_velocity, q, qdot = (
            port.Eval(context).reshape(count, -1) for port in
            (self._base_pose, self._base_velocity, self._q, self._qdot))
        information = context.get_discrete_state(self._information).get_value(
            ).reshape(count, -1).copy()
        self._trees.AddInformation(base_pose, base_velocity, q, qdot, information)
        discrete_state.get_mutable_vector(self._information).SetFromVector(
            information.reshape(-1))
        noise_information = self._AddNoiseInformation(context, discrete_state, t,
                                                      base_pose, q)
        if self._ensemble_information is not None:
            drawn = context.get_discrete_state(self._ensemble_information).get_value(
                ).reshape(self._ensemble.members, -1).copy()
            bias = None
            if self._ensemble_bias is not None:
                bias = context.get_discrete_state(self._ensemble_bias).get_value(
                    ).reshape(self._ensemble.members, -1).copy()
            self._ensemble.AddInformation(base_pose, base_velocity, q, qdot, drawn, bias)
            if bias is not None:
                discrete_state.get_mutable_vector(self._ensemble_bias).SetFromVector(
                    bias.reshape(-1))
            discrete_state.get_mutable_vector(self._ensemble_information).SetFromVector(
                drawn.reshape(-1))
        if t < settings.start:
            return
        estimates = context.get_discrete_state(self._estimate).get_value().reshape(
            count, -1).copy()
        epochs = context.get_discrete_state(self._epoch).get_value().reshape(
            count, -1).copy()
        status = context.get_discrete_state(self._status).get_value().reshape(
            count, -1).copy()
        if self._identified is None:
            candidates = self._Identify(information.reshape(count, size, size), None, t,
                                        status)
        else:
            # With noisy sensors the identified parameters are read only by the next
            # check (_UpdateModelError), so they are identified at the update before it
            # and at the window's last.
            if self._ChecksNext(t):
                discrete_state.get_mutable_vector(self._identified).SetFromVector(
                    self._Identify(information.reshape(count, size, size),
                                   noise_information, t, status).reshape(-1))
            candidates = context.get_discrete_state(self._approved).get_value().reshape(
                count, -1)
        M = self._trees.ReducedMassMatrices(candidates, q)
        usable = positive_definite(M) & np.all(candidates[:, MASS::PER_BODY] > 0, axis=1)
        estimates[usable] = candidates[usable]
        # A new epoch where M(q) moved by more than change_threshold in some entry,
        # relative to sqrt(M_ii M_jj), from the epoch's estimate's.
        diagonal = np.diagonal(M, axis1=1, axis2=2)
        with np.errstate(invalid="ignore"):
            change = np.abs(M - self._trees.ReducedMassMatrices(epochs[:, 1:], q)) / \
                np.sqrt(diagonal[:, :, None] * diagonal[:, None, :])
            changed = usable & (np.max(change, axis=(1, 2)) > settings.change_threshold)
        epochs[changed, 0] += 1
        epochs[changed, 1:] = candidates[changed]
        status[:, 0] = np.sum(estimates[:, MASS::PER_BODY], axis=1)
        discrete_state.get_mutable_vector(self._status).SetFromVector(status.reshape(-1))
        discrete_state.get_mutable_vector(self._estimate).SetFromVector(
            estimates.reshape(-1))
        discrete_state.get_mutable_vector(self._epoch).SetFromVector(epochs.reshape(-1))

    def _Identify(self, information: np.ndarray, noise_information: Optional[np.ndarray],
                  t: float, status: np.ndarray) -> np.ndarray:
        """The trials' identified parameters from their information (compensated for
        the noise's, if any) and the samples' momentum misfit and mismatch (``status``
        in place); the prior where a mismatch returns the LHS to it."""
        settings = self._settings
        if noise_information is not None:
            information = compensated_information(information, noise_information,
                                                  self._Readings(t))
        candidates = identify_parameters(information, self._priors, self._scales,
                                         settings.prior_weight, self._anchor,
                                         self._anchor_value)
        misfit = momentum_misfit(information, candidates)
        status[:, 1] = np.where(np.isfinite(misfit), misfit, status[:, 1])
        if settings.fit_tolerance > 0:
            status[:, 2] = np.maximum(status[:, 2], status[:, 1] > settings.fit_tolerance)
        if settings.on_mismatch == "nominal":
            candidates = np.where(status[:, 2:3] > 0.5, self._priors, candidates)
        return candidates

    def _WindowEnd(self) -> float:
        """When the estimate is kept (settings.start + settings.duration) [s]."""
        return self._settings.start + self._settings.duration

    def _ChecksNext(self, t: float) -> bool:
        """Whether the update at t [s] is the last before a check of E (every
        error_period) or the window's last: the next update is no earlier than either,
        at the instants Drake schedules them."""
        following = _next_sample(t, self._period)
        return (following > self._WindowEnd()
                or following >= _next_sample(t, self._error_period))

    def _AddNoiseInformation(self, context, discrete_state, t, base_pose, q
                             ) -> Optional[np.ndarray]:
        """Adds this reading's noise information (state in place); the trials' sums
        (trials, p, p), or None with noiseless sensors. The gyro's bias counts as noise
        of its variance, gyro_bias^2 + gyro_bias_walk^2 t."""
        if self._noise_information is None:
            return None
        count, size, noise = len(self._priors), self.parameters.size, self._noise
        sums = context.get_discrete_state(self._noise_information).get_value().reshape(
            count, -1).copy()
        self._trees.AddNoiseInformation(
            base_pose, q, self._base_velocity.size() // count, self._rate_columns,
            noise.base_rate ** 2 + noise.gyro_bias ** 2 + noise.gyro_bias_walk ** 2 * t,
            noise.joint_rate ** 2, sums)
        discrete_state.get_mutable_vector(self._noise_information).SetFromVector(
            sums.reshape(-1))
        return sums.reshape(count, size, size)

    def _Readings(self, t: float) -> int:
        """The samples the information holds after the update at t [s] (one per period
        from t = 0)."""
        return int(round(t / self._period)) + 1

    def _UpdateModelError(self, context, discrete_state):
        count, size = len(self._priors), self.parameters.size
        q = self._q.Eval(context).reshape(count, -1)
        state = (self._ensemble_information if self._ensemble_information is not None
                 else self._information)
        information = context.get_discrete_state(state).get_value().reshape(
            -1, size, size)
        if self._noise_information is None:
            estimates = context.get_discrete_state(self._estimate).get_value().reshape(
                count, -1)
            sd = self._ensemble.ErrorSd(information,
                                        self._trees.ReducedMassMatrices(estimates, q), q)
            discrete_state.get_mutable_vector(self._model_error).SetFromVector(
                sd.reshape(-1))
            return
        # Noisy sensors: the latest identified parameters' error; they are approved (the
        # estimate's candidates until the next check) where it is below the nominal's
        # stated tolerance (nominal_tolerance) in every entry, else the nominal is.
        identified = context.get_discrete_state(self._identified).get_value().reshape(
            count, -1)
        sd = self._ensemble.ErrorSd(
            information, self._trees.ReducedMassMatrices(identified, q), q,
            context.get_discrete_state(self._noise_information).get_value().reshape(
                count, size, size),
            self._Readings(min(context.get_time(), self._WindowEnd())))
        # Strictly below: where no draw is usable ErrorSd gives the tolerance itself.
        trusted = np.all(sd < self._settings.nominal_tolerance, axis=(1, 2))
        discrete_state.get_mutable_vector(self._approved).SetFromVector(np.where(
            trusted[:, None], identified, self._priors).reshape(-1))
        discrete_state.get_mutable_vector(self._model_error).SetFromVector(np.where(
            trusted[:, None, None], sd, self._settings.nominal_tolerance).reshape(-1))

    def _Anchor(self, settings, measured_masses, count):
        """Each trial's anchor (constraint vector, value); (None, None): the model's."""
        if settings.anchor == "model":
            return None, None
        layout = self.parameters
        base = [int(np.flatnonzero(self._trees.nodes == 0)[0])]
        c = mass_anchor(layout, None if settings.anchor == "total_mass" else base)
        if settings.anchor_mass > 0:
            values = np.full(count, settings.anchor_mass)
        else:
            which = 0 if settings.anchor == "total_mass" else 1
            values = np.array([masses[which] for masses in measured_masses]) * (
                1.0 + settings.anchor_error)
        return np.tile(c, (count, 1)), values


def _next_sample(t: float, period: float) -> float:
    """The first instant k period strictly after t [s], as Drake computes a periodic
    event's (offset 0)."""
    k = np.ceil(t / period)
    return k * period if k * period > t else (k + 1) * period
