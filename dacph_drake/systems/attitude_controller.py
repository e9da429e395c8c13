"""LHS controller of a spatial arm: the sliding-mode law of LhsController with the 3D
end-effector attitude as its task (attitude.py) and the damping and the robust
term's boundary layer scaled to the inertia (scenario.AttitudeGains)."""
import numpy as np
from pydrake.math import RotationMatrix
from pydrake.systems.framework import LeafSystem

from dacph_drake.kernels.attitude import attitude_update, turned
from dacph_drake.dynamics.floating_model import FloatingBaseModel
from dacph_drake.log_layout import AttitudeLog
from dacph_drake.dynamics.plant import END_EFFECTOR
from dacph_drake.scenario import AttitudeGains, AttitudeReference, Excitation
from dacph_drake.robots.clearance_potential import BaseClearancePotential

XI_DOT_STEP = 1e-5              # [s] of xi's central difference along the motion
# [m] beyond the potential's margin, the nearest link keeps xi = -eta grad U zero at
# q +- h qdot (it would move faster than FAR / XI_DOT_STEP = 1000 m/s to reach it).
FAR = 0.01


class AttitudeController(LeafSystem):
    """Every ``period`` seconds, from the measured state (inputs ``base_pose`` =
    (qw, qx, qy, qz, x, y, z), ``base_velocity`` = (omega_W, v_W), ``q``, ``qdot``):

        e   = attitude_error(R_WE, R_d(t)),   D = angular rows of the end effector's GJM
        nu  = D^+ (omega_d - Lambda e) + (I - D^+ D) xi,   xi = -eta grad U(q)
        s   = qdot - nu
        tau = M nu_dot + C' nu - damping_rate M s - chi tanh(diag(M) s / phi)
              + tau_pe(t),   phi = epsilon + chi / boundary_rate

    so that V = s^T M s / 2 has dV/dt = -2 damping_rate V - chi s^T tanh(...) + s^T
    (e_tau + tau_pe) (Mdot - 2C' skew), with chi from input ``chi`` (the RHS loop's
    bound on ||e_tau|| in DAC, a constant in the baseline) and tau_pe the
    learner's excitation (``excitation``, scenario.Excitation). nu_dot
    is nu's exact rate along the current motion (joints at qdot, the base turning
    at omega_b, the reference at t: kernels.attitude.task_rates), from dD = d(R_WB
    D_B)/dt with dA/dq of the same evaluation; xi's rate is the central difference
    along the motion (q +- h qdot, the base turned by +- h omega_b; h =
    XI_DOT_STEP), zero unless a link is within FAR beyond the potential's margin
    (xi = 0 at all three points then). M, dM, C' and the Jacobians come from one
    compiled evaluation of the model inside the update's one compiled call
    (kernels.attitude.attitude_update). U is the link-base clearance potential (``potential``: robots.clearance_potential.
    BaseClearancePotential, or None).
    Output ``tau_request`` is held between updates; ``attitude_log``
    (log_layout.AttitudeLog) = [e (3), |e|, ||s||, V, R_d(t) as a quaternion] of the
    last update, which a replay reads, with the smallest link-base distance [m] at
    the current state (inf without a potential; the potential itself queries only
    the pairs within its margin + FAR);
    ``reduced_model`` = [vec(M), vec(C')] of the same sample (row-major), for the
    port observer. With ``identify``, input ``inertial_parameters`` (an
    InertialIdentifier's estimate) sets the model's inertias before every update
    (FloatingBaseModel.SetInertialParameters): M, C', the GJM and the clearance
    potential's gradient are then the identified bodies'."""

    def __init__(self, *, model: FloatingBaseModel, reference: AttitudeReference,
                 gains: AttitudeGains, period: float, q0,
                 potential: BaseClearancePotential = None, eta: float = 0.0,
                 excitation: Excitation = Excitation(amplitude=0.0),
                 identify: bool = False):
        super().__init__()
        n = model.num_joints
        self._model, self._reference, self._gains = model, reference, gains
        self._potential, self._eta = potential, eta
        self._excitation = np.concatenate([[excitation.amplitude],
                                           2 * np.pi * excitation.Frequencies(n)])
        self._gain_arguments = np.array([gains.Lambda, gains.task_damping,
                                         gains.damping_rate, gains.epsilon,
                                         gains.boundary_rate], float)
        end_effector = model.plant.GetFrameByName(END_EFFECTOR)
        node, X_CE = model.FrameNode(end_effector)
        self._end_effector_node = (node, np.ascontiguousarray(X_CE[:3, :3]))
        self._R_d0 = reference.Start(RotationMatrix(model.FramePose(
            end_effector, model.Evaluate(np.asarray(q0, float), derivatives=False))))
        axis = np.asarray(reference.axis, float)
        self._reference_arguments = (self._R_d0.matrix(), axis / np.linalg.norm(axis),
                                     float(reference.amplitude),
                                     2 * np.pi / reference.period)
        self._base_pose = self.DeclareVectorInputPort("base_pose", 7)
        self._base_velocity = self.DeclareVectorInputPort("base_velocity", 6)
        self._q = self.DeclareVectorInputPort("q", n)
        self._qdot = self.DeclareVectorInputPort("qdot", n)
        self._chi = self.DeclareVectorInputPort("chi", 1)
        self._parameters = (self.DeclareVectorInputPort(
            "inertial_parameters", model.parameters.size) if identify else None)
        self._tau_index = self.DeclareDiscreteState(n)
        self._log_index = self.DeclareDiscreteState(AttitudeLog().size)
        self._model_index = self.DeclareDiscreteState(2 * n * n)
        self.DeclareStateOutputPort("tau_request", self._tau_index)
        self.DeclareVectorOutputPort(
            "attitude_log", AttitudeLog().size, self._CalcAttitudeLog,
            prerequisites_of_calc={self.discrete_state_ticket(self._log_index),
                                   self._q.ticket(), self._base_pose.ticket()})
        self.DeclareStateOutputPort("reduced_model", self._model_index)
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._UpdateControl)
        self.DeclareInitializationDiscreteUpdateEvent(self._UpdateControl)

    def DesiredAttitude(self, t: float):
        """(R_d(t), omega_d(t))."""
        return self._reference.At(self._R_d0, t)

    def _Secondary(self, q, base_pose):
        """(xi = -eta grad U, the nearest link-base distance if within the
        potential's margin + FAR, else inf) at q and the base pose."""
        if self._potential is None:
            return np.zeros(self._model.num_joints), np.inf
        potential = self._potential.Evaluate(q, base_pose,
                                             query_distance=self._potential.margin + FAR)
        return -self._eta * potential.gradient, potential.min_distance

    def _CalcAttitudeLog(self, context, output):
        """The update's log with the smallest link-base distance at the current
        state (the full query, at the loggers' rate rather than every update)."""
        log = context.get_discrete_state(self._log_index).CopyToVector()
        if self._potential is not None:
            log[AttitudeLog().clearance] = self._potential.Evaluate(
                self._q.Eval(context), self._base_pose.Eval(context)).min_distance
        output.SetFromVector(log)

    def _UpdateControl(self, context, discrete_state):
        if self._parameters is not None and self._parameters.HasValue(context):
            self._model.SetInertialParameters(self._parameters.Eval(context))
        t = context.get_time()
        base_pose = self._base_pose.Eval(context)
        omega_base = self._base_velocity.Eval(context)[:3]
        q, qdot = self._q.Eval(context), self._qdot.Eval(context)
        xi, clearance = self._Secondary(q, base_pose)
        xi_dot = np.zeros_like(xi)
        if self._potential is not None and clearance <= self._potential.margin + FAR:
            h, sides = XI_DOT_STEP, []
            for sign in (1.0, -1.0):
                q_h = q + sign * h * qdot
                pose_h = np.concatenate([turned(base_pose[:4], sign * h * omega_base),
                                         base_pose[4:]])
                sides.append(self._Secondary(q_h, pose_h)[0])
            xi_dot = (sides[0] - sides[1]) / (2 * h)
        tau, M, C, log, desired = attitude_update(
            self._model.kernel_tree, q, qdot, base_pose[:4], omega_base, t,
            self._reference_arguments, self._end_effector_node, xi, xi_dot,
            self._gain_arguments, self._chi.Eval(context)[0], self._excitation)
        discrete_state.set_value(self._tau_index, tau)
        discrete_state.set_value(self._model_index,
                                 np.concatenate([M.reshape(-1), C.reshape(-1)]))
        discrete_state.set_value(self._log_index, np.concatenate([log, [np.inf],
                                                                  desired]))
