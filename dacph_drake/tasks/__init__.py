"""The tasks an LHS controller tracks: the planar end-effector angle's reference and
the 3D attitude's error and rates."""
