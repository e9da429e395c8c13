"""Verification of the paper's Lyapunov claims on any run (``dacph verify``)."""
