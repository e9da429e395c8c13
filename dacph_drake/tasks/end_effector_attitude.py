"""task: !EndEffectorAttitude, tracked by the AttitudeController (K_d = damping_rate M(q),
inertia-scaled layer); certificate: the region with nothing frozen (E26-E28)."""
from typing import Dict, Sequence, Tuple

import numpy as np

from dacph_drake.dynamics.plant import ArmCoordinates
from dacph_drake.scenario.errors import (ConfigError, require_finite_numbers, require_in_range,
                                require_nonnegative, require_positive)
from dacph_drake.log_layout import AttitudeLog
from dacph_drake.robots.described import DescribedRobot
from dacph_drake.robots.start_pose import ATTITUDE_ROWS, task_singularity
from dacph_drake.scenario import (AttitudeGains, AttitudeReference, EndEffectorAttitude,
                                  Excitation, Periods)
from dacph_drake.systems.attitude_controller import AttitudeController, AttitudeTrial
from dacph_drake.robots.robot import Robot
from dacph_drake.tasks.task import (ControlAtTheTruth, LhsSide, TaskSignals,
                                    lyapunov_at_the_truth)

SETTLING_TIME = 1.0             # [s] left out of the steady-state error metrics
# Configurations sampled for sup_q max_i M_ii in VerifyLhs, and the margin on the
# largest: it only lowers the envelope's allowed decay (a false alarm, never a miss).
DIAGONAL_SAMPLES, DIAGONAL_MARGIN = 256, 0.1


