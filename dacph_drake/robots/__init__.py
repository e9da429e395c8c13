"""Robots: what a closed loop needs of the robot it controls, for every robot alike.

A scenario's ``robot:`` section is one of two typed variants (scenario.PlanarArm,
scenario.DescribedArm) and its ``task:`` one of two (scenario.EndEffectorAngle,
scenario.EndEffectorAttitude); ``robot_of(scenario)`` is the one place that
dispatches on them, returning an object with the Robot protocol below
(robots.planar.PlanarRobot, robots.described.DescribedRobot). The loop builder
(loop.closed_loop), ``loop.simulate``, the metrics, the figures, ``dacph verify``
and the animations use that protocol only."""
import importlib
from typing import (TYPE_CHECKING, Callable, Dict, List, Optional, Protocol, Sequence,
                    Tuple)

import numpy as np

from dacph_drake.dynamics import ReducedModel
from dacph_drake.errors import ConfigError

if TYPE_CHECKING:
    from dacph_drake.scenario import Scenario


class Robot(Protocol):
    """A robot and its task, as the loop builder and the tools use it."""
    scenario: object                # the scenario.Scenario it was made from
    num_joints: int
    model: ReducedModel             # the controller's model (its inertias nominal)
    lhs_name: str                   # the LHS controller's system name
    lhs_log: str                    # the name of its log output
    task_panels: Tuple[str, ...]    # figures.make_panels' panels of this task

    @classmethod
    def AddGroundTruth(cls, builder, trials: Sequence["Robot"]) -> Tuple[object, object]:
        """Adds the ground-truth MultibodyPlant ("plant") of a batch of ``trials``
        (each trial's Robot; one: a single run) and its SceneGraph."""

    @classmethod
    def MakeTrueRhs(cls, plant, trials: Sequence["Robot"]):
        """The port's true RHS system of the ``trials`` for their ``plant`` (inputs
        u, state, disturbance_model; outputs tau, true_matrices; stacked)."""

    def RequireRunnableStart(self) -> None:
        """ConfigError unless a run can start at the scenario's q0."""

    def GainRuleRates(self) -> Tuple[float, float]:
        """(lambda_max(K_d), inf_q lambda_min(M)) of the LHS for eq. (48)."""

    @classmethod
    def AddLhsController(cls, controller, trials: Sequence["Robot"], excitation,
                         identify: bool) -> Dict:
        """Adds the LHS controller of the ``trials`` (outputs tau_request,
        reduced_model and its log; input chi; stacked) and, with ``identify``, an
        InertialIdentifier feeding it, into the controller's builder; returns the
        named systems."""

    def LimitViolation(self) -> Optional[Callable[[np.ndarray], Optional[str]]]:
        """q -> why the joints are beyond the robot's position limits (or None),
        for the run's monitor; None where the robot has no limits to check."""

    def Clearance(self) -> Optional[Callable[[np.ndarray], float]]:
        """q -> the ground truth's link-base clearance [m] for the run's monitor,
        or None where the ground truth has no such measure."""

    def LiveView(self, loop, meshcat):
        """An animation.LiveView drawing the loop's ground truth."""

    def WriteAnimation(self, logs, out_html):
        """A self-contained HTML replay of a run's logs."""

    def TaskSignals(self, logs) -> Tuple[np.ndarray, ...]:
        """(tracking error, s, link-base clearance [m], base turn [rad]) over time."""

    def TaskMetrics(self, logs) -> Dict[str, float]:
        """The task's own metrics beside metrics.run_metrics' shared ones."""

    def TotalMass(self) -> float:
        """The ground truth's total mass [kg]."""

    def VerifyLhs(self, logs, region_budget: float):
        """analysis.verify.LhsSide: what dacph verify checks of this LHS (the
        region of attraction's program stopped after region_budget seconds)."""


# Each robot section (scenario.PlanarArm, scenario.DescribedArm, by class name: the
# scenario module imports this one, not the reverse), the task section its LHS
# tracks, and the module:class of its Robot.
_ROBOTS = {"PlanarArm": ("EndEffectorAngle", "dacph_drake.robots.planar:PlanarRobot"),
           "DescribedArm": ("EndEffectorAttitude",
                            "dacph_drake.robots.described:DescribedRobot")}


def robot_type(scenario):
    """The class of ``scenario``'s Robot (its class attributes, such as
    task_panels, without building or validating it); ConfigError when the task is
    not the one this robot tracks."""
    robot, given = type(scenario.robot).__name__, type(scenario.task).__name__
    task, path = _ROBOTS[robot]
    if given != task:
        raise ConfigError(f"task: !{given} with robot: !{robot}; allowed: task: !{task} "
                          "(the task this robot's LHS controller tracks)")
    module, name = path.split(":")
    return getattr(importlib.import_module(module), name)


def robot_of(scenario: "Scenario") -> Robot:
    """Makes the Robot of a scenario, validating the scenario against it.

    Args:
        scenario: A scenario.Scenario.

    Returns:
        Its Robot (robots.planar.PlanarRobot or robots.described.DescribedRobot).

    Raises:
        ConfigError: Naming the first invalid setting."""
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
