"""LHS model-based controller: Slotine-Li sliding mode with a null-space potential
field (paper section "LHS Model-Based Control", SPEC section 4)."""
import numpy as np
from pydrake.systems.framework import LeafSystem

from dacph_drake.kernels.loop import lhs_control
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
    ``lhs_log`` = [s (n), alpha~, alpha_d, V = s^T M s / 2, U(q), lambda_min(M)];
    output ``reduced_model`` = [vec(M), vec(C')] at the same sample (row-major), for
    the port observer. The update is one compiled kernel (kernels.loop.lhs_control)."""


    def __init__(self, model: ReducedOrderModel, potential: BaseRepulsionPotential,
                 reference: OrientationReference, gains: LhsGains, period: float,
                 num_positions: int, fixed_chi: float,
                 excitation: Excitation = Excitation(amplitude=0.0)):
        super().__init__()
        n = model.num_joints
        self._n, self._nq = n, num_positions
        self._fixed_chi = fixed_chi
        # The kernel's constant arguments (kernels.loop.lhs_control).
        self._arguments = (
            *model.trigonometric_representation, *potential.kernel_arguments,
            reference.kernel_arguments,
            np.array([gains.Kd, gains.Lambda, gains.epsilon, gains.eta]),
            np.concatenate([[excitation.amplitude], 2 * np.pi * excitation.Frequencies(n)]))
        self._state = self.DeclareVectorInputPort("state", 2 * num_positions)
        self._chi = self.DeclareVectorInputPort("chi", 1)
        self._tau_index = self.DeclareDiscreteState(n)
        self._log_index = self.DeclareDiscreteState(LhsLog(n).size)
        self._model_index = self.DeclareDiscreteState(2 * n * n)
        self.DeclareStateOutputPort("tau_request", self._tau_index)
        self.DeclareStateOutputPort("lhs_log", self._log_index)
        self.DeclareStateOutputPort("reduced_model", self._model_index)
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._UpdateControl)
        self.DeclareInitializationDiscreteUpdateEvent(self._UpdateControl)

    def Control(self, t: float, x: np.ndarray, chi: float):
        """(tau_c^r, log vector) at time t and plant state x."""
        return self._Evaluate(t, x, chi)[:2]

    def _Evaluate(self, t, x, chi):
        tau, log, M, C = lhs_control(t, x, chi, *self._arguments)
        return tau, np.append(log, np.linalg.eigvalsh(M)[0]), M, C

    def _UpdateControl(self, context, discrete_state):
        chi = (self._chi.Eval(context)[0] if self._chi.HasValue(context)
               else self._fixed_chi)
        tau, log, M, C = self._Evaluate(context.get_time(), self._state.Eval(context), chi)
        discrete_state.get_mutable_vector(self._tau_index).SetFromVector(tau)
        discrete_state.get_mutable_vector(self._log_index).SetFromVector(log)
        discrete_state.get_mutable_vector(self._model_index).SetFromVector(
            np.concatenate([M.reshape(-1), C.reshape(-1)]))
