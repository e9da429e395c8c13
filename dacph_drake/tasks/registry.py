"""The tasks an LHS controller tracks (task.Task); register() adds one from outside."""
from dacph_drake.scenario import add_section_type
from dacph_drake.tasks.end_effector_angle import END_EFFECTOR_ANGLE
from dacph_drake.tasks.end_effector_attitude import END_EFFECTOR_ATTITUDE
from dacph_drake.tasks.end_effector_pose import END_EFFECTOR_POSE
from dacph_drake.tasks.end_effector_position import END_EFFECTOR_POSITION
from dacph_drake.tasks.task import Task

TASKS = {}


def register(task: Task) -> None:
    """Registers a task: its section becomes a scenario's ``task: !Section``.

    Args:
        task: The Task (its ``section`` the key)."""
    TASKS[task.section] = task
    add_section_type("task", task.section)


for _task in (END_EFFECTOR_ANGLE, END_EFFECTOR_ATTITUDE, END_EFFECTOR_POSE,
              END_EFFECTOR_POSITION):
    register(_task)
