"""Where trials run: any ``concurrent.futures.Executor``. Provided here: a local
process pool (the default), this process (debugging, tests), and a Dask cluster
(optional extra: ``pip install 'dacph-drake[dask]'``)."""
import ctypes
import multiprocessing
import os
import signal
import sys
from concurrent.futures import Executor, Future, ProcessPoolExecutor
from contextlib import contextmanager
from typing import Optional

from dacph_drake.errors import ConfigError

THREAD_VARIABLES = ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS")


class InProcessExecutor(Executor):
    """Runs each submitted call at once, in this process."""

    def submit(self, fn, /, *args, **kwargs) -> Future:
        """Runs fn(*args, **kwargs) now and returns its finished Future."""
        future = Future()
        try:
            future.set_result(fn(*args, **kwargs))
        except Exception as e:   # noqa: BLE001 -- delivered through the future
            future.set_exception(e)
        return future


def local_process_pool(workers: int) -> ProcessPoolExecutor:
    """``workers`` fresh processes ('spawn': no forked copy of this process's torch or
    Drake threads), each with one thread for OpenMP, MKL and OpenBLAS, and each
    ending with this process even when it is killed."""
    return ProcessPoolExecutor(max_workers=workers,
                               mp_context=multiprocessing.get_context("spawn"),
                               initializer=_prepare_worker, initargs=(os.getpid(),))


def stop_local_pool(pool: ProcessPoolExecutor) -> None:
    """Shuts ``pool`` down without waiting for the trials it is running: kills its
    workers and cancels the queued trials (an interrupted sweep returns at once)."""
    if hasattr(pool, "terminate_workers"):      # Python >= 3.14
        pool.terminate_workers()
        return
    for process in list((pool._processes or {}).values()):   # no public way before 3.14
        process.kill()
    pool.shutdown(wait=False, cancel_futures=True)


def _prepare_worker(parent: int) -> None:
    """One thread per library that reads these variables when it loads (torch loads
    with the first trial); on Linux, ask the kernel to SIGKILL this worker when its
    parent dies (a parent killed with -9 leaves no worker running)."""
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


@contextmanager
def dask_executor(address: str, workers: Optional[int] = None):
    """(executor, number of worker slots) on the Dask cluster at ``address``
    (``Client(address).get_executor()``), or on a new LocalCluster of ``workers``
    single-threaded worker processes when address is "local". Each worker must have
    one thread: torch's random state and thread settings are per process."""
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
        client = Client(address)
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
