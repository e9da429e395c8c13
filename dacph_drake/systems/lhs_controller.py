"""LHS model-based controller: Slotine-Li sliding mode with a null-space potential
field (paper section "LHS Model-Based Control", docs/equations.md E20-E25, E41)."""
from dataclasses import dataclass
from typing import Optional, Sequence, Tuple

import numpy as np
from pydrake.systems.framework import LeafSystem

from dacph_drake.dynamics.inertial_parameters import InertialParameters
from dacph_drake.kernels.loop import lhs_samples, pack_lhs, stack_packs
from dacph_drake.log_layout import LhsLog
from dacph_drake.dynamics.base_repulsion import BaseRepulsionPotential
from dacph_drake.dynamics.reduced_model import ReducedOrderModel
from dacph_drake.dynamics.reference import OrientationReference
from dacph_drake.scenario import Excitation, LhsGains


def boundary_layer_per_chi(gains: LhsGains, lambda_min_M: float) -> float:
    """d phi / d chi = 1 / (boundary_rate inf_q lambda_min(M)) (0 with boundary_rate 0).

    Args:
        gains: The sliding-mode gains (their boundary_rate [1/s]).
        lambda_min_M: inf_q lambda_min(M) of the controller's model."""
    return 1.0 / (gains.boundary_rate * lambda_min_M) if gains.boundary_rate > 0 else 0.0


@dataclass
class LhsTrial:
    """One trial's part of an LhsController.

    Attributes:
        model: The controller's model of its robot.
        potential: The base-repulsion potential of that robot.
        reference: Its reference (theta0(0) from its q0).
        lambda_min_M: inf_q lambda_min(M) of its model (the boundary layer's scale)."""
    model: ReducedOrderModel
    potential: BaseRepulsionPotential
    reference: OrientationReference
    lambda_min_M: float = 1.0


