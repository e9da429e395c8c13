"""Tasks: what an LHS controller tracks, beside the robot (task.Task; registry.TASKS)."""
