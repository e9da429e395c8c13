"""The Task protocol: what an LHS controller tracks, beside the robot: its section, LHS
system, log, panels, signals, metrics, part of the certificate and the robots it serves."""
from dataclasses import dataclass
from typing import Callable, Dict, NamedTuple, Optional, Protocol, Sequence, Tuple

import numpy as np

from dacph_drake.log_layout import LogColumns, RhsLog
from dacph_drake.robots.robot import Robot
from dacph_drake.scenario import Excitation, Periods, Scenario
from dacph_drake.systems.sensors import measures_nothing

# The LHS recomputed at the ground truth's k-th logged state with the run's chi [N m]
# and identified inertias (None: the model's): (tau_c^r [N m], its log).
ControlAtTheTruth = Callable[[int, float, Optional[np.ndarray]],
                            Tuple[np.ndarray, np.ndarray]]


class TaskSignals(NamedTuple):
    """A task's signals over a run, one row per logged sample.

    Attributes:
        error: The tracking error the tables compare (rad for the shipped tasks).
        sliding: s, or ||s|| (T or T x n).
        clearance: The link-base clearance [m].
        base_turn: The base's rotation from its start [rad]."""
    error: np.ndarray
    sliding: np.ndarray
    clearance: np.ndarray
    base_turn: np.ndarray


@dataclass
class LhsSide:
    """What ``dacph verify`` needs of a run's LHS (the task's part of the certificate).

    Attributes:
        V: V = s^T M s / 2 at every logged sample [J].
        s0_norm: ||s(0)|| [rad/s].
        constants: The envelope's lyapunov_envelope.EnvelopeConstants.
        lambda_lhs: lambda_LHS of eq. (45) [1/s].
        region: The region-of-attraction certificate at q0.
        settings: The LHS's settings, for the report.
        command_error: The largest ||tau_c^r as commanded - tau_c^r at the true state||
            over the logged samples [N m]: what the sensors' noise and the command's
            hold over an LHS period put on the true s dynamics, the envelope's bounded
            input with V at the true state (0: V as the LHS measured it)."""
    V: np.ndarray
    s0_norm: float
    constants: object
    lambda_lhs: float
    region: object
    settings: Dict
    command_error: float = 0.0


def lyapunov_at_the_truth(scenario: Scenario, logs: Dict[str, np.ndarray],
                          lyapunov_column: int, logged: np.ndarray,
                          make_control: Callable[[], ControlAtTheTruth]
                          ) -> Tuple[np.ndarray, float]:
    """(V [J] at every logged sample, LhsSide.command_error [N m]) for the envelope:
    ``logged`` (the LHS's own V) and 0 unless the sensors measure anything; then V of
    the LHS recomputed at the ground truth's logged state (``make_control()``; its log's
    ``lyapunov_column``) and the largest ||tau_c^r held - tau_c^r at the truth||, the
    request it holds having been computed from its measurements up to one LHS period
    earlier.

    Args:
        scenario: The run's scenario.
        logs: The run's logs.
        lyapunov_column: V's column in the recomputed log.
        logged: The LHS's own V at every logged sample [J].
        make_control: Builds the LHS at the truth (called only with noisy sensors)."""
    if not scenario.sensing.enabled or measures_nothing(scenario.sensing):
        return logged, 0.0
    control = make_control()
    chi = logs["rhs_log"][:, RhsLog(len(scenario.q0)).chi]
    inertias = logs.get("inertial_parameters")
    V, error = np.empty(len(chi)), np.empty(len(chi))
    for k in range(len(chi)):
        tau, log = control(k, chi[k], None if inertias is None else inertias[k])
        V[k] = log[lyapunov_column]
        error[k] = np.linalg.norm(logs["tau_request"][k] - tau)
    return V, float(np.max(error))


class Task(Protocol):
    """A task, as the loop builder, the metrics, the figures and verify use it.

    Attributes:
        section: Its scenario section's dataclass (YAML tag ``!section``).
        robots: The robot kinds it serves (PlanarRobot, DescribedRobot), subclasses too.
        lhs_name: The LHS system's name.
        log_name: Its log output's name.
        panels: figures.make_panels' panels of this task."""
    section: type
    robots: Tuple[type, ...]
    lhs_name: str
    log_name: str
    panels: Tuple[str, ...]

    def LogLayout(self, n: int) -> LogColumns:
        """The columns of the task's log (log_name) by name: its signals.

        Args:
            n: The number of joints."""

    def Validate(self, section: object, periods: Periods) -> None:
        """ConfigError naming the section's first invalid setting.

        Args:
            section: The scenario's task section.
            periods: The scenario's periods."""

    def RequireRegularStart(self, robot: Robot) -> None:
        """ConfigError if the task is (nearly) singular at q0.

        Args:
            robot: The trial's Robot."""

    def GainRuleRates(self, robot: Robot) -> Tuple[float, float]:
        """(lambda_max(K_d), inf_q lambda_min(M)) for eq. (48).

        Args:
            robot: The trial's Robot."""

    def AddLhsController(self, controller: "ControllerBuilder", trials: Sequence[Robot],
                         excitation: Excitation,
                         identify: bool) -> Dict:
        """Adds the batch's LHS (out: tau_request, reduced_model, log_name; in: chi).

        Args:
            controller: The controller's closed_loop.ControllerBuilder.
            trials: Each trial's Robot.
            excitation: The learner's excitation tau_pe.
            identify: Feed the LHS from an InertialIdentifier.

        Returns:
            System name -> system."""

    def Signals(self, robot: Robot, logs: Dict[str, np.ndarray]) -> TaskSignals:
        """The task's signals over a run.

        Args:
            robot: The trial's Robot.
            logs: The run's logs."""

    def Metrics(self, robot: Robot, logs: Dict[str, np.ndarray]) -> Dict[str, float]:
        """The task's own metrics beside loop.metrics' shared ones.

        Args:
            robot: The trial's Robot.
            logs: The run's logs."""

    def VerifyLhs(self, robot: Robot, logs: Dict[str, np.ndarray], region_budget: float
                  ) -> LhsSide:
        """The task's part of the certificate.

        Args:
            robot: The trial's Robot.
            logs: The run's logs.
            region_budget: The region search's wall-time budget [s]."""
