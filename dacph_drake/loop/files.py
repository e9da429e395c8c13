"""Saving files so that a reader or a crash never sees half of one, and reading
them back so that a damaged one is named."""
import json
import os
from contextlib import contextmanager
from pathlib import Path
from typing import Dict, Iterator, Sequence, Union

from dacph_drake.errors import ConfigError


def prepare_out_dir(out_dir: Union[str, Path]) -> Path:
    """Creates a run directory and checks it is writable, before any simulation.

    Args:
        out_dir: The directory (created with its parents if missing).

    Returns:
        It, as a Path.

    Raises:
        ConfigError: It is a file, cannot be created or is not writable (naming
            the path)."""
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise ConfigError(f"--out = {str(out)!r} is an existing file; allowed: a "
                          "directory (created if missing)")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise ConfigError(f"--out = {str(out)!r} cannot be created ({e.strerror}); "
                          "allowed: a writable directory") from e
    if not os.access(out, os.W_OK | os.X_OK):
        raise ConfigError(f"--out = {str(out)!r} is not writable; allowed: a writable "
                          "directory")
    return out


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


def read_json_record(path: Union[str, Path], keys: Sequence[str], written_by: str
                     ) -> Dict:
    """Reads a JSON object this project saved (run_CONTROLLER.json, a sweep's
    manifest.json), naming the file when it is damaged.

    Args:
        path: The file.
        keys: The keys every such record has.
        written_by: What writes such a file, for the message.

    Returns:
        The record.

    Raises:
        ConfigError: The file cannot be read, is not JSON, or is not an object with
            ``keys`` (one line naming the file)."""
    try:
        record = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, ValueError) as e:         # UnicodeDecodeError is a ValueError
        raise ConfigError(f"{path} is damaged ({e}); allowed: a file saved by "
                          f"{written_by}") from e
    missing = ([key for key in keys if key not in record] if isinstance(record, dict)
               else list(keys))
    if missing:
        raise ConfigError(f"{path} is damaged (no {', '.join(missing)}); allowed: a "
                          f"file saved by {written_by}")
    return record
