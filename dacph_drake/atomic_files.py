"""Saving files so that a reader or a crash never sees half of one, and reading
them back so that a damaged one is named."""
import json
import os
from contextlib import contextmanager
from pathlib import Path
from typing import Dict, Iterator, Sequence, Union

from dacph_drake.scenario.errors import ConfigError


def prepare_out_dir(out_dir: Union[str, Path]) -> Path:
    """Creates a run directory, checked writable before any run; returns its Path.

    Args:
        out_dir: The directory (created with its parents if missing).

    Raises:
        ConfigError: It is a file, cannot be created or is not writable (naming it)."""
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
    """Replaces ``path`` in one step (os.replace) with what the block writes, if it raises
    nothing; yields the temporary path beside it (name + ".<pid>.tmp").

    Args:
        path: The file to replace."""
    path = Path(path)
    temporary = path.with_name(f"{path.name}.{os.getpid()}.tmp")
    yield temporary
    os.replace(temporary, path)


def read_json_record(path: Union[str, Path], keys: Sequence[str], written_by: str
                     ) -> Dict:
    """Reads a JSON object this project saved, naming the file when damaged.

    Args:
        path: The file.
        keys: The keys every such record has.
        written_by: What writes such a file, for the message.

    Raises:
        ConfigError: The file is unreadable, not JSON, or not an object with ``keys``."""
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
