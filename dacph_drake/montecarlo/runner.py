"""Running a sweep: the trials not yet saved, handed to an executor (one batch per worker
slot in flight), each row persisted as it arrives, with progress and ETA."""
import sys
from concurrent.futures import FIRST_COMPLETED, Executor, wait
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path
from typing import Dict, Iterator, List, Optional, Union

from dacph_drake.assembly.registry import robot_kind
from dacph_drake.scenario.errors import require_in_range
from dacph_drake.montecarlo.definition import SweepDefinition, sample_trial
from dacph_drake.montecarlo.executors import (default_workers, local_process_pool,
                                              stop_local_pool)
from dacph_drake.montecarlo.store import RowStore, sorted_rows
from dacph_drake.montecarlo.trial import Trial, failed_row, run_trials
from dacph_drake.loop.progress import progress_bar


def run_sweep(definition: SweepDefinition, out_dir: Union[str, Path], executor: Optional[Executor] = None,
              slots: Optional[int] = None, progress: bool = False,
              batch_size: Optional[int] = None) -> List[Dict]:
    """Runs the trials missing from a sweep's directory; returns every trial's row by id. A
    trial whose worker dies runs again alone in a fresh process, and is recorded failed if
    it kills that too. A row's values, wall times aside, do not depend on how it ran.

    Args:
        definition: The loaded sweep (definition.load_sweep).
        out_dir: The sweep's directory; resumed if it holds this sweep, else refused.
        executor: Any concurrent.futures.Executor, or None for a local process pool.
        slots: Batches kept in flight (the pool's workers); default: one per core.
        progress: Show a progress bar.
        batch_size: Trials per diagram; default: batch_size_for(definition)."""
    from dacph_drake.loop.run_store import versions
    slots = slots or default_workers()
    if batch_size is not None:
        require_in_range("batch_size", batch_size, 1, 4096)
    batch_size = batch_size or batch_size_for(definition)
    label = (f"{type(executor).__name__}, {slots} slots" if executor
             else f"local process pool, {slots} workers") + f", batches of {batch_size}"
    store = RowStore(out_dir, definition, versions(), label)
    bar = _Progress(definition.sweep.trials, len(store.rows), progress)
    try:
        pending = [t for t in range(definition.sweep.trials) if t not in store.rows]
        # As many batches as slots at least, so that every worker has one.
        size = max(1, min(batch_size, -(-len(pending) // slots)))
        tasks = ([_task(definition, t, store.out) for t in pending[i:i + size]]
                 for i in range(0, len(pending), size))

        def record(rows: List[Dict]) -> None:
            for row in rows:
                store.append(row)
                bar.update(row)

        if executor is not None:
            _dispatch(executor, tasks, slots, record, recover=False)
        else:
            _run_on_local_pools(tasks, slots, record)
        return sorted_rows(store.rows)
    finally:
        bar.close()
        store.close()


def batch_size_for(definition: SweepDefinition) -> int:
    """The sweep's batch_size if > 0, else its robot kind's (Robot.BATCH_SIZE).

    Args:
        definition: The sweep."""
    if definition.sweep.batch_size > 0:
        return definition.sweep.batch_size
    return robot_kind(definition.scenario.robot).BATCH_SIZE


def _task(definition: SweepDefinition, trial: int, out) -> Trial:
    sample = sample_trial(definition, trial)
    return Trial(trial=trial, seed=sample.seed, scenario=sample.scenario,
                 sampled=sample.sampled, controllers=list(definition.sweep.controllers),
                 log_dir=str(out / "logs") if definition.sweep.save_logs else None,
                 verify=definition.sweep.verify)


def _run_on_local_pools(tasks: Iterator[List[Trial]], workers: int, record) -> None:
    while True:
        pool = local_process_pool(workers)
        try:
            suspects = _dispatch(pool, tasks, workers, record, recover=True)
        except BaseException:       # an interruption: do not wait for running trials
            stop_local_pool(pool)
            raise
        # A worker killed while idle breaks no future, but would keep the
        # interpreter from exiting: such a pool's other workers are stopped.
        if any(not worker.is_alive() for worker in (pool._processes or {}).values()):
            stop_local_pool(pool)
        else:       # joined here: at the interpreter's exit a Ctrl-C would hit the join
            pool.shutdown(wait=True, cancel_futures=True)
        if not suspects:
            return
        print(f"\na worker process died: trials "
              f"{[t.trial for batch in suspects for t in batch]} run again, "
              "each alone in a new process", file=sys.stderr)
        for task in (task for batch in suspects for task in batch):
            record([_run_alone(task)])


def _run_alone(task: Trial) -> Dict:
    """A trial that was running when a worker died, in a process of its own."""
    pool = local_process_pool(1)
    try:
        row = pool.submit(run_trials, [task]).result()[0]
    except BrokenProcessPool:
        row = failed_row(task, "the worker process died while running this trial, also "
                               "when run alone")
    except BaseException:
        stop_local_pool(pool)
        raise
    pool.shutdown(wait=False)
    return row


def _dispatch(executor: Executor, tasks: Iterator[List[Trial]], slots: int, record,
              recover: bool) -> List[List[Trial]]:
    """Keeps ``slots`` batches in flight, recording rows as they arrive. Returns [] when
    done, or, with ``recover``, the batches in flight when the process pool broke."""
    in_flight = {}
    while True:
        while len(in_flight) < slots:
            task = next(tasks, None)
            if task is None:
                break
            in_flight[executor.submit(run_trials, task)] = task
        if not in_flight:
            return []
        done, _ = wait(in_flight, return_when=FIRST_COMPLETED)
        for future in done:
            task = in_flight.pop(future)
            try:
                record(future.result())
            except BrokenProcessPool:
                if not recover:
                    raise
                in_flight[future] = task
                return _salvage(in_flight, record)
            except Exception as e:
                if type(e).__name__ != "KilledWorker":      # Dask gave up on the trial
                    raise
                record([failed_row(trial, f"KilledWorker: {e}") for trial in task])


def _salvage(in_flight: Dict, record) -> List[List[Trial]]:
    """Records a broken pool's finished batches; returns the other batches."""
    suspects = []
    for future, task in in_flight.items():
        if future.done() and future.exception() is None:
            record(future.result())
        else:
            suspects.append(task)
    return suspects


class _Progress:
    """The sweep's bar: trials done / total, failed, rate and ETA."""

    def __init__(self, total: int, done: int, enabled: bool):
        if enabled and done:
            sys.stderr.write(f"resuming: {done} of {total} trials already done\n")
        self._bar = progress_bar(total, "sweep", "trial", enabled, initial=done)
        self._failed = 0

    def update(self, row: Dict) -> None:
        self._failed += row["status"] != "ok"
        self._bar.set_postfix(failed=self._failed, refresh=False)
        self._bar.update(1)

    def close(self) -> None:
        self._bar.close()
