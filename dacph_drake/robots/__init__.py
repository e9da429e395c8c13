"""Robots: what a closed loop needs of the robot it controls, for every robot alike.

A scenario's ``robot:`` section is one of two typed variants (scenario.PlanarArm,
scenario.DescribedArm) and its ``task:`` one of two (scenario.EndEffectorAngle,
scenario.EndEffectorAttitude); ``robot_of(scenario)`` is the one place that
dispatches on them, returning an object with the Robot protocol below
(robots.planar.PlanarRobot, robots.described.DescribedRobot). The loop builder
(loop.closed_loop), ``loop.simulate``, the metrics, the figures, ``dacph verify``
and the animations use that protocol only."""
import importlib
from pathlib import Path
from typing import (TYPE_CHECKING, Callable, Dict, List, Optional, Protocol, Sequence,
                    Tuple, Union)

import numpy as np

from dacph_drake.dynamics import ReducedModel
from dacph_drake.errors import ConfigError, require_setting_types

if TYPE_CHECKING:       # type names only: importing robots loads no Drake module
    from pydrake.geometry import Meshcat, SceneGraph
    from pydrake.multibody.plant import MultibodyPlant
    from pydrake.systems.framework import DiagramBuilder

    from dacph_drake.analysis.verify import LhsSide
    from dacph_drake.loop.closed_loop import ClosedLoop, ControllerBuilder
    from dacph_drake.robots import viewers
    from dacph_drake.scenario import Excitation, Scenario
    from dacph_drake.systems.true_rhs import TrueRhsSystem


class Robot(Protocol):
    """A robot and its task, as the loop builder and the tools use it.

    Attributes:
        scenario: The scenario.Scenario it was made from.
        num_joints: The number of the arm's joints n.
        model: The controller's model (its inertias nominal).
        lhs_name: The LHS controller's system name.
        lhs_log: The name of its log output.
        task_panels: figures.make_panels' panels of this task.
    """
    scenario: object                # the scenario.Scenario it was made from
    num_joints: int
    model: ReducedModel             # the controller's model (its inertias nominal)
    lhs_name: str                   # the LHS controller's system name
    lhs_log: str                    # the name of its log output
    task_panels: Tuple[str, ...]    # figures.make_panels' panels of this task

    @classmethod
    def AddGroundTruth(cls, builder: "DiagramBuilder", trials: Sequence["Robot"]
                       ) -> Tuple["MultibodyPlant", "SceneGraph"]:
        """Adds the ground-truth plant of a batch and its SceneGraph.

        The plant is a MultibodyPlant named "plant".

        Args:
            builder: The closed loop's builder.
            trials: Each trial's Robot (one: a single run).

        Returns:
            (plant, scene_graph)."""

    @classmethod
    def MakeTrueRhs(cls, plant: "MultibodyPlant", trials: Sequence["Robot"]
                    ) -> "TrueRhsSystem":
        """Makes the port's true RHS system of a batch.

        Args:
            plant: The trials' ground-truth plant (AddGroundTruth).
            trials: Each trial's Robot.

        Returns:
            The system (inputs u, state, disturbance_model; outputs tau,
                true_matrices; stacked)."""

    def RequireRunnableStart(self) -> None:
        """Requires that a run can start at the scenario's q0.

        Raises:
            ConfigError: Naming why it cannot."""

    def GainRuleRates(self) -> Tuple[float, float]:
        """The LHS's rates for eq. (48).

        Returns:
            (lambda_max(K_d), inf_q lambda_min(M))."""

    @classmethod
    def AddLhsController(cls, controller: "ControllerBuilder", trials: Sequence["Robot"],
                         excitation: "Excitation", identify: bool) -> Dict:
        """Adds the LHS controller of a batch into the controller's builder.

        The controller has outputs tau_request, reduced_model and its log, and
        input chi; stacked.

        Args:
            controller: The controller's ControllerBuilder.
            trials: Each trial's Robot.
            excitation: The learner's excitation tau_pe(t) (amplitude 0: off).
            identify: Add an InertialIdentifier feeding the LHS controller.

        Returns:
            The named systems added (system name -> system)."""

    def LimitViolation(self) -> Optional[Callable[[np.ndarray], Optional[str]]]:
        """The check of the robot's position limits, for the run's monitor.

        Returns:
            q -> why the joints are beyond the limits (or None); None where the
                robot has no limits to check."""

    def Clearance(self) -> Optional[Callable[[np.ndarray], float]]:
        """The ground truth's link-base clearance, for the run's monitor.

        Returns:
            q -> the clearance [m], or None where the ground truth has no such
                measure."""

    def LiveView(self, loop: "ClosedLoop", meshcat: "Meshcat") -> "viewers.LiveView":
        """Makes a viewers.LiveView drawing the loop's ground truth.

        Args:
            loop: The closed loop (of this robot) being simulated.
            meshcat: The Meshcat to draw into.

        Returns:
            The LiveView."""

    def WriteAnimation(self, logs: Dict[str, np.ndarray], out_html: Union[str, Path]
                       ) -> Path:
        """Writes a self-contained HTML replay of a run's logs.

        Args:
            logs: The run's logs (RunResult.logs).
            out_html: The HTML file to write.

        Returns:
            The HTML file's path."""

    def TaskSignals(self, logs: Dict[str, np.ndarray]) -> Tuple[np.ndarray, ...]:
        """The task's signals over time, for metrics.run_metrics.

        Args:
            logs: The run's logs (RunResult.logs).

        Returns:
            (tracking error, s, link-base clearance [m], base turn [rad])."""

    def TaskMetrics(self, logs: Dict[str, np.ndarray]) -> Dict[str, float]:
        """The task's own metrics beside metrics.run_metrics' shared ones.

        Args:
            logs: The run's logs (RunResult.logs).

        Returns:
            Metric name -> value."""

    def MeasuredMasses(self) -> Tuple[float, float]:
        """The ground truth's total and base mass, as a spacecraft's mass
        properties give them (the inertial identifier's anchor, scenario.inertia).

        Returns:
            (total, base) [kg]."""

    def TotalMass(self) -> float:
        """The ground truth's total mass.

        Returns:
            The mass [kg]."""

    def VerifyLhs(self, logs: Dict[str, np.ndarray], region_budget: float
                  ) -> "LhsSide":
        """What dacph verify checks of this LHS.

        Args:
            logs: The run's logs (RunResult.logs).
            region_budget: The wall time [s] after which the region of
                attraction's program is stopped.

        Returns:
            The analysis.verify.LhsSide."""


