"""Descriptions as their makers ship them: what Drake's parser refuses or repeats, made
into one line per kind naming the user's file: a material defined twice (the first
kept, a later one a reference or renamed NAME__K), a xacro file (refused with the
command that expands it), parser warnings (logged once per kind and file)."""
import logging
import re
from collections import OrderedDict
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator, List, Tuple

from dacph_drake.scenario.errors import ConfigError

_MATERIAL = re.compile(r'<material\s+name\s*=\s*"([^"]*)"\s*>(.*?)</material>', re.S)
_LOCATION = re.compile(r"^(?:[^:\s]*<literal-string>[^:]*|[^:\s]+\.(?:urdf|sdf|xml)):"
                       r"(\d+):\s*(?:warning:\s*)?")
_QUOTED = re.compile(r"'[^']*'|\"[^\"]*\"")     # names and values within a kind
# Drake's parser warnings on an <inertial> it could not use as written.
_UNPHYSICAL_INERTIA = re.compile(r"condition 'mass > 0' failed|not physically valid|"
                                 r"central inertia", re.I)
_logger = logging.getLogger(__name__)
_reported: set = set()


def refuse_xacro(path: Path, text: str) -> None:
    """Refuses a xacro macro file, naming the command that expands it.

    Args:
        path: The description's path.
        text: Its text.

    Raises:
        ConfigError: The file is a xacro file."""
    if path.name.endswith(".xacro") or "<xacro:" in text:
        expanded = path.name.removesuffix(".xacro")
        expanded = expanded if expanded.endswith(".urdf") else expanded + ".urdf"
        raise ConfigError(
            f"robot.description {str(path)!r} is a xacro macro file, which Drake does "
            f"not expand; allowed: the URDF it expands to, made with `xacro {path} -o "
            f"{path.parent / expanded}` (pip install xacro), named in robot.description")


def without_duplicate_materials(text: str, path: Path) -> Tuple[str, bool]:
    """(text, changed): a URDF with each material name defined once, lines in place.

    Args:
        text: The URDF's text.
        path: Its path (named in the note)."""
    first = {}
    repeated: "OrderedDict[str, List[int]]" = OrderedDict()
    renamed = {}

    def replace(match):
        name, body = match.group(1), match.group(2)
        if name not in first:
            first[name] = body.strip()
            return match.group(0)
        line = text.count("\n", 0, match.start()) + 1
        repeated.setdefault(name, []).append(line)
        blank = "\n" * match.group(0).count("\n")
        if body.strip() == first[name] or not body.strip():
            return f'<material name="{name}"/>' + blank
        renamed[name] = renamed.get(name, 1) + 1
        return (f'<material name="{name}__{renamed[name]}">'
                f'{" ".join(body.split())}</material>' + blank)
    changed = _MATERIAL.sub(replace, text)
    for name, lines in repeated.items():
        _Once(f"{path}: material {name!r} is defined again on {len(lines)} lines "
              f"({_Lines(lines)}): "
              + ("read as the first where the same, renamed where its colour differs"
                 if name in renamed else "each read as the first"))
    return changed, bool(repeated)


@contextmanager
def parser_warnings_once(path: Path) -> Iterator[None]:
    """Logs Drake's parser warnings during a parse once per kind, on exit.

    Args:
        path: The description's path (named in each line)."""
    drake = logging.getLogger("drake")
    kinds: "OrderedDict[str, list]" = OrderedDict()    # kind -> [first text, lines]

    class Collect(logging.Filter):
        def filter(self, record) -> bool:
            message = record.getMessage()
            location = _LOCATION.match(message)
            line = int(location.group(1)) if location else 0
            text = message[location.end():] if location else message
            kind = _QUOTED.sub("'...'", text)
            kinds.setdefault(kind, [text, []])[1].append(line)
            return False
    collect = Collect()
    drake.addFilter(collect)
    try:
        yield
    finally:
        drake.removeFilter(collect)
        for first, lines in kinds.values():
            where = f"{path}:{lines[0]}" if lines[0] else str(path)
            more = (f" ({len(lines)} lines of this kind: {_Lines(lines)})"
                    if len(lines) > 1 else "")
            _Once(f"{where}: {first}{more}")
    for first, lines in kinds.values():
        if _UNPHYSICAL_INERTIA.search(first):     # Drake simulates a substitute body
            where = f"{path}:{lines[0]}" if lines[0] else str(path)
            failed = re.search(r"condition '([^']*)' failed", first)
            raise ConfigError(f"{where}: a link's mass or inertia is not physical "
                              f"(Drake: {failed.group(0) if failed else first.strip()})"
                              "; allowed: mass > 0 and a "
                              "physically valid inertia on every link with an "
                              "<inertial>")


def _Lines(lines: List[int]) -> str:
    shown = ", ".join(str(line) for line in lines[:6])
    return shown + (", ..." if len(lines) > 6 else "")


def _Once(message: str) -> None:
    """Logs a warning once per process (a run parses its description several times)."""
    if message not in _reported:
        _reported.add(message)
        _logger.warning(message)
