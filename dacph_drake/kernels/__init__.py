"""Compiled (numba, cached on disk) kernels of the closed loop's fast path.

Each kernel computes what a Python/Drake reference in the package computes, to
round-off (tests/test_kernels.py): arm.py the reduced model
(reduced_model.ReducedOrderModel), potential.py the null-space potential
(potential.BaseRepulsionPotential), loop.py the LHS control law, the true RHS with
d(t), and the RHS sample (observer and integrator). The systems call them once per
update with plain arrays, so a callback costs a few microseconds."""
