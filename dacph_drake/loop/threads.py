"""One thread for the numerical libraries while a closed loop runs.

The loop multiplies matrices of a few rows thousands of times a second: BLAS and
OpenMP thread pools gain nothing there, and with another process on the machine
their spinning threads made an 8 s Panda DAC run take 22-30 s instead of 4.4 s
(docs/results/performance.md). Sweep workers get one thread from their
environment (montecarlo.executors); single runs and the API get it here, at run
time, whatever the caller's environment says, and give the caller's settings
back afterwards."""
import sys
from contextlib import contextmanager
from typing import Iterator

from threadpoolctl import threadpool_limits


@contextmanager
def single_threaded() -> Iterator[None]:
    """Limits BLAS, OpenMP and torch's intra-op pool to one thread inside the block.

    Yields:
        Nothing; the previous limits are restored on exit."""
    torch = sys.modules.get("torch")        # not imported for it: torch loads slowly
    previous = torch.get_num_threads() if torch is not None else None
    with threadpool_limits(limits=1):
        if torch is not None:
            torch.set_num_threads(1)
        try:
            yield
        finally:
            if torch is not None:
                torch.set_num_threads(previous)
