"""The one place a scenario's typed sections meet their implementations: the robot
section's Robot (robots.robot.Robot) and the task section's Task (tasks.TASKS),
checked to be a pair that works together."""
from typing import List, Sequence

from dacph_drake.errors import ConfigError, require_setting_types
from dacph_drake.robots.described import DescribedRobot
from dacph_drake.robots.planar import PlanarRobot
from dacph_drake.robots.robot import Robot
from dacph_drake.scenario import DescribedArm, PlanarArm, Scenario
from dacph_drake.tasks.registry import TASKS
from dacph_drake.tasks.task import Task

ROBOTS = {PlanarArm: PlanarRobot, DescribedArm: DescribedRobot}


def task_of(scenario: Scenario) -> Task:
    """The scenario's Task, checked against its robot section.

    Args:
        scenario: The scenario.

    Raises:
        ConfigError: The robot cannot serve the task (naming the tasks it can)."""
    task = TASKS.get(type(scenario.task))
    robot = type(scenario.robot)
    if task is None or robot not in task.robots:
        allowed = ", ".join(f"!{t.section.__name__}" for t in TASKS.values()
                            if robot in t.robots)
        raise ConfigError(f"task: !{type(scenario.task).__name__} with robot: "
                          f"!{robot.__name__}; allowed: task: {allowed} (the tasks "
                          "this robot serves)")
    return task


def robot_of(scenario: Scenario) -> Robot:
    """Makes a scenario's Robot (serving its Task), validating the scenario.

    Args:
        scenario: The scenario.

    Raises:
        ConfigError: Naming the first invalid setting."""
    require_setting_types("", scenario)   # a Python user's sections, before any range
    return ROBOTS[type(scenario.robot)](scenario, task_of(scenario))


def robots_of(scenarios: Sequence[Scenario]) -> List[Robot]:
    """The Robot of each trial of a batch, all of one type and joint count.

    Args:
        scenarios: The batch's trials.

    Raises:
        ConfigError: The trials' robots differ in type or number of joints."""
    robots = [robot_of(scenario) for scenario in scenarios]
    kinds = {(type(robot).__name__, robot.num_joints) for robot in robots}
    if len(kinds) > 1:
        raise ConfigError(f"a batch's trials have robots {sorted(kinds)}; allowed: one "
                          "robot type with one number of joints per batch")
    return robots


def validate_scenario(scenario: Scenario) -> None:
    """Checks every setting (the robot's constructor checks the seed, the robot and
    its task: scenario.checks.validate_shared).

    Args:
        scenario: The scenario.

    Raises:
        ConfigError: Naming the first invalid setting and its allowed range."""
    robot_of(scenario)
