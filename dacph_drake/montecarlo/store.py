"""A sweep's output directory, also its resume state: rows.jsonl (one fsync'ed row per
finished trial), sweep.yaml and scenario.yaml, manifest.json (fingerprint and sessions). A
truncated last line is dropped on reopening; a lock keeps a second sweep out."""
import fcntl
import json
import os
import sys
import time
from pathlib import Path
from typing import Dict, List, Union

from dacph_drake.scenario.errors import ConfigError
from dacph_drake.atomic_files import prepare_out_dir, read_json_record, replaced_atomically
from dacph_drake.montecarlo.definition import SweepDefinition
from dacph_drake.assembly.scenario_files import save_scenario

ROWS, MANIFEST = "rows.jsonl", "manifest.json"


def read_rows(out_dir: Union[str, Path]) -> Dict[int, Dict]:
    """Trial id -> row of every complete line of a sweep's rows.

    Args:
        out_dir: The sweep's directory (its rows.jsonl).

    Raises:
        ConfigError: A complete line is not a JSON row, or a trial appears twice."""
    rows, _ = _parse_rows(Path(out_dir) / ROWS)
    return rows


def _parse_rows(path: Path):
    """(rows, number of bytes of complete lines)."""
    data = path.read_bytes() if path.exists() else b""
    complete = data.rfind(b"\n") + 1
    rows: Dict[int, Dict] = {}
    for number, line in enumerate(data[:complete].splitlines(), start=1):
        try:
            row = json.loads(line)
        except json.JSONDecodeError as e:
            raise ConfigError(f"{path}: line {number} is not a JSON row ({e}); allowed: "
                              "one row per line (only the last line may be cut short)")
        if row["trial"] in rows:
            raise ConfigError(f"{path}: trial {row['trial']} appears twice (line "
                              f"{number}); allowed: one row per trial")
        rows[row["trial"]] = row
    return rows, complete


def read_manifest(out_dir: Union[str, Path], definition: SweepDefinition) -> Dict:
    """Reads a sweep's manifest.json, after checking which sweep created it.

    Args:
        out_dir: The sweep's directory.
        definition: The sweep that must have created it.

    Raises:
        ConfigError: The directory holds no sweep, another sweep's, or a damaged one."""
    path = Path(out_dir) / MANIFEST
    if not path.exists():
        raise ConfigError(f"{out_dir} holds no sweep ({MANIFEST} is missing); allowed: a "
                          "sweep's output directory")
    manifest = read_json_record(path, ("fingerprint", "sessions"), "dacph sweep")
    if manifest["fingerprint"] not in definition.fingerprints():
        raise ConfigError(
            f"{out_dir} holds a different sweep (its sweep.yaml and scenario.yaml differ "
            f"from {definition.source} and its scenario); allowed: the sweep that created "
            "it, or a new output directory")
    return manifest


def _require_no_run(out: Path) -> None:
    """Refuses a directory with a run but no sweep (its scenario.yaml would go)."""
    if (out / MANIFEST).exists():
        return
    run = sorted(p.name for p in out.iterdir()
                 if p.name.startswith(("run_", "logs_")) or (
                     p.name == "scenario.yaml" and not (out / "sweep.yaml").exists()))
    if run:
        raise ConfigError(f"--out = {str(out)!r} holds a run ({', '.join(run)}); "
                          "allowed: a sweep's directory (to resume it) or a new one")


class RowStore:
    """A sweep's output directory, opened (created or resumed) for one session.

    Args:
        out_dir: The directory.
        definition: The sweep (a directory holding another sweep is refused).
        versions: The library versions of the session (run_store.versions).
        executor: A label of the executor, for the manifest.

    Raises:
        ConfigError: The directory is in use, holds another sweep, or lacks a manifest."""

    def __init__(self, out_dir: Union[str, Path], definition: SweepDefinition,
                 versions: Dict[str, str], executor: str):
        self.out = prepare_out_dir(out_dir)
        _require_no_run(self.out)
        self._fd = os.open(self.out / ROWS, os.O_RDWR | os.O_CREAT | os.O_APPEND, 0o644)
        try:
            fcntl.flock(self._fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            os.close(self._fd)
            raise ConfigError(f"{self.out} is in use by another running sweep; allowed: "
                              "one sweep per output directory at a time")
        try:
            self._open_manifest(definition, versions, executor)
            self.rows, complete = _parse_rows(self.out / ROWS)
        except BaseException:
            self.close()
            raise
        os.ftruncate(self._fd, complete)     # drop a truncated last line

    def _open_manifest(self, definition: SweepDefinition, versions, executor) -> None:
        path = self.out / MANIFEST
        session = {"started": time.strftime("%Y-%m-%dT%H:%M:%S%z"), "executor": executor,
                   "versions": versions}
        if path.exists():
            manifest = read_manifest(self.out, definition)
            first = manifest["sessions"][0]["versions"]
            if first != versions:
                print(f"warning: {self.out} was started with {first}, this session has "
                      f"{versions}: rows of the two may differ", file=sys.stderr)
            manifest["sessions"].append(session)
        elif os.path.getsize(self.out / ROWS) > 0:
            raise ConfigError(f"{self.out} has rows.jsonl but no {MANIFEST}; allowed: a "
                              "sweep's output directory or a new one")
        else:
            (self.out / "sweep.yaml").write_text(definition.text)
            save_scenario(definition.scenario, self.out / "scenario.yaml")
            manifest = {"fingerprint": definition.fingerprint(),
                        "sweep_file": str(definition.source), "sessions": [session]}
        _write_atomically(path, json.dumps(manifest, indent=2))

    def append(self, row: Dict) -> None:
        """Persists (fsyncs) one finished trial's row before returning.

        Args:
            row: The trial's row (its "trial" entry the trial id)."""
        os.write(self._fd, (json.dumps(row, sort_keys=True) + "\n").encode())
        os.fsync(self._fd)
        self.rows[row["trial"]] = row

    def close(self) -> None:
        """Closes the rows file and releases the directory's lock."""
        if self._fd >= 0:
            os.close(self._fd)      # also releases the lock
            self._fd = -1


def _write_atomically(path: Path, text: str) -> None:
    with replaced_atomically(path) as temporary:
        temporary.write_text(text)


def sorted_rows(rows: Dict[int, Dict]) -> List[Dict]:
    """The rows in trial order.

    Args:
        rows: Trial id -> row."""
    return [rows[t] for t in sorted(rows)]
