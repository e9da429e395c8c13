"""Identification of the bodies' inertial parameters from momentum conservation (a
project extension for the LHS's "parametric uncertainties (e.g., misidentified mass
or inertia)", docs/equations.md E8-E9)."""
from typing import Optional, Sequence

import numpy as np
from pydrake.multibody.plant import MultibodyPlant
from pydrake.systems.framework import LeafSystem

from dacph_drake.dynamics.inertial_parameters import (MASS, PER_BODY, InertialParameters,
                                             identify_parameters, prior_scales)
from dacph_drake.dynamics.kinematic_tree import KinematicTree
from dacph_drake.dynamics.plant import ArmCoordinates
from dacph_drake.kernels import spatial
from dacph_drake.scenario import InertiaIdentification


class InertialIdentifier(LeafSystem):
    """Every ``period`` h, at the measured state (inputs ``base_pose``,
    ``base_velocity``, ``q``, ``qdot``: the base's pose and twist as a satellite's
    navigation and gyros give them, and the joints'):

        A <- A + Y(x)^T Y(x),      Y(x) pi = [L; P] (the momentum, linear in pi,
                                               inertial_parameters.MomentumRegressor)
        pi_hat = argmin pi^T A pi + r (pi - pi0)^T S^-2 (pi - pi0),
                 subject to pi0^T S^-2 pi = pi0^T S^-2 pi0

    (inertial_parameters.identify_parameters, r from ``settings.prior_weight``). The
    robot starts at rest, so L = P = 0 along the whole motion and Y(x) pi~ = 0 for
    the true parameters pi~: the samples determine the parameters up to one common
    factor, which the prior pi0 (the controller's model: ``prior``, by default
    ``plant``'s own inertias) fixes, and the directions the motion has not informed
    stay at the prior. No actuator model enters.

    Output ``inertial_parameters`` is pi0 until ``settings.start`` and pi_hat after
    it, every period until ``settings.duration`` has passed (then it is kept: the
    bodies' inertias do not change, while the directions the data hardly inform
    keep refining); an estimate with a mass <= 0, or whose mass matrix at the
    sample is not positive definite, is not used. Output ``model_epoch`` counts the
    estimates that changed the reduced mass matrix M(q) at the sample by more than
    ``settings.change_threshold`` in some entry (relative to sqrt(M_ii M_jj), so that
    a light wrist's change counts as much as a heavy shoulder's) since the last such
    one: the learner treats a new epoch as a change of the port relation it observes
    (Learner.model_change), while the refinements in between reach the LHS without
    disturbing it.

    What the controller does with it: the LHS controller's M, C' and task Jacobian D
    are those of pi_hat (its input of the same name), so the port observer's tau_obs
    and the learner's samples are too.

    For a batch (``plants``: each trial's controller plant, ``priors`` each trial's
    pi0 or None; one: a single run) every port carries the trials' signals
    stacked and each trial is identified alone."""

    def __init__(self, *, plants: Sequence[MultibodyPlant],
                 settings: InertiaIdentification, period: float,
                 priors: Optional[Sequence[np.ndarray]] = None):
        super().__init__()
        priors = [None] * len(plants) if priors is None else priors
        self._trials = [_TrialIdentification(plant, prior)
                        for plant, prior in zip(plants, priors, strict=True)]
        self.parameters = self._trials[0].parameters
        self._settings = settings
        count, size = len(self._trials), self.parameters.size
        c = self._trials[0].coordinates
        self._base_pose = self.DeclareVectorInputPort("base_pose", len(c.base_q) * count)
        self._base_velocity = self.DeclareVectorInputPort("base_velocity",
                                                          len(c.base_v) * count)
        self._q = self.DeclareVectorInputPort("q", c.num_joints * count)
        self._qdot = self.DeclareVectorInputPort("qdot", c.num_joints * count)
        self._information = self.DeclareDiscreteState(size * size * count)
        priors = np.concatenate([trial.prior for trial in self._trials])
        self._estimate = self.DeclareDiscreteState(priors)
        # Per trial [number of the model, the estimate that began it].
        self._epoch = self.DeclareDiscreteState(np.concatenate([
            np.concatenate([[0.0], trial.prior]) for trial in self._trials]))
        self.DeclareStateOutputPort("inertial_parameters", self._estimate)
        epochs = np.arange(count) * (1 + size)
        self.DeclareVectorOutputPort(
            "model_epoch", count, lambda context, output: output.SetFromVector(
                context.get_discrete_state(self._epoch).get_value()[epochs]),
            prerequisites_of_calc={self.discrete_state_ticket(self._epoch)})
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._UpdateEstimate)

    def _UpdateEstimate(self, context, discrete_state):
        if context.get_time() > self._settings.start + self._settings.duration:
            return              # the estimate is kept (settings.duration)
        count = len(self._trials)
        inputs = [port.Eval(context).reshape(count, -1) for port in
                  (self._base_pose, self._base_velocity, self._q, self._qdot)]
        information = context.get_discrete_state(self._information).get_value(
            ).reshape(count, -1).copy()
        estimates = context.get_discrete_state(self._estimate).get_value().reshape(
            count, -1).copy()
        epochs = context.get_discrete_state(self._epoch).get_value().reshape(
            count, -1).copy()
        for i, trial in enumerate(self._trials):
            base_pose, base_velocity, q, qdot = (x[i] for x in inputs)
            information[i] += trial.Information(base_pose, base_velocity, q, qdot)
            if context.get_time() >= self._settings.start:
                estimate, M = trial.Estimate(information[i], q, self._settings)
                if estimate is not None:
                    estimates[i] = estimate
                    if trial.Changed(M, epochs[i][1:], q,
                                     self._settings.change_threshold):
                        epochs[i] = np.concatenate([[epochs[i][0] + 1], estimate])
        discrete_state.get_mutable_vector(self._information).SetFromVector(
            information.reshape(-1))
        if context.get_time() < self._settings.start:
            return
        discrete_state.get_mutable_vector(self._estimate).SetFromVector(
            estimates.reshape(-1))
        discrete_state.get_mutable_vector(self._epoch).SetFromVector(epochs.reshape(-1))