# Each robot section (scenario.PlanarArm, scenario.DescribedArm, by class name: the
# scenario module imports this one, not the reverse), the task section its LHS
# tracks, and the module:class of its Robot.
_ROBOTS = {"PlanarArm": ("EndEffectorAngle", "dacph_drake.robots.planar:PlanarRobot"),
           "DescribedArm": ("EndEffectorAttitude",
                            "dacph_drake.robots.described:DescribedRobot")}


def robot_type(scenario: "Scenario") -> type:
    """The class of a scenario's Robot, without building or validating it.

    Its class attributes, such as task_panels, are then at hand.

    Args:
        scenario: A scenario.Scenario.

    Returns:
        robots.planar.PlanarRobot or robots.described.DescribedRobot.

    Raises:
        ConfigError: The task is not the one this robot tracks."""
    robot, given = type(scenario.robot).__name__, type(scenario.task).__name__
    task, path = _ROBOTS[robot]
    if given != task:
        raise ConfigError(f"task: !{given} with robot: !{robot}; allowed: task: !{task} "
                          "(the task this robot's LHS controller tracks)")
    module, name = path.split(":")
    return getattr(importlib.import_module(module), name)


def require_clear_start(q0: Sequence[float],
                        clearance: Optional[Callable[[np.ndarray], float]]) -> None:
    """Requires every link of the ground truth outside the base at q0.

    The ground truth has no contact model: a run started inside the base would go
    on through it (the run's monitor stops one that gets there, with reason
    "collision").

    Args:
        q0: The scenario's start.
        clearance: The robot's Robot.Clearance (None: it measures none).

    Raises:
        ConfigError: q0 puts a link into the base (naming q0 and the clearance)."""
    rho = clearance(np.asarray(q0, float)) if clearance is not None else np.inf
    if rho <= 0:
        raise ConfigError(f"q0 = {list(q0)} puts the arm into the base (clearance "
                          f"{rho:.3f} m); allowed: a configuration with every link "
                          "outside the base")


def robot_of(scenario: "Scenario") -> Robot:
    """Makes the Robot of a scenario, validating the scenario against it.

    Args:
        scenario: A scenario.Scenario.

    Returns:
        Its Robot (robots.planar.PlanarRobot or robots.described.DescribedRobot).

    Raises:
        ConfigError: Naming the first invalid setting."""
    require_setting_types("", scenario)   # a Python user's sections, before any range
    return robot_type(scenario)(scenario)


def robots_of(scenarios: Sequence) -> List[Robot]:
    """Makes the Robot of each trial of a batch (robot_of).

    Args:
        scenarios: The batch's trials.

    Returns:
        Their Robots, all of one type with one number of joints.

    Raises:
        ConfigError: The trials' robots differ in type or number of joints."""
    robots = [robot_of(scenario) for scenario in scenarios]
    kinds = {(type(robot).__name__, robot.num_joints) for robot in robots}
    if len(kinds) > 1:
        raise ConfigError(f"a batch's trials have robots {sorted(kinds)}; allowed: one "
                          "robot type with one number of joints per batch")
    return robots
