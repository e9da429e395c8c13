"""The closed loop every robot and controller shares: the builder (closed_loop),
the simulation (simulate) and the run layout (run_store), with Drake's simulator
settings (simulator), the progress bar and atomic files."""
