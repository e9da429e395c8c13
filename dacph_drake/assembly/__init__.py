"""Where a scenario's typed sections meet their implementations: the robot and task
kinds' registry (registry) and scenario files, read and sized to their robot
(scenario_files)."""
