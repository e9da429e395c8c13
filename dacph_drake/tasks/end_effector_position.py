"""task: !EndEffectorPosition, a described arm's end-effector position: the
AttitudeController with the GJM's linear rows D_p (3 x n) alone (position_rates),
nu = D_p^+ (v_d - Lambda e_p) + (I - D_p^+ D_p) xi, e_p = p_E - p_d(t) (world): an arm
of 3 to 5 joints can place its end effector, not turn it about every axis; a longer arm
leaves its attitude to the null space. The law, V = s^T M s / 2 and the certificate are
the attitude task's (E26-E28 hold for any nu); the tracking error is |e_p| [m]."""
from typing import Dict

import numpy as np

from dacph_drake.scenario.errors import ConfigError
from dacph_drake.log_layout import PoseLog
from dacph_drake.robots.robot import Robot
from dacph_drake.robots.start_pose import POSITION_ROWS
from dacph_drake.scenario import EndEffectorPosition, Periods
from dacph_drake.tasks.end_effector_pose import EndEffectorPoseTask
from dacph_drake.tasks.task import TaskSignals


class EndEffectorPositionTask(EndEffectorPoseTask):
    """tasks.task.Task of a described arm's end-effector position."""
    section = EndEffectorPosition
    lhs_name, log_name = "position_controller", "position_log"
    panels = ("e_position_dac_vs_model_based", "f_inputs_and_joints")
    jacobian_rows = POSITION_ROWS   # the GJM's linear rows (start_pose)

    def Validate(self, section: EndEffectorPosition, periods: Periods) -> None:
        """The gains' checks (the attitude task's) and the position reference's.

        Args:
            section: The task section.
            periods: The scenario's periods."""
        self.ValidateGains(section.gains, periods)
        self.ValidatePosition(section.position)

    def RequireRegularStart(self, robot: Robot) -> None:
        """ConfigError on fewer than 3 joints or (nearly) singular linear GJM rows at q0.

        Args:
            robot: The trial's DescribedRobot."""
        if robot.num_joints < 3:
            raise ConfigError(f"task: !EndEffectorPosition on a {robot.num_joints}-"
                              "joint arm; allowed: an arm of at least 3 joints")
        self.RequireRegularRows(robot)

    def ControllerOptions(self, section: EndEffectorPosition) -> Dict:
        """The position rows alone, and the position log.

        Args:
            section: The task section."""
        return {"position": section.position, "log_name": self.log_name,
                "attitude": False}

    def Signals(self, robot: Robot, logs: Dict[str, np.ndarray]) -> TaskSignals:
        """The attitude task's signals with |e_p| [m] as the tracking error.

        Args:
            robot: The trial's DescribedRobot.
            logs: The run's logs."""
        signals = super().Signals(robot, logs)
        return TaskSignals(logs[self.log_name][:, PoseLog().e_position_norm],
                           *signals[1:])


    def Metrics(self, robot: Robot, logs: Dict[str, np.ndarray]) -> Dict[str, float]:
        """The pose task's metrics but the attitude's (no attitude is tracked).

        Args:
            robot: The trial's DescribedRobot.
            logs: The run's logs."""
        return {key: value for key, value in super().Metrics(robot, logs).items()
                if not key.startswith("attitude_error")}


END_EFFECTOR_POSITION = EndEffectorPositionTask()
