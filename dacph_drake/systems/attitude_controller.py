"""LHS controller of a spatial arm: the sliding-mode law of LhsController with the 3D
end-effector attitude as its task (attitude.py) and the damping and the robust
term's boundary layer scaled to the inertia (scenario.AttitudeGains)."""
from dataclasses import dataclass
from typing import Optional, Sequence, Tuple

import numpy as np
from pydrake.math import RotationMatrix
from pydrake.systems.framework import LeafSystem

from dacph_drake.kernels.attitude import attitude_update, turned
from dacph_drake.dynamics.floating_model import FloatingBaseModel
from dacph_drake.log_layout import AttitudeLog, PoseLog
from dacph_drake.dynamics.plant import END_EFFECTOR
from dacph_drake.scenario import AttitudeGains, AttitudeReference, Excitation
from dacph_drake.dynamics.attitude import reference_at, reference_start

XI_DOT_STEP = 1e-5              # [s] of xi's central difference along the motion
# [m] beyond the potential's margin, the nearest link keeps xi = -eta grad U zero at
# q +- h qdot (it would move faster than FAR / XI_DOT_STEP = 1000 m/s to reach it).
FAR = 0.01


@dataclass
class AttitudeTrial:
    """One trial's part of an AttitudeController.

    Attributes:
        model: The controller's model (inertias set by ``inertial_parameters``).
        potential: The clearance potential (BaseClearancePotential), or None.
        q0: The start [rad] (n), where R_d(0) is the end effector's attitude."""
    model: FloatingBaseModel
    potential: Optional[object]
    q0: Sequence[float]


# The most the sampled LHS's linear slope may take per period (the gains' rule
# (damping_rate + boundary_rate) * periods.lhs <= 0.5, scenario.AttitudeGains).
SAMPLED_SLOPE = 0.5

