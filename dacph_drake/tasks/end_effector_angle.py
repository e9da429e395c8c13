"""task: the planar end effector's angle alpha = theta0 + sum q, tracked by the sliding-mode
LhsController (E23-E25), K_d = Kd I; certificate: Drake's SOS region at frozen q."""
from typing import Dict, Sequence, Tuple

import numpy as np

from dacph_drake.dynamics.inertial_parameters import InertialParameters
from dacph_drake.dynamics.plant import ArmCoordinates
from dacph_drake.dynamics.reduced_model import mass_matrix_bounds
from dacph_drake.scenario.errors import (ConfigError, require_in_range, require_nonnegative,
                                require_positive)
from dacph_drake.log_layout import LhsLog
from dacph_drake.dynamics.base_repulsion import BaseRepulsionPotential
from dacph_drake.robots.planar import PlanarRobot
from dacph_drake.scenario import EndEffectorAngle, Excitation, Periods
from dacph_drake.systems.lhs_controller import (LhsController, LhsTrial,
                                                boundary_layer_per_chi)
from dacph_drake.dynamics.reference import OrientationReference
from dacph_drake.robots.robot import Robot
from dacph_drake.tasks.task import (ControlAtTheTruth, LhsSide, TaskSignals,
                                    lyapunov_at_the_truth)


