"""Robots: what a closed loop needs of the arm it controls (robots.robot.Robot; a
scenario's is made by assembly.registry.robot_of)."""
