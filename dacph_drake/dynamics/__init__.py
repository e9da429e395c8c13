"""The reduced models of free-floating arms at zero momentum (the planar closed form,
any plant's by AutoDiff), their inertial parameters and bounds, and the port's true
RHS model."""
