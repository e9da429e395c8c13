"""Saving files so that a reader or a crash never sees half of one."""
import os
from contextlib import contextmanager
from pathlib import Path


@contextmanager
def replaced_atomically(path):
    """Yields a temporary path beside ``path`` (its name + ".tmp"); when the block
    ends without an exception, the temporary file replaces ``path`` in one step
    (os.replace)."""
    path = Path(path)
    temporary = path.with_name(path.name + ".tmp")
    yield temporary
    os.replace(temporary, path)
