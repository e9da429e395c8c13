"""Tasks: what an LHS controller tracks, as its own axis beside the robot
(tasks.task.Task; the registered ones in tasks.registry.TASKS)."""
