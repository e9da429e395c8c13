"""Saving files so that a reader or a crash never sees half of one."""
import os
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator, Union


@contextmanager
def replaced_atomically(path: Union[str, Path]) -> Iterator[Path]:
    """Replaces a file in one step with what a block writes.

    When the block ends without an exception, the temporary file replaces ``path``
    (os.replace).

    Args:
        path: The file to replace.

    Yields:
        A temporary path beside ``path`` to write, its name + ".<pid>.tmp" (so that
            writers in several processes, such as `dacph reproduce --jobs 3` saving the
            one scenario.yaml of a run directory, never share one)."""
    path = Path(path)
    temporary = path.with_name(f"{path.name}.{os.getpid()}.tmp")
    yield temporary
    os.replace(temporary, path)
