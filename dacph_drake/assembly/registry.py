"""The sections' kinds: ROBOTS, tasks.TASKS (checked to pair) and learning.LEARNERS."""
from typing import List, Optional, Sequence, Type

from dacph_drake.scenario.errors import ConfigError, require_setting_types
from dacph_drake.learning import learner_kind
from dacph_drake.robots.described import DescribedRobot
from dacph_drake.robots.planar import PlanarRobot
from dacph_drake.robots.robot import Robot
from dacph_drake.scenario import (DescribedArm, EndEffectorAttitude, PlanarArm, Scenario,
                                  add_section_type)
from dacph_drake.scenario.built_in import described_arm_periods
from dacph_drake.scenario.checks import validate_start
from dacph_drake.tasks.registry import TASKS
from dacph_drake.tasks.task import Task

ROBOTS = {PlanarArm: PlanarRobot, DescribedArm: DescribedRobot}


def register_robot(section: type, kind: Type[Robot]) -> None:
    """Registers a robot kind: its section becomes a scenario's ``robot: !Section``.

    Args:
        section: The robot section's dataclass.
        kind: Its Robot class (serving the tasks whose ``robots`` name it or a base)."""
    ROBOTS[section] = kind
    add_section_type("robot", section)


def robot_kind(section: object) -> Type[Robot]:
    """The Robot class of a robot section (ROBOTS).

    Args:
        section: The robot section."""
    return ROBOTS[type(section)]


def task_of(scenario: Scenario) -> Task:
    """The scenario's Task, checked against its robot section.

    Args:
        scenario: The scenario.

    Raises:
        ConfigError: The robot cannot serve the task (naming the tasks it can)."""
    return _task_kind(scenario.robot, scenario.task)


def _task_kind(robot: object, task: object) -> Task:
    """The Task of a task section that the robot section can serve (task_of)."""
    kind, robot_class = TASKS.get(type(task)), robot_kind(robot)
    if kind is None or not issubclass(robot_class, kind.robots):
        allowed = ", ".join(f"!{t.section.__name__}" for t in TASKS.values()
                            if issubclass(robot_class, t.robots))
        raise ConfigError(f"task: !{type(task).__name__} with robot: "
                          f"!{type(robot).__name__}; allowed: task: {allowed} (the tasks "
                          "this robot serves)")
    return kind


def robot_of(scenario: Scenario) -> Robot:
    """Makes a scenario's Robot (serving its Task), validating the scenario.

    Args:
        scenario: The scenario.

    Raises:
        ConfigError: Naming the first invalid setting."""
    require_setting_types("", scenario)   # a Python user's sections, before any range
    learner_kind(scenario.learner)        # a registered learner.model
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
    """Checks every setting (the robot's constructor: scenario.checks.validate_shared).

    Args:
        scenario: The scenario.

    Raises:
        ConfigError: Naming the first invalid setting and its allowed range."""
    robot_of(scenario)


def sized_defaults(robot: object, q0: Optional[Sequence[float]],
                   task: Optional[object]) -> Optional[Scenario]:
    """Robot.SizedScenario: the scenario a file naming this robot starts from, or None.

    Args:
        robot: The file's robot section.
        q0: The file's q0 [rad] (None where it leaves it out).
        task: The file's task (None where it leaves it out)."""
    validate_given(q0, task)
    kind = _task_kind(robot, task) if task is not None else TASKS[EndEffectorAttitude]
    return robot_kind(robot).SizedScenario(robot, q0, task,
                                           getattr(kind, "jacobian_rows", ()))


def validate_given(q0: Optional[Sequence[float]], task: Optional[object]) -> None:
    """Checks a file's q0 and task before sizing, a start-pose search or a plant reads them.

    Args:
        q0: The file's q0 [rad] (None where it leaves it out).
        task: The file's task (None where it leaves it out).

    Raises:
        ConfigError: Naming the first bad setting."""
    if q0 is not None:
        validate_start(q0)
    if task is not None and type(task) in TASKS:
        TASKS[type(task)].Validate(task, described_arm_periods())
