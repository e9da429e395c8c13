"""LHS controller of a spatial arm: the sliding-mode law of LhsController with the 3D
end-effector attitude as its task (attitude.py) and the damping and the robust
term's boundary layer scaled to the inertia (scenario.AttitudeGains)."""
import numpy as np
from pydrake.common.eigen_geometry import AngleAxis, Quaternion
from pydrake.math import RotationMatrix
from pydrake.systems.framework import LeafSystem

from dacph_drake.tasks.attitude import attitude_error, reference_rates
from dacph_drake.dynamics.floating_model import FloatingBaseModel
from dacph_drake.log_layout import AttitudeLog
from dacph_drake.dynamics.plant import END_EFFECTOR
from dacph_drake.scenario import AttitudeGains, AttitudeReference, Excitation
from dacph_drake.robots.clearance_potential import BaseClearancePotential

NU_DOT_STEP = 1e-5              # [s] of the central difference along the motion


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
    is the central difference of nu along the current motion (q +- h qdot, the base
    turned by +- h omega_b, t +- h; h = NU_DOT_STEP). U is the link-base clearance
    potential (``potential``: robots.clearance_potential.BaseClearancePotential, or None).
    Output ``tau_request`` is held between updates; ``attitude_log``
    (log_layout.AttitudeLog) = [e (3), |e|, ||s||, V, smallest link-base distance [m]
    (inf without a potential), R_d(t) as a quaternion], which a replay reads;
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
        self._excitation_amplitude = excitation.amplitude
        self._excitation_omega = 2 * np.pi * excitation.Frequencies(n)
        self._context = model.plant.CreateDefaultContext()
        self._end_effector = model.plant.GetFrameByName(END_EFFECTOR)
        model.plant.SetPositions(self._context, model.FullPositions(q0))
        self._R_d0 = reference.Start(self._end_effector.CalcPoseInWorld(
            self._context).rotation())
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
        self.DeclareStateOutputPort("attitude_log", self._log_index)
        self.DeclareStateOutputPort("reduced_model", self._model_index)
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._UpdateControl)
        self.DeclareInitializationDiscreteUpdateEvent(self._UpdateControl)

    def DesiredAttitude(self, t: float):
        """(R_d(t), omega_d(t))."""
        return self._reference.At(self._R_d0, t)

    def _ReferenceRates(self, t: float, q, base_pose):
        """(nu, e, clearance, R_d) at time t, joints q, base pose (quaternion,
        position)."""
        self._model.plant.SetPositions(self._context,
                                       self._model.FullPositions(q, base_pose))
        R_WE = self._end_effector.CalcPoseInWorld(self._context).rotation()
        R_d, omega_d = self.DesiredAttitude(t)
        e = attitude_error(R_WE, R_d)
        D = self._model.GeneralizedJacobian(q, self._end_effector,
                                            base_positions=base_pose)[:3]
        xi, clearance = np.zeros(self._model.num_joints), np.inf
        if self._potential is not None:
            potential = self._potential.Evaluate(q, base_pose)
            xi, clearance = -self._eta * potential.gradient, potential.min_distance
        nu = reference_rates(D, omega_d, e, self._gains.Lambda, xi,
                             self._gains.task_damping)
        return nu, e, clearance, R_d

    @staticmethod
    def _Turned(base_pose, rotation_vector):
        """The base pose with its attitude turned by ``rotation_vector`` (world)."""
        angle = np.linalg.norm(rotation_vector)
        turn = (RotationMatrix(AngleAxis(angle, rotation_vector / angle)) if angle > 0
                else RotationMatrix())
        quaternion = Quaternion(base_pose[:4] / np.linalg.norm(base_pose[:4]))
        turned = (turn @ RotationMatrix(quaternion)).ToQuaternion()
        return np.concatenate([[turned.w(), turned.x(), turned.y(), turned.z()],
                               base_pose[4:]])

    def _UpdateControl(self, context, discrete_state):
        if self._parameters is not None and self._parameters.HasValue(context):
            self._model.SetInertialParameters(self._parameters.Eval(context))
        t = context.get_time()
        base_pose = self._base_pose.Eval(context)
        omega_base = self._base_velocity.Eval(context)[:3]
        q, qdot = self._q.Eval(context), self._qdot.Eval(context)
        nu, e, clearance, R_d = self._ReferenceRates(t, q, base_pose)
        h = NU_DOT_STEP
        nu_plus = self._ReferenceRates(t + h, q + h * qdot,
                                       self._Turned(base_pose, h * omega_base))[0]
        nu_minus = self._ReferenceRates(t - h, q - h * qdot,
                                        self._Turned(base_pose, -h * omega_base))[0]
        nu_dot = (nu_plus - nu_minus) / (2 * h)
        M, C = self._model.MassAndCoriolis(q, qdot)
        s = qdot - nu
        chi = self._chi.Eval(context)[0]
        tau = (M @ nu_dot + C @ nu - self._gains.damping_rate * M @ s
               - chi * np.tanh(np.diag(M) * s / (self._gains.epsilon
                                                 + chi / self._gains.boundary_rate)))
        if self._excitation_amplitude > 0:
            tau += self._excitation_amplitude * np.sin(self._excitation_omega * t)
        discrete_state.set_value(self._tau_index, tau)
        discrete_state.set_value(self._model_index,
                                 np.concatenate([M.reshape(-1), C.reshape(-1)]))
        desired = R_d.ToQuaternion()
        discrete_state.set_value(self._log_index, np.concatenate(
            [e, [np.linalg.norm(e), np.linalg.norm(s), 0.5 * s @ M @ s, clearance,
                 desired.w(), desired.x(), desired.y(), desired.z()]]))