class _TrialIdentification:
    """One trial's part of an InertialIdentifier: its controller's plant (a context
    of its own for the momentum regressor), the prior pi0 (the plant's inertias
    unless given) and the compiled reduced model of any pi."""

    def __init__(self, plant: MultibodyPlant, prior: Optional[np.ndarray]):
        self._plant = plant
        self._context = plant.CreateDefaultContext()
        self.parameters = InertialParameters(plant)
        self.coordinates = ArmCoordinates.FromPlant(plant)
        self.prior = (self.parameters.FromContext(self._context) if prior is None
                      else np.asarray(prior, float).copy())
        self._scales = prior_scales(self.parameters, self.prior)
        self._tree = KinematicTree.FromPlant(plant)
        self._node_inertias = self.parameters.NodeInertias(self._tree, self._context)

    def Information(self, base_pose, base_velocity, q, qdot) -> np.ndarray:
        """vec(Y^T Y) of the momentum regressor at the measured state."""
        c = self.coordinates
        velocities = np.zeros(self._plant.num_velocities())
        velocities[c.base_v] = base_velocity
        velocities[c.joint_v] = qdot
        self._plant.SetPositionsAndVelocities(self._context, np.concatenate([
            c.Positions(q, base_pose), velocities]))
        Y = self.parameters.MomentumRegressor(self._context)
        return (Y.T @ Y).reshape(-1)

    def Estimate(self, information: np.ndarray, q: np.ndarray,
                 settings: InertiaIdentification):
        """(pi_hat from the information, its M(q)), or (None, None) where it has no
        mass matrix (a mass <= 0, or M(q) not positive definite)."""
        size = self.parameters.size
        estimate = identify_parameters(information.reshape(size, size), self.prior,
                                       self._scales, settings.prior_weight)
        M = self.ReducedMassMatrix(estimate, q)
        if not (np.all(estimate[MASS::PER_BODY] > 0) and M is not None
                and np.linalg.eigvalsh(M)[0] > 0):
            return None, None
        return estimate, M

    def Changed(self, M, epoch_estimate, q, threshold: float) -> bool:
        """Whether M (of an estimate, at q) differs from M(q) of the epoch's
        estimate by more than ``threshold`` in some entry, relative to
        sqrt(M_ii M_jj)."""
        change = (np.abs(M - self.ReducedMassMatrix(epoch_estimate, q))
                  / np.sqrt(np.outer(np.diag(M), np.diag(M))))
        return np.max(change) > threshold

    def ReducedMassMatrix(self, pi: np.ndarray, q: np.ndarray):
        """M(q) = H_mm - H_bm^T H_bb^-1 H_bm with the bodies' inertias pi (the
        compiled kernel, kernels.spatial.reduced_model), or None where H_bb is not
        positive definite (its Cholesky factor then is not finite): with M
        positive definite too, the full mass matrix H is."""
        M = spatial.reduced_model(*self._tree.KernelArrays(), *self._node_inertias(pi),
                                  np.asarray(q, float), False)[0]
        return M if np.all(np.isfinite(M)) else None