class EndEffectorAngleTask:
    """tasks.task.Task of the planar end effector's angle."""
    section, robots = EndEffectorAngle, (PlanarRobot,)
    lhs_name, log_name = "lhs_controller", "lhs_log"
    panels = ("e_dac_vs_model_based", "f_inputs_and_states")

    def LogLayout(self, n: int) -> LhsLog:
        """tasks.task.Task.LogLayout: lhs_log's columns.

        Args:
            n: The number of joints."""
        return LhsLog(n)

    def Validate(self, section: EndEffectorAngle, periods: Periods) -> None:
        """ConfigError naming the first invalid gain or reference setting.

        Args:
            section: The task section.
            periods: The scenario's periods (not needed)."""
        gains, reference = section.gains, section.reference
        for name in ("Kd", "Lambda", "epsilon", "eta"):
            require_positive(f"task.gains.{name}", getattr(gains, name))
        require_nonnegative("task.gains.chi_model_based", gains.chi_model_based, "N m")
        require_in_range("task.gains.min_task_singular_value",
                         gains.min_task_singular_value, 0.0, 10.0)
        require_nonnegative("task.gains.boundary_rate", gains.boundary_rate, "1/s")
        if len(reference.amplitudes) != len(reference.periods):
            raise ConfigError("task.reference.amplitudes and task.reference.periods "
                              "must have the same length")
        for i, T in enumerate(reference.periods):
            require_positive(f"task.reference.periods[{i}]", T, "s")

    def RequireRegularStart(self, robot: Robot) -> None:
        """ConfigError unless ||d alpha / d qdot|| >= gains.min_task_singular_value at q0.

        Args:
            robot: The trial's robots.planar.PlanarRobot."""
        scenario = robot.scenario
        q0 = np.asarray(scenario.q0, float)
        sigma = float(np.linalg.norm(robot.model.Evaluate(q0, np.zeros_like(q0)).D))
        bound = scenario.task.gains.min_task_singular_value
        if sigma < bound:
            raise ConfigError(
                f"q0 = {list(scenario.q0)} is near a singularity of the task Jacobian D "
                f"(||D(q0)|| = {sigma:.3g}); allowed: a q0 with ||D(q0)|| >= "
                f"task.gains.min_task_singular_value = {bound:g}")

    def GainRuleRates(self, robot: Robot) -> Tuple[float, float]:
        """(Kd, the nominal robot's inf_q lambda_min(M)).

        Args:
            robot: The trial's PlanarRobot."""
        return robot.scenario.task.gains.Kd, robot.mass_matrix_bounds[0]

    def AddLhsController(self, controller: "ControllerBuilder", trials: Sequence[Robot],
                         excitation: Excitation,
                         identify: bool) -> Dict:
        """Adds the LhsController (each trial's potential, theta0(0) = 0).

        Args:
            controller: The controller's ControllerBuilder.
            trials: Each trial's PlanarRobot.
            excitation: The learner's excitation tau_pe.
            identify: Feed the LHS from an InertialIdentifier.

        Returns:
            System name -> system."""
        builder = controller.builder
        systems = ({"inertial_identifier": builder.AddNamedSystem(
            "inertial_identifier", type(trials[0]).MakeInertialIdentifier(trials))}
            if identify else {})
        lhs = builder.AddNamedSystem(self.lhs_name, self._LhsController(
            trials, excitation, identify))
        for signal in ("base_pose", "q", "qdot"):
            controller.Input(lhs.GetInputPort(signal), signal)
        return {self.lhs_name: lhs, **systems}

    def _LhsController(self, trials: Sequence[Robot], excitation: Excitation,
                       identify: bool) -> LhsController:
        """The trials' LhsController (each trial's potential and reference)."""
        scenario = trials[0].scenario
        return LhsController(
            trials=[LhsTrial(
                model=t.model, potential=BaseRepulsionPotential(
                    t.scenario.robot.nominal, t.scenario.robot.potential),
                reference=OrientationReference(t.scenario.task.reference,
                                               float(np.sum(t.scenario.q0))),
                lambda_min_M=self.GainRuleRates(t)[1]) for t in trials],
            gains=scenario.task.gains, period=scenario.periods.lhs,
            excitation=excitation, identify=identify)

    def _ControlAtTheTruth(self, robot: Robot, logs: Dict[str, np.ndarray]
                           ) -> ControlAtTheTruth:
        """The trial's LhsController at the ground truth's logged states."""
        lhs = self._LhsController([robot], robot.scenario.excitation,
                                  "inertial_parameters" in logs)
        base_pose, q, _, qdot = ArmCoordinates.ForPlanarArm(robot.num_joints).Split(
            logs["state"])
        t = logs["time"]
        return lambda k, chi, inertias: lhs.Control(
            t[k], base_pose[k, 2], q[k], qdot[k], chi, inertial_parameters=inertias)

    def Signals(self, robot: Robot, logs: Dict[str, np.ndarray]) -> TaskSignals:
        """(alpha~ [rad], s, the truth's kinematic clearance [m], theta0 - theta0(0)).

        Args:
            robot: The trial's PlanarRobot.
            logs: The run's logs."""
        n = robot.num_joints
        lhs, L = logs[self.log_name], LhsLog(n)
        base_pose, q, _, _ = ArmCoordinates.ForPlanarArm(n).Split(logs["state"])
        clearance = robot.Clearance()
        return TaskSignals(lhs[:, L.alpha_error], lhs[:, L.s],
                           np.array([clearance(joints) for joints in q]),
                           base_pose[:, 2] - base_pose[0, 2])

    def Metrics(self, robot: Robot, logs: Dict[str, np.ndarray]) -> Dict[str, float]:
        """None beyond the shared metrics.

        Args:
            robot: The trial's PlanarRobot.
            logs: The run's logs."""
        return {}

    def VerifyLhs(self, robot: Robot, logs: Dict[str, np.ndarray], region_budget: float
                  ) -> LhsSide:
        """The envelope and eq. (45) on the nominal and identified models' inertia bounds;
        with sensors that measure anything, on V at the true state with their noise a
        bounded input (tasks.task.lyapunov_at_the_truth).

        Args:
            robot: The trial's PlanarRobot.
            logs: The run's logs.
            region_budget: The SOS program's wall-time budget [s]."""
        from dacph_drake.analysis.lyapunov_envelope import EnvelopeConstants
        from dacph_drake.analysis.region_of_attraction import sliding_region_of_attraction
        scenario, n, model = robot.scenario, robot.num_joints, robot.model
        models = [model]
        if "inertial_parameters" in logs:
            models.append(model.WithInertialParameters(
                InertialParameters(model.plant), logs["inertial_parameters"][-1]))
        bounds = np.array([mass_matrix_bounds(m) for m in models])
        lambda_min_M, lambda_max_M = float(bounds[:, 0].min()), float(bounds[:, 1].max())
        gains = scenario.task.gains
        Kd, epsilon = gains.Kd, gains.epsilon
        # The boundary layer as the controller built it, from the nominal robot's bound.
        layer_per_chi = boundary_layer_per_chi(gains, bounds[0, 0])
        L = LhsLog(n)
        V, command_error = lyapunov_at_the_truth(
            scenario, logs, L.lyapunov_V, logs[self.log_name][:, L.lyapunov_V],
            lambda: self._ControlAtTheTruth(robot, logs))
        return LhsSide(
            V=V, command_error=command_error,
            s0_norm=float(np.linalg.norm(logs[self.log_name][0, L.s])),
            constants=EnvelopeConstants.ForConstantDamping(
                Kd, Kd, lambda_min_M, lambda_max_M, epsilon, n, layer_per_chi),
            lambda_lhs=2 * Kd / lambda_min_M,
            region=sliding_region_of_attraction(
                model, np.asarray(scenario.q0), Kd, scenario.rhs.chi_initial,
                epsilon + layer_per_chi * scenario.rhs.chi_initial, region_budget),
            settings={"inf_lambda_min_M": lambda_min_M, "sup_lambda_max_M": lambda_max_M,
                      "models": len(models)})


END_EFFECTOR_ANGLE = EndEffectorAngleTask()
