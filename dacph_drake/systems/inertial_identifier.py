"""Identification of the bodies' inertial parameters from momentum conservation (a
project extension for the LHS's "parametric uncertainties (e.g., misidentified mass
or inertia)", docs/equations.md E8-E9)."""
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
    and the learner's samples are too."""

    def __init__(self, *, plant: MultibodyPlant, settings: InertiaIdentification,
                 period: float, prior: np.ndarray = None):
        super().__init__()
        self._plant = plant
        self._context = plant.CreateDefaultContext()
        self.parameters = InertialParameters(plant)
        self._coordinates = ArmCoordinates.FromPlant(plant)
        self._settings = settings
        self.prior = (self.parameters.FromContext(self._context) if prior is None
                      else np.asarray(prior, float).copy())
        self._scales = prior_scales(self.parameters, self.prior)
        self._tree = KinematicTree.FromPlant(plant)
        self._node_inertias = self.parameters.NodeInertias(self._tree, self._context)
        size = self.parameters.size
        c = self._coordinates
        self._base_pose = self.DeclareVectorInputPort("base_pose", len(c.base_q))
        self._base_velocity = self.DeclareVectorInputPort("base_velocity", len(c.base_v))
        self._q = self.DeclareVectorInputPort("q", c.num_joints)
        self._qdot = self.DeclareVectorInputPort("qdot", c.num_joints)
        self._information = self.DeclareDiscreteState(size * size)
        self._estimate = self.DeclareDiscreteState(self.prior)
        # [number of the model, the estimate that began it].
        self._epoch = self.DeclareDiscreteState(np.concatenate([[0.0], self.prior]))
        self.DeclareStateOutputPort("inertial_parameters", self._estimate)
        self.DeclareVectorOutputPort(
            "model_epoch", 1, lambda context, output: output.SetAtIndex(
                0, context.get_discrete_state(self._epoch).GetAtIndex(0)),
            prerequisites_of_calc={self.discrete_state_ticket(self._epoch)})
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._UpdateEstimate)

    def _UpdateEstimate(self, context, discrete_state):
        if context.get_time() > self._settings.start + self._settings.duration:
            return              # the estimate is kept (settings.duration)
        c, size = self._coordinates, self.parameters.size
        velocities = np.zeros(self._plant.num_velocities())
        velocities[c.base_v] = self._base_velocity.Eval(context)
        velocities[c.joint_v] = self._qdot.Eval(context)
        q = self._q.Eval(context)
        self._plant.SetPositionsAndVelocities(self._context, np.concatenate([
            c.Positions(q, self._base_pose.Eval(context)), velocities]))
        Y = self.parameters.MomentumRegressor(self._context)
        information = (context.get_discrete_state(self._information).get_value()
                       + (Y.T @ Y).reshape(-1))
        discrete_state.get_mutable_vector(self._information).SetFromVector(information)
        if context.get_time() < self._settings.start:
            return
        estimate = identify_parameters(information.reshape(size, size), self.prior,
                                       self._scales, self._settings.prior_weight)
        M = self._ReducedMassMatrix(estimate, q)
        if not (np.all(estimate[MASS::PER_BODY] > 0) and M is not None
                and np.linalg.eigvalsh(M)[0] > 0):
            return              # no mass matrix: keep the previous estimate
        discrete_state.get_mutable_vector(self._estimate).SetFromVector(estimate)
        epoch = context.get_discrete_state(self._epoch).get_value()
        change = (np.abs(M - self._ReducedMassMatrix(epoch[1:], q))
                  / np.sqrt(np.outer(np.diag(M), np.diag(M))))
        if np.max(change) > self._settings.change_threshold:
            discrete_state.get_mutable_vector(self._epoch).SetFromVector(
                np.concatenate([[epoch[0] + 1], estimate]))

    def _ReducedMassMatrix(self, pi: np.ndarray, q: np.ndarray):
        """M(q) = H_mm - H_bm^T H_bb^-1 H_bm with the bodies' inertias pi (the
        compiled kernel, kernels.spatial.reduced_model), or None where H_bb is not
        positive definite (its Cholesky factor then is not finite): with M
        positive definite too, the full mass matrix H is."""
        M = spatial.reduced_model(*self._tree.KernelArrays(), *self._node_inertias(pi),
                                  np.asarray(q, float), False)[0]
        return M if np.all(np.isfinite(M)) else None
