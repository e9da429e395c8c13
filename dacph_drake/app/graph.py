"""Rendering a diagram's graph with Drake's Graphviz export and the ``dot`` program."""
import re
import shutil
import subprocess
from pathlib import Path
from typing import TYPE_CHECKING, List, Union

from dacph_drake.atomic_files import prepare_out_dir

if TYPE_CHECKING:
    from pydrake.systems.framework import Diagram

_ID = re.compile(r"(digraph _|clusters|cluster|\bs)(\d+)")


def diagram_graphviz(diagram: "Diagram", max_depth: int = 2) -> str:
    """Drake's Graphviz source of ``diagram``, ids renumbered and edges sorted.

    Args:
        diagram: The diagram.
        max_depth: How many levels deep (2: the controller sub-diagram's systems shown)."""
    ids = {}

    def renumber(match):
        ids.setdefault(match.group(2), str(len(ids)))
        return match.group(1) + ids[match.group(2)]

    lines = _ID.sub(renumber, diagram.GetGraphvizString(max_depth=max_depth)).split("\n")
    # Sort each run of consecutive edge lines in place: an edge stays in the
    # (sub)graph block that declares it, which decides the cluster of its nodes.
    run = []
    for i in range(len(lines) + 1):
        if i < len(lines) and " -> " in lines[i]:
            run.append(i)
            continue
        for row, line in zip(run, sorted(lines[r] for r in run)):
            lines[row] = line
        run = []
    return "\n".join(lines)


def _dot() -> str:
    dot = shutil.which("dot")
    if dot is None:
        raise RuntimeError("graphviz's 'dot' program is not installed; run "
                           "scripts/setup.sh (it installs graphviz)")
    return dot


def render_diagram(diagram: "Diagram", stem: Union[str, Path]) -> List[Path]:
    """Writes stem.dot, stem.svg and stem.png; returns their paths.

    Args:
        diagram: The diagram.
        stem: The files' path without suffix (its folder is created if missing).

    Raises:
        RuntimeError: Graphviz's ``dot`` program is not installed."""
    dot = _dot()
    stem = Path(stem)
    prepare_out_dir(stem.parent)
    source = stem.with_suffix(".dot")
    source.write_text(diagram_graphviz(diagram))
    paths = [source]
    for fmt in ("svg", "png"):
        target = stem.with_suffix(f".{fmt}")
        subprocess.run([dot, f"-T{fmt}", str(source), "-o", str(target)], check=True)
        paths.append(target)
    return paths


def diagram_svg(diagram: "Diagram", max_depth: int = 2) -> str:
    """The diagram's graph as SVG text (a notebook: IPython.display.SVG(diagram_svg(d))).

    Args:
        diagram: The diagram.
        max_depth: How many levels deep (diagram_graphviz).

    Raises:
        RuntimeError: Graphviz's ``dot`` program is not installed."""
    return subprocess.run([_dot(), "-Tsvg"], input=diagram_graphviz(diagram, max_depth),
                          capture_output=True, text=True, check=True).stdout
