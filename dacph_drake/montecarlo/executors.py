"""Where trials run: any ``concurrent.futures.Executor``; here a local process pool (the
default), this process, and a Dask cluster (extra ``dacph-drake[dask]``)."""
import ctypes
import multiprocessing
import os
import signal
import sys
from concurrent.futures import Executor, Future, ProcessPoolExecutor
from contextlib import contextmanager
from typing import Callable, Iterator, Optional, Tuple

from dacph_drake.scenario.errors import ConfigError

THREAD_VARIABLES = ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS")


class InProcessExecutor(Executor):
    """Runs each submitted call at once, in this process."""

    def submit(self, fn: Callable, /, *args: object, **kwargs: object) -> Future:
        """Runs a call now; returns its finished Future.

        Args:
            fn: The function.
            *args: Its positional arguments.
            kwargs: Its keyword arguments."""
        future = Future()
        try:
            future.set_result(fn(*args, **kwargs))
        except Exception as e:   # noqa: BLE001 -- delivered through the future
            future.set_exception(e)
        return future


def local_process_pool(workers: int) -> ProcessPoolExecutor:
    """A process pool of fresh ('spawn') single-threaded workers ending with this process.

    Args:
        workers: The number of worker processes."""
    return ProcessPoolExecutor(max_workers=workers,
                               mp_context=multiprocessing.get_context("spawn"),
                               initializer=_prepare_worker, initargs=(os.getpid(),))


def stop_local_pool(pool: ProcessPoolExecutor) -> None:
    """Shuts a pool down at once: its workers killed, the queued trials cancelled.

    Args:
        pool: The pool (local_process_pool)."""
    if hasattr(pool, "terminate_workers"):      # Python >= 3.14
        pool.terminate_workers()
        return
    for process in list((pool._processes or {}).values()):   # no public way before 3.14
        process.kill()
    pool.shutdown(wait=False, cancel_futures=True)


def _prepare_worker(parent: int) -> None:
    """One thread per library; on Linux, SIGKILL this worker when its parent dies."""
    for name in THREAD_VARIABLES:
        os.environ[name] = "1"
    if sys.platform.startswith("linux"):
        PR_SET_PDEATHSIG = 1
        ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGKILL)
    if os.getppid() != parent:      # the parent died before prctl
        os._exit(1)


def default_workers() -> int:
    """One worker per core this process may use."""
    return len(os.sched_getaffinity(0))


# [s] how long dask_executor waits for a scheduler to answer.
CONNECT_TIMEOUT = 10.0


@contextmanager
def dask_executor(address: str, workers: Optional[int] = None,
                  timeout: float = CONNECT_TIMEOUT) -> Iterator[Tuple[Executor, int]]:
    """Opens a Dask executor, yielding (executor, worker slots); each worker must have one
    thread (torch's state and thread settings are per process).

    Args:
        address: The scheduler's address, or "local" for a new single-threaded LocalCluster.
        workers: The LocalCluster's worker processes (default: one per core).
        timeout: How long to wait for the scheduler at ``address`` [s].

    Raises:
        ConfigError: No Dask, a bad or silent address, or no or multi-threaded workers."""
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError as e:
        raise ConfigError("--dask needs Dask: pip install 'dacph-drake[dask]'") from e
    cluster = None
    if address == "local":
        cluster = LocalCluster(n_workers=workers or default_workers(), threads_per_worker=1,
                               processes=True, dashboard_address=None)
        client = Client(cluster)
    else:
        allowed = "allowed: a running scheduler's address such as tcp://host:8786, or local"
        try:
            client = Client(address, timeout=timeout)
        except OSError as e:
            raise ConfigError(f"--dask {address}: no scheduler answered within "
                              f"{timeout:g} s; {allowed}") from e
        except (ValueError, TypeError) as e:
            raise ConfigError(f"--dask {address} is not a scheduler address "
                              f"({str(e).splitlines()[0]}); {allowed}") from e
    try:
        threads = client.nthreads()
        if not threads:
            raise ConfigError(f"--dask {address}: the cluster has no workers; allowed: a "
                              "cluster with at least one worker")
        crowded = {w: n for w, n in threads.items() if n != 1}
        if crowded:
            raise ConfigError(f"--dask {address}: workers {crowded} run several threads; "
                              "allowed: 1 thread per worker (dask worker --nthreads 1)")
        executor = client.get_executor()
        try:
            yield executor, len(threads)
        finally:
            executor.shutdown(wait=False)   # cancels what an interruption left running
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
