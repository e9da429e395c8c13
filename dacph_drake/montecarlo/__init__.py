"""Monte Carlo sweeps over uncertainty (``dacph sweep``): a sweep file samples the ground
truth around a base scenario; trials run on any concurrent.futures.Executor; every
finished trial's row is persisted at once, so a killed sweep resumes with the same
command. Modules: definition (the sweep file, sampling), trial, store (rows, manifest),
executors, runner (run_sweep), summary."""