class EndEffectorAttitudeTask:
    """tasks.task.Task of a described arm's end-effector attitude."""
    section, robots = EndEffectorAttitude, (DescribedRobot,)
    lhs_name, log_name = "attitude_controller", "attitude_log"
    panels = ("e_attitude_dac_vs_model_based", "f_inputs_and_joints")
    jacobian_rows = ATTITUDE_ROWS   # the GJM's rows the task tracks (start_pose)

    def LogLayout(self, n: int) -> AttitudeLog:
        """tasks.task.Task.LogLayout: attitude_log's columns.

        Args:
            n: The number of joints."""
        return AttitudeLog()

    def Validate(self, section: EndEffectorAttitude, periods: Periods) -> None:
        """ConfigError naming the first invalid gain or reference setting.

        Args:
            section: The task section.
            periods: The scenario's periods (the gains' rates against periods.lhs)."""
        self.ValidateGains(section.gains, periods)
        r = section.reference
        require_positive("task.reference.period", r.period, "s")
        require_nonnegative("task.reference.amplitude", r.amplitude, "rad")
        require_in_range("task.reference.initial_error", r.initial_error, 0.0, np.pi,
                         "rad")
        for name in ("axis", "initial_error_axis"):
            axis = getattr(r, name)
            require_finite_numbers(f"task.reference.{name}", list(axis))
            if len(axis) != 3 or np.linalg.norm(axis) == 0:
                raise ConfigError(f"task.reference.{name} = {list(axis)}; allowed: a "
                                  "non-zero 3-vector")

    @staticmethod
    def ValidateGains(g: AttitudeGains, periods: Periods) -> None:
        """ConfigError naming the first invalid gain.

        Args:
            g: The task's gains.
            periods: The scenario's periods (the gains' rates against periods.lhs)."""
        require_positive("task.gains.Lambda", g.Lambda, "1/s")
        require_positive("task.gains.damping_rate", g.damping_rate, "1/s")
        require_nonnegative("task.gains.task_damping", g.task_damping)
        require_positive("task.gains.epsilon", g.epsilon, "N m s")
        require_positive("task.gains.boundary_rate", g.boundary_rate, "1/s")
        require_nonnegative("task.gains.chi_model_based", g.chi_model_based, "N m")
        for name, rate in (("damping_rate", g.damping_rate),
                           ("damping_rate + task.gains.boundary_rate",
                            g.damping_rate + g.boundary_rate)):
            if rate * periods.lhs > 0.5:
                raise ConfigError(
                    f"task.gains.{name} = {rate:g} 1/s with periods.lhs = "
                    f"{periods.lhs:g} s; allowed: rate * periods.lhs <= 0.5 (the "
                    "sampled sliding-mode loop stays well damped)")

    def RequireRegularStart(self, robot: Robot) -> None:
        """RequireRegularRows: ConfigError if the task's GJM rows are (nearly) singular.

        Args:
            robot: The trial's robots.described.DescribedRobot."""
        self.RequireRegularRows(robot)

    def RequireRegularRows(self, robot: Robot) -> None:
        """ConfigError if the task's GJM rows are (nearly) singular at q0, naming joints.

        Args:
            robot: The trial's robots.described.DescribedRobot."""
        q0 = robot.scenario.q0
        singular = task_singularity(robot.model, q0, self.jacobian_rows)
        if singular:
            raise ConfigError(f"q0 = {list(q0)}: {singular}; allowed: a q0 away from "
                              "the task's singularities, or none (a start is then "
                              "chosen: robots.start_pose.choose_start)")

    def GainRuleRates(self, robot: Robot) -> Tuple[float, float]:
        """(damping_rate, 1): K_d = damping_rate M sets the LHS rate on every arm.

        Args:
            robot: The trial's DescribedRobot."""
        return robot.scenario.task.gains.damping_rate, 1.0

    def Controller(self, trials: Sequence[Robot], excitation: Excitation, identify: bool
                   ) -> AttitudeController:
        """The batch's LHS system.

        Args:
            trials: Each trial's DescribedRobot.
            excitation: The learner's excitation tau_pe.
            identify: Declare the input inertial_parameters."""
        first = trials[0].scenario
        return AttitudeController(
            trials=[AttitudeTrial(model=t.model, potential=t.BasePotential(),
                                  q0=t.scenario.q0) for t in trials],
            # A task without an attitude reference (task: !EndEffectorPosition)
            # gives the default one, which its position rows leave unused.
            reference=getattr(first.task, "reference", None) or AttitudeReference(),
            gains=first.task.gains,
            period=first.periods.lhs, eta=first.robot.potential.eta,
            excitation=excitation, identify=identify,
            **self.ControllerOptions(first.task))

    def ControllerOptions(self, section: EndEffectorAttitude) -> Dict:
        """The AttitudeController's task-specific options: none.

        Args:
            section: The task section."""
        return {}

    def AddLhsController(self, controller: "ControllerBuilder", trials: Sequence[Robot],
                         excitation: Excitation,
                         identify: bool) -> Dict:
        """Adds the controller and, with ``identify``, its InertialIdentifier.

        Args:
            controller: The controller's ControllerBuilder.
            trials: Each trial's DescribedRobot.
            excitation: The learner's excitation tau_pe.
            identify: Feed the LHS from an InertialIdentifier.

        Returns:
            System name -> system."""
        builder = controller.builder
        lhs = builder.AddNamedSystem(self.lhs_name,
                                     self.Controller(trials, excitation, identify))
        for signal in ("base_pose", "base_velocity", "q", "qdot"):
            controller.Input(lhs.GetInputPort(signal), signal)
        if not identify:
            return {self.lhs_name: lhs}
        identifier = builder.AddNamedSystem(
            "inertial_identifier", type(trials[0]).MakeInertialIdentifier(trials))
        return {self.lhs_name: lhs, "inertial_identifier": identifier}

    def Signals(self, robot: Robot, logs: Dict[str, np.ndarray]) -> TaskSignals:
        """(|e| [rad], ||s||, the link-base distance [m], the base's turn [rad]).

        Args:
            robot: The trial's DescribedRobot.
            logs: The run's logs."""
        log, A = logs[self.log_name], AttitudeLog()
        base_q = ArmCoordinates.FromPlant(robot.model.plant).base_q
        quaternion = logs["state"][:, base_q[:4]]       # the free base's (w, x, y, z)
        quaternion = quaternion / np.linalg.norm(quaternion, axis=1, keepdims=True)
        cosine = np.clip(np.abs(quaternion @ quaternion[0]), 0.0, 1.0)
        return TaskSignals(log[:, A.e_norm], log[:, A.s_norm], log[:, A.clearance],
                           2 * np.arccos(cosine))

    def Metrics(self, robot: Robot, logs: Dict[str, np.ndarray]) -> Dict[str, float]:
        """|e| after SETTLING_TIME (final, RMS, max) [rad], the least link-base distance
        [m], the largest |spatial momentum| and the share of samples with a command clipped.

        Args:
            robot: The trial's DescribedRobot.
            logs: The run's logs."""
        layout = AttitudeLog()
        t, error = logs["time"], logs[self.log_name][:, layout.e_norm]
        settled = t >= SETTLING_TIME
        clearance = logs[self.log_name][:, layout.clearance]
        plant = robot.truth_plant
        context = plant.CreateDefaultContext()
        momentum = 0.0
        for x in logs["state"]:
            plant.SetPositionsAndVelocities(context, x)
            momentum = max(momentum, float(np.max(np.abs(
                plant.CalcSpatialMomentumInWorldAboutPoint(context, np.zeros(3)
                                                           ).get_coeffs()))))
        nan = float("nan")
        return {
            "attitude_error_final": float(error[-1]) if len(error) else nan,
            "attitude_error_rms_settled": (float(np.sqrt(np.mean(error[settled]**2)))
                                           if settled.any() else nan),
            "attitude_error_max_settled": (float(np.max(error[settled]))
                                           if settled.any() else nan),
            "min_clearance": (float(np.min(clearance)) if np.all(np.isfinite(clearance))
                              and len(clearance) else nan),
            "max_momentum": momentum,
            "effort_saturated_share": (float(np.mean(np.any(logs["saturated"] > 0.5,
                                                            axis=1)))
                                       if "saturated" in logs and len(t) else nan)}

    def _ControlAtTheTruth(self, robot: Robot, logs: Dict[str, np.ndarray]
                           ) -> ControlAtTheTruth:
        """The trial's controller, on a fresh model, at the ground truth's logged states."""
        scenario = robot.scenario
        lhs = self.Controller([type(robot)(scenario, self)], scenario.excitation,
                              "inertial_parameters" in logs)
        base_pose, q, base_velocity, qdot = ArmCoordinates.FromPlant(
            robot.model.plant).Split(logs["state"])
        t = logs["time"]
        return lambda k, chi, inertias: lhs.Control(
            t[k], base_pose[k], base_velocity[k], q[k], qdot[k], chi,
            inertial_parameters=inertias)

    def VerifyLhs(self, robot: Robot, logs: Dict[str, np.ndarray], region_budget: float
                  ) -> LhsSide:
        """The inertia-scaled envelope (ForInertiaScaled), the moving-configuration region;
        with sensors that measure anything, on V at the true state with their noise a
        bounded input (tasks.task.lyapunov_at_the_truth).

        Args:
            robot: The trial's DescribedRobot.
            logs: The run's logs.
            region_budget: Not binding here [s]."""
        from dacph_drake.analysis.lyapunov_envelope import EnvelopeConstants
        from dacph_drake.analysis.region_of_attraction import (
            moving_region_of_attraction)
        from dacph_drake.dynamics.inertia_bound import search_inertia_bound
        scenario, model = robot.scenario, robot.model
        models = [model]
        if "inertial_parameters" in logs:
            models.append(type(robot)(scenario, self).model)
            models[-1].SetInertialParameters(logs["inertial_parameters"][-1])
        n, gains = model.num_joints, scenario.task.gains
        lambda_min_M = min(search_inertia_bound(m).lambda_min for m in models)
        samples = np.random.default_rng(0).uniform(-np.pi, np.pi, (DIAGONAL_SAMPLES, n))
        max_diagonal_M = (1 + DIAGONAL_MARGIN) * max(
            float(np.max(np.diag(m.MassMatrix(q)))) for q in samples for m in models)
        L, log = AttitudeLog(), logs[self.log_name]
        V, command_error = lyapunov_at_the_truth(
            scenario, logs, L.lyapunov_V, log[:, L.lyapunov_V],
            lambda: self._ControlAtTheTruth(robot, logs))
        return LhsSide(
            V=V, command_error=command_error, s0_norm=float(log[0, L.s_norm]),
            constants=EnvelopeConstants.ForInertiaScaled(
                gains.damping_rate, lambda_min_M, max_diagonal_M, gains.epsilon,
                gains.boundary_rate, n),
            lambda_lhs=2 * gains.damping_rate,
            region=moving_region_of_attraction(model, np.asarray(scenario.q0),
                                               gains.damping_rate),
            settings={"inf_lambda_min_M": lambda_min_M,
                      "sup_max_diagonal_M": max_diagonal_M})


END_EFFECTOR_ATTITUDE = EndEffectorAttitudeTask()
