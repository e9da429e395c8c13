"""Saving files so that a reader or a crash never sees half of one."""
import os
from contextlib import contextmanager
from pathlib import Path


@contextmanager
def replaced_atomically(path):
    """Yields a temporary path beside ``path`` (its name + ".<pid>.tmp": writers in
    several processes, such as `dacph reproduce --jobs 3` saving the one
    scenario.yaml of a run directory, never share one); when the block ends
    without an exception, the temporary file replaces ``path`` in one step
    (os.replace)."""
    path = Path(path)
    temporary = path.with_name(f"{path.name}.{os.getpid()}.tmp")
    yield temporary
    os.replace(temporary, path)
