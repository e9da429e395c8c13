"""LHS model-based controller: Slotine-Li sliding mode with a null-space potential
field (paper section "LHS Model-Based Control", SPEC section 4)."""
import numpy as np
from pydrake.systems.framework import LeafSystem

from dacph_drake.log_layout import LhsLog
from dacph_drake.potential import BaseRepulsionPotential
from dacph_drake.reduced_model import ReducedOrderModel
from dacph_drake.reference import OrientationReference
from dacph_drake.scenario import Excitation, LhsGains


class LhsController(LeafSystem):
    """Every ``period`` seconds, from the measured state (q0, q, qdot):

        alpha~ = alpha - alpha_d,   D+ = D^T / (D D^T),   P = I - D+ D
        nu     = D+ (alpha_d_dot - Lambda alpha~) + P xi,  xi = -eta grad U(q)
        s      = qdot - nu
        tau_c^r = M nu_dot + C' nu - K_d s - chi tanh(s / epsilon)

    with nu_dot exact: it uses dD/dq from the reduced model and Hess U qdot from the
    potential (no numerical differentiation). chi comes from input ``chi`` (the RHS
    loop's bound on ||e_tau||) or is the fixed ``chi`` given here when that input is
    not connected. Output ``tau_request`` is held between updates; output
    ``lhs_log`` = [s (n), alpha~, alpha_d, V = s^T M s / 2, U(q), lambda_min(M)]."""


    def __init__(self, model: ReducedOrderModel, potential: BaseRepulsionPotential,
                 reference: OrientationReference, gains: LhsGains, period: float,
                 num_positions: int, fixed_chi: float,
                 excitation: Excitation = Excitation(amplitude=0.0)):
        super().__init__()
        n = model.num_joints
        self._n, self._nq = n, num_positions
        self._model, self._potential, self._reference = model, potential, reference
        self._Kd, self._Lambda = gains.Kd, gains.Lambda
        self._epsilon, self._eta = gains.epsilon, gains.eta
        self._fixed_chi = fixed_chi
        self._excitation_amplitude = excitation.amplitude
        self._excitation_omega = 2 * np.pi * excitation.Frequencies(n)
        self._state = self.DeclareVectorInputPort("state", 2 * num_positions)
        self._chi = self.DeclareVectorInputPort("chi", 1)
        self._tau_index = self.DeclareDiscreteState(n)
        self._log_index = self.DeclareDiscreteState(LhsLog(n).size)
        self.DeclareStateOutputPort("tau_request", self._tau_index)
        self.DeclareStateOutputPort("lhs_log", self._log_index)
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._UpdateControl)
        self.DeclareInitializationDiscreteUpdateEvent(self._UpdateControl)

    def Control(self, t: float, x: np.ndarray, chi: float):
        """(tau_c^r, log vector) at time t and plant state x."""
        nq = self._nq
        q_full, qdot = x[:nq], x[nq + 3:]
        q = q_full[3:]
        r = self._model.Evaluate(q, qdot)
        alpha = q_full[2] + np.sum(q)
        alpha_d, alpha_d_dot, alpha_d_ddot = self._reference(t)
        alpha_error = alpha - alpha_d
        alpha_error_dot = r.D @ qdot - alpha_d_dot
        D, D_dot = r.D, qdot @ r.dD
        DDt = D @ D
        D_pinv = D / DDt
        D_pinv_dot = D_dot / DDt - D * (2 * (D @ D_dot) / DDt**2)
        P = np.eye(self._n) - np.outer(D_pinv, D)
        P_dot = -(np.outer(D_pinv_dot, D) + np.outer(D_pinv, D_dot))
        U, grad_U, grad_U_dot = self._potential.Evaluate(q, qdot)
        xi, xi_dot = -self._eta * grad_U, -self._eta * grad_U_dot
        task = alpha_d_dot - self._Lambda * alpha_error
        nu = D_pinv * task + P @ xi
        nu_dot = (D_pinv_dot * task + D_pinv * (alpha_d_ddot - self._Lambda * alpha_error_dot)
                  + P_dot @ xi + P @ xi_dot)
        s = qdot - nu
        tau = r.M @ nu_dot + r.C @ nu - self._Kd * s - chi * np.tanh(s / self._epsilon)
        if self._excitation_amplitude > 0:
            tau = tau + self._excitation_amplitude * np.sin(self._excitation_omega * t)
        log = np.concatenate([s, [alpha_error, alpha_d, 0.5 * s @ r.M @ s, U,
                                  np.linalg.eigvalsh(r.M)[0]]])
        return tau, log

    def _UpdateControl(self, context, discrete_state):
        chi = (self._chi.Eval(context)[0] if self._chi.HasValue(context)
               else self._fixed_chi)
        tau, log = self.Control(context.get_time(), self._state.Eval(context), chi)
        discrete_state.get_mutable_vector(self._tau_index).SetFromVector(tau)
        discrete_state.get_mutable_vector(self._log_index).SetFromVector(log)
