"""task: !EndEffectorPose, a described arm's end-effector position and attitude: the
AttitudeController with the GJM's linear rows under its angular ones (D, 6 x n,
pose_rates), so nu = D^+ [omega_d - Lambda e; v_d - Lambda e_p] + (I - D^+ D) xi,
e_p = p_E - p_d(t) (world); the null space (n > 6) keeps the links off the base. The law,
V = s^T M s / 2 and the certificate are the attitude task's (E26-E28 hold for any nu)."""
from typing import Dict

import numpy as np

from dacph_drake.analysis.phases import phase_windows, rms
from dacph_drake.scenario.errors import ConfigError, require_finite_numbers, require_positive
from dacph_drake.log_layout import PoseLog
from dacph_drake.scenario import EndEffectorPose, Periods, PositionReference
from dacph_drake.robots.robot import Robot
from dacph_drake.tasks.end_effector_attitude import EndEffectorAttitudeTask

class EndEffectorPoseTask(EndEffectorAttitudeTask):
    """tasks.task.Task of a described arm's end-effector pose."""
    section = EndEffectorPose
    lhs_name, log_name = "pose_controller", "pose_log"
    panels = ("e_pose_dac_vs_model_based", "f_inputs_and_joints")
    jacobian_rows = (0, 1, 2, 3, 4, 5)

    def LogLayout(self, n: int) -> PoseLog:
        """tasks.task.Task.LogLayout: pose_log's columns.

        Args:
            n: The number of joints."""
        return PoseLog()

    def Validate(self, section: EndEffectorPose, periods: Periods) -> None:
        """The attitude task's checks, then the position reference's.

        Args:
            section: The task section.
            periods: The scenario's periods."""
        super().Validate(section, periods)
        self.ValidatePosition(section.position)

    @staticmethod
    def ValidatePosition(p: PositionReference) -> None:
        """ConfigError naming the first invalid setting of the position reference.

        Args:
            p: The position reference."""
        require_positive("task.position.period", p.period, "s")
        require_finite_numbers("task.position.amplitude", [p.amplitude])
        if p.amplitude < 0:
            raise ConfigError(f"task.position.amplitude = {p.amplitude!r} m; allowed: "
                              ">= 0")
        for name in ("axis", "initial_offset"):
            vector = getattr(p, name)
            require_finite_numbers(f"task.position.{name}", list(vector))
            if len(vector) != 3 or (name == "axis" and np.linalg.norm(vector) == 0):
                raise ConfigError(f"task.position.{name} = {list(vector)}; allowed: a "
                                  + ("non-zero " if name == "axis" else "") + "3-vector")

    def RequireRegularStart(self, robot: Robot) -> None:
        """ConfigError on fewer than 6 joints or a (nearly) singular 6-row GJM at q0.

        Args:
            robot: The trial's DescribedRobot."""
        if robot.num_joints < 6:
            raise ConfigError(f"task: !EndEffectorPose on a {robot.num_joints}-joint "
                              "arm; allowed: an arm of at least 6 joints (or task: "
                              "!EndEffectorAttitude)")
        super().RequireRegularStart(robot)

    def ControllerOptions(self, section: EndEffectorPose) -> Dict:
        """The position rows and the pose log.

        Args:
            section: The task section."""
        return {"position": section.position, "log_name": self.log_name}

    def Metrics(self, robot: Robot, logs: Dict[str, np.ndarray]) -> Dict[str, float]:
        """The attitude task's metrics and the RMS |e_p| [m] per phase.

        Args:
            robot: The trial's DescribedRobot.
            logs: The run's logs."""
        out = super().Metrics(robot, logs)
        log, L = logs[self.log_name], PoseLog()
        for phase, mask in phase_windows(robot.scenario, logs["time"]).items():
            out[f"{phase}.position_error_rms"] = rms(log[mask, L.e_position_norm])
        return out


END_EFFECTOR_POSE = EndEffectorPoseTask()