class AttitudeController(LeafSystem):
    """The spatial LHS (the attitude or, with ``position``, the pose task). Every ``period``
    seconds, from the measured base pose and twist, q and qdot:

        e   = attitude_error(R_WE, R_d(t)),   D = the end effector's GJM rows
        nu  = D^+ (omega_d - Lambda e) + (I - D^+ D) xi,   xi = -eta grad U(q)
              (pose: D^+ [omega_d - Lambda e; v_d - Lambda e_p], D 6 x n)
        s   = qdot - nu
        tau = M nu_dot + C' nu + b nu - damping_rate M s - chi tanh(diag(M) s / phi)
              + tau_pe(t),   phi = epsilon + chi max(1, rho / rho_allowed) / boundary_rate

    rho = lambda_max(diag(M)^1/2 M^-1 diag(M)^1/2) >= 1: the layer thickens where
    (damping_rate + boundary_rate rho) periods.lhs would pass SAMPLED_SLOPE, keeping the
    sampled loop well damped when the coupled motion is much lighter than M_ii. b is the
    joint damping: V = s^T M s / 2 has dV/dt = -2 damping_rate V - s^T b s
    - chi s^T tanh(...) + s^T (e_tau + tau_pe) (Mdot - 2C' skew). nu_dot is exact
    (kernels.attitude); xi's rate a central difference (XI_DOT_STEP), zero unless a link
    is within FAR beyond the potential's margin. Outputs ``tau_request`` (held), the log
    (log_layout.AttitudeLog, PoseLog) and ``reduced_model`` = [vec(M), vec(C')]; a batch's
    trials are stacked on every port.

    Args:
        trials: Each trial's AttitudeTrial; one: a single run.
        reference: The attitude reference R_d(t) (task.reference).
        gains: The sliding-mode gains (task.gains).
        period: The update period [s] (periods.lhs).
        eta: The null-space gain of xi = -eta grad U.
        excitation: The learner's excitation tau_pe(t) (DAC loops; amplitude 0: off).
        identify: Declare input ``inertial_parameters`` (the inertias, each update).
        position: The pose task's position reference (PositionReference), which adds the
            GJM's linear rows to D; None: the attitude task.
        log_name: The log output's name (with ``position``: log_layout.PoseLog's columns).
        attitude: Track the attitude reference; False (with ``position``): the position
            rows alone (task: !EndEffectorPosition)."""

    def __init__(self, *, trials: Sequence[AttitudeTrial], reference: AttitudeReference,
                 gains: AttitudeGains, period: float, eta: float = 0.0,
                 excitation: Excitation = Excitation(amplitude=0.0),
                 identify: bool = False, position: Optional[object] = None,
                 log_name: str = "attitude_log", attitude: bool = True):
        super().__init__()
        self._trials = list(trials)
        model = trials[0].model
        n, count = model.num_joints, len(trials)
        self._n, self._reference, self._gains, self._eta = n, reference, gains, eta
        self._excitation = np.concatenate([excitation.Amplitudes(n),
                                           2 * np.pi * excitation.Frequencies(n)])
        rho_allowed = ((SAMPLED_SLOPE - gains.damping_rate * period)
                       / (gains.boundary_rate * period))
        self._gain_arguments = np.concatenate([
            [gains.Lambda, gains.task_damping, gains.damping_rate, gains.epsilon,
             gains.boundary_rate, rho_allowed], model.joint_damping]).astype(float)
        end_effector = model.plant.GetFrameByName(END_EFFECTOR)
        node, X_CE = model.FrameNode(end_effector)
        self._end_effector_node = (node, np.ascontiguousarray(X_CE[:3, :3]))
        axis = np.asarray(reference.axis, float)
        self._R_d0, self._reference_arguments = [], []
        for trial in trials:
            R_d0 = reference_start(reference, RotationMatrix(trial.model.FramePose(
                end_effector, trial.model.Evaluate(np.asarray(trial.q0, float),
                                                   derivatives=False))))
            self._R_d0.append(R_d0)
            self._reference_arguments.append((R_d0.matrix(), axis / np.linalg.norm(axis),
                                              float(reference.amplitude),
                                              2 * np.pi / reference.period))
        p_CE = np.ascontiguousarray(X_CE[:3, 3])
        self._position_arguments = []
        for trial in trials:
            if position is None:
                self._position_arguments.append(np.concatenate([np.zeros(9),
                                                                [-1.0, 0.0, 0.0]]))
                continue
            X = trial.model.Evaluate(np.asarray(trial.q0, float), derivatives=False)[4]
            p_E0 = X[node, :3, :3] @ p_CE + X[node, :3, 3]     # the base at the origin
            direction = np.asarray(position.axis, float)
            self._position_arguments.append(np.concatenate([
                p_CE, p_E0 + np.asarray(position.initial_offset, float),
                direction / np.linalg.norm(direction),
                [float(position.amplitude), 2 * np.pi / position.period,
                 0.0 if attitude else 1.0]]))
        self._pose = position is not None
        self._layout = PoseLog() if self._pose else AttitudeLog()
        self._base_pose = self.DeclareVectorInputPort("base_pose", 7 * count)
        self._base_velocity = self.DeclareVectorInputPort("base_velocity", 6 * count)
        self._q = self.DeclareVectorInputPort("q", n * count)
        self._qdot = self.DeclareVectorInputPort("qdot", n * count)
        self._chi = self.DeclareVectorInputPort("chi", count)
        self._parameters = (self.DeclareVectorInputPort(
            "inertial_parameters", model.parameters.size * count) if identify else None)
        self._tau_index = self.DeclareDiscreteState(n * count)
        self._log_index = self.DeclareDiscreteState(self._layout.size * count)
        self._model_index = self.DeclareDiscreteState(2 * n * n * count)
        self.DeclareStateOutputPort("tau_request", self._tau_index)
        self.DeclareVectorOutputPort(
            log_name, self._layout.size * count, self._CalcAttitudeLog,
            prerequisites_of_calc={self.discrete_state_ticket(self._log_index),
                                   self._q.ticket(), self._base_pose.ticket()})
        self.DeclareStateOutputPort("reduced_model", self._model_index)
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._UpdateControl)
        self.DeclareInitializationDiscreteUpdateEvent(self._UpdateControl)

    def DesiredAttitude(self, t: float, trial: int = 0
                        ) -> Tuple[RotationMatrix, np.ndarray]:
        """(R_d(t), omega_d(t)) of trial ``trial``.

        Args:
            t: The time [s].
            trial: The trial's index in the batch.

        Returns:
            (R_d(t), omega_d(t) in the world frame [rad/s] (3))."""
        return reference_at(self._reference, self._R_d0[trial], t)

    def _Secondary(self, potential, q, base_pose):
        """(xi = -eta grad U, the nearest link-base distance if within the
        potential's margin + FAR, else inf) at q and the base pose."""
        if potential is None:
            return np.zeros(self._n), np.inf
        clearance = potential.Evaluate(q, base_pose,
                                       query_distance=potential.margin + FAR)
        return -self._eta * clearance.gradient, clearance.min_distance

    def _CalcAttitudeLog(self, context, output):
        """The update's logs with the smallest link-base distance at the current state."""
        count = len(self._trials)
        logs = context.get_discrete_state(self._log_index).CopyToVector().reshape(
            count, -1)
        q = self._q.Eval(context).reshape(count, -1)
        base_pose = self._base_pose.Eval(context).reshape(count, -1)
        for i, trial in enumerate(self._trials):
            if trial.potential is not None:
                logs[i, self._layout.clearance] = trial.potential.Evaluate(
                    q[i], base_pose[i]).min_distance
        output.SetFromVector(logs.reshape(-1))

    def _UpdateControl(self, context, discrete_state):
        count, t = len(self._trials), context.get_time()
        parameters = (self._parameters.Eval(context).reshape(count, -1)
                      if self._parameters is not None and self._parameters.HasValue(
                          context) else None)
        base_pose, base_velocity, q, qdot = (
            port.Eval(context).reshape(count, -1) for port in
            (self._base_pose, self._base_velocity, self._q, self._qdot))
        chi = self._chi.Eval(context)
        tau, models, logs = [], [], []
        for i, trial in enumerate(self._trials):
            if parameters is not None:
                trial.model.SetInertialParameters(parameters[i])
            torque, M, C, log = self._Update(trial, i, t, base_pose[i],
                                             base_velocity[i], q[i], qdot[i], chi[i])
            tau.append(torque)
            models += [M.reshape(-1), C.reshape(-1)]
            logs.append(log)
        discrete_state.set_value(self._tau_index, np.concatenate(tau))
        discrete_state.set_value(self._model_index, np.concatenate(models))
        discrete_state.set_value(self._log_index, np.concatenate(logs))

    def Control(self, t: float, base_pose: np.ndarray, base_velocity: np.ndarray,
                q: np.ndarray, qdot: np.ndarray, chi: float, trial: int = 0,
                inertial_parameters: Optional[np.ndarray] = None
                ) -> Tuple[np.ndarray, np.ndarray]:
        """(tau_c^r [N m] (n), the log) of one trial at one state, as an update computes
        them (with ``inertial_parameters``, the trial's model takes them first).

        Args:
            t: The time [s].
            base_pose: The base's pose (quaternion w, x, y, z; position) (7).
            base_velocity: The base's twist (omega_W, v_W) (6).
            q: The joint angles [rad] (n).
            qdot: The joint rates [rad/s] (n).
            chi: The RHS loop's bound chi [N m].
            trial: The trial's index in the batch.
            inertial_parameters: The model's inertias (None: as they are)."""
        if inertial_parameters is not None:
            self._trials[trial].model.SetInertialParameters(inertial_parameters)
        tau, _, _, log = self._Update(self._trials[trial], trial, t, base_pose,
                                      base_velocity, q, qdot, chi)
        return tau, log

    def _Update(self, trial: AttitudeTrial, i: int, t, base_pose, base_velocity, q,
                qdot, chi):
        """One trial's (tau, M, C', attitude log) (class docstring)."""
        potential, omega_base = trial.potential, base_velocity[:3]
        xi, clearance = self._Secondary(potential, q, base_pose)
        xi_dot = np.zeros_like(xi)
        if potential is not None and clearance <= potential.margin + FAR:
            h, sides = XI_DOT_STEP, []
            for sign in (1.0, -1.0):
                q_h = q + sign * h * qdot
                pose_h = np.concatenate([turned(base_pose[:4], sign * h * omega_base),
                                         base_pose[4:]])
                sides.append(self._Secondary(potential, q_h, pose_h)[0])
            xi_dot = (sides[0] - sides[1]) / (2 * h)
        tau, M, C, log, desired, position = attitude_update(
            trial.model.kernel_tree, q, qdot, base_pose, base_velocity, t,
            self._reference_arguments[i], self._end_effector_node,
            self._position_arguments[i], xi, xi_dot, self._gain_arguments, chi,
            self._excitation)
        logged = [log, [np.inf], desired] + ([position] if self._pose else [])
        return tau, M, C, np.concatenate(logged)
