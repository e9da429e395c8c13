"""One thread for the numerical libraries while a closed loop runs: on matrices of a few
rows, BLAS and OpenMP pools gain nothing and their spinning threads slow the loop
several times beside another process. Sweep workers get one thread from their
environment (montecarlo.executors); single runs and the API get it here, and the
caller's settings are restored afterwards."""
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
