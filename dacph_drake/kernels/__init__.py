"""Compiled (numba, cached on disk) kernels of the closed loop's fast path, each equal to
round-off to a Python/Drake reference in the package (tests/test_kernels.py), called
once per update with plain arrays."""
