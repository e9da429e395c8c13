"""Monte Carlo sweeps over uncertainty (``dacph sweep``): a sweep file samples the
ground truth around a base scenario; trials run on any concurrent.futures.Executor
(a local process pool by default, or a Dask cluster); every finished trial's row is
persisted at once, so a killed sweep resumes with the same command.

    definition.py  the sweep file and the sampling of a trial from (seed, trial id)
    trial.py       one trial as a worker runs it: scenario in, row out
    store.py       the output directory: rows.jsonl, manifest, resume
    executors.py   local process pool, in-process, Dask
    runner.py      run_sweep: dispatch, persistence, progress
    summary.py     quantiles, success rates, paired comparison, Parquet, plots

Import from the modules (workers import only what a trial needs).
"""