class LhsController(LeafSystem):
    """Every ``period`` seconds, for every trial of a batch, from the measured state (inputs
    ``base_pose`` = (x, y, theta0), ``q``, ``qdot``; alpha = theta0 + q_1 + ... + q_n):

        alpha~ = alpha - alpha_d,   D+ = D^T / (D D^T),   P = I - D+ D
        nu     = D+ (alpha_d_dot - Lambda alpha~) + P xi,  xi = -eta grad U(q)
        s      = qdot - nu
        tau_c^r = M nu_dot + C' nu - K_d s - chi tanh(s / phi),
        phi    = epsilon + chi / (boundary_rate inf_q lambda_min(M))

    with nu_dot exact (dD/dq and Hess U qdot, no numerical differentiation). chi comes
    from input ``chi`` (the RHS loop's bound on ||e_tau|| in DAC, a constant in the
    baseline); phi follows chi (Slotine and Li's balance condition) so the robust term
    adds at most ``gains.boundary_rate`` [1/s] to any joint's rate. Outputs
    ``tau_request`` (held), ``lhs_log`` = [s (n), alpha~, alpha_d, V = s^T M s / 2, U(q),
    lambda_min(M)] and ``reduced_model`` = [vec(M), vec(C')] (row-major). With
    ``identify``, input ``inertial_parameters`` replaces the models' inertias. Ports
    stack the trials; one compiled kernel updates all (kernels.loop.lhs_samples).

    Args:
        trials: Each trial's LhsTrial.
        gains: The sliding-mode gains (task.gains).
        period: The update period [s] (periods.lhs).
        excitation: The learner's excitation tau_pe(t) (DAC loops; amplitude 0: off).
        identify: Declare input ``inertial_parameters`` (an InertialIdentifier's)."""

    def __init__(self, *, trials: Sequence[LhsTrial], gains: LhsGains, period: float,
                 excitation: Excitation = Excitation(amplitude=0.0),
                 identify: bool = False):
        super().__init__()
        n = trials[0].model.num_joints
        self._n, self._trials = n, len(trials)
        excitation_arguments = np.concatenate([excitation.Amplitudes(n),
                                               2 * np.pi * excitation.Frequencies(n)])
        # The kernel's constant arguments (kernels.loop.lhs_sample), per trial.
        self._coefficients = np.array([trial.model.trigonometric_representation[0]
                                       for trial in trials])
        self._packs, self._offsets = stack_packs([pack_lhs(
            trial.model.trigonometric_representation[1],
            *trial.potential.kernel_arguments, trial.reference.kernel_arguments,
            np.array([gains.Kd, gains.Lambda, gains.epsilon, gains.eta,
                      boundary_layer_per_chi(gains, trial.lambda_min_M)]),
            excitation_arguments) for trial in trials])
        N = self._trials
        self._base_pose = self.DeclareVectorInputPort("base_pose", 3 * N)
        self._q = self.DeclareVectorInputPort("q", n * N)
        self._qdot = self.DeclareVectorInputPort("qdot", n * N)
        self._chi = self.DeclareVectorInputPort("chi", N)
        self._parameters = None
        if identify:
            layouts = [InertialParameters(trial.model.plant) for trial in trials]
            self._parameters = self.DeclareVectorInputPort(
                "inertial_parameters", sum(layout.size for layout in layouts))
            self._coefficient_bases = np.array([trial.model.CoefficientBasis(layout)
                                                for trial, layout in zip(trials, layouts)])
            self._identified_key, self._identified = None, None
        self._tau_index = self.DeclareDiscreteState(n * N)
        self._log_index = self.DeclareDiscreteState((n + 4) * N)   # lhs_log but lambda_min
        self._model_index = self.DeclareDiscreteState(2 * n * n * N)
        self.DeclareStateOutputPort("tau_request", self._tau_index)
        self.DeclareVectorOutputPort(
            "lhs_log", LhsLog(n).size * N, self._CalcLog,
            prerequisites_of_calc={self.discrete_state_ticket(self._log_index),
                                   self.discrete_state_ticket(self._model_index)})
        self.DeclareStateOutputPort("reduced_model", self._model_index)
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._UpdateControl)
        self.DeclareInitializationDiscreteUpdateEvent(self._UpdateControl)

    def Control(self, t: float, theta0: float, q: np.ndarray, qdot: np.ndarray,
                chi: float, trial: int = 0,
                inertial_parameters: Optional[np.ndarray] = None
                ) -> Tuple[np.ndarray, np.ndarray]:
        """(tau_c^r [N m] (n), lhs_log (log_layout.LhsLog)) of one trial at one state.

        Args:
            t: The time [s].
            theta0: The base angle [rad].
            q: The joint angles [rad] (n).
            qdot: The joint rates [rad/s] (n).
            chi: The RHS loop's bound chi [N m].
            trial: The trial's index in the batch.
            inertial_parameters: The model's inertias (built with ``identify``; None:
                the nominal model's)."""
        coefficients = self._coefficients[trial:trial + 1]
        if inertial_parameters is not None:
            coefficients = np.einsum("p,per->er", inertial_parameters,
                                     self._coefficient_bases[trial])[None]
        tau, log, model = lhs_samples(
            t, np.array([theta0]), q, qdot, np.array([chi]), coefficients,
            self._packs[self._offsets[trial]:self._offsets[trial + 1]],
            np.array([0, self._offsets[trial + 1] - self._offsets[trial]]))
        return tau, self._Log(log, model)

    def _Log(self, logs, models):
        """The trials' lhs_log from their kernel logs and [vec(M), vec(C')]."""
        n = self._n
        M = models.reshape(-1, 2, n, n)[:, 0]
        return np.concatenate([logs.reshape(-1, n + 4),
                               np.linalg.eigvalsh(M)[:, :1]], axis=1).reshape(-1)

    def _UpdateControl(self, context, discrete_state):
        tau, logs, models = lhs_samples(
            context.get_time(), self._base_pose.Eval(context)[2::3],
            self._q.Eval(context), self._qdot.Eval(context), self._chi.Eval(context),
            self._Coefficients(context), self._packs, self._offsets)
        discrete_state.get_mutable_vector(self._tau_index).SetFromVector(tau)
        discrete_state.get_mutable_vector(self._log_index).SetFromVector(logs)
        discrete_state.get_mutable_vector(self._model_index).SetFromVector(models)

    def _Coefficients(self, context) -> np.ndarray:
        """The trigonometric coefficients: of ``inertial_parameters`` if connected."""
        if self._parameters is None or not self._parameters.HasValue(context):
            return self._coefficients
        pi = self._parameters.Eval(context)
        key = pi.tobytes()
        if key != self._identified_key:
            self._identified_key = key
            self._identified = np.einsum("tp,tper->ter", pi.reshape(self._trials, -1),
                                         self._coefficient_bases)
        return self._identified

    def _CalcLog(self, context, output):
        output.SetFromVector(self._Log(
            context.get_discrete_state(self._log_index).get_value(),
            context.get_discrete_state(self._model_index).get_value()))
