"""Rendering a diagram's graph with Drake's Graphviz export and the ``dot`` program."""
import re
import shutil
import subprocess
from pathlib import Path

_ID = re.compile(r"(digraph _|clusters|cluster|\bs)(\d+)")


def diagram_graphviz(diagram, max_depth: int = 2) -> str:
    """Drake's Graphviz source of ``diagram`` (two levels deep: the controller
    sub-diagram shows its systems) with its process-specific system ids
    renumbered in order of appearance and its edges sorted (Drake lists them in no
    fixed order), so equal diagrams give equal text."""
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


def render_diagram(diagram, stem) -> list:
    """Writes stem.dot, stem.svg and stem.png; returns their paths."""
    dot = _dot()
    stem = Path(stem)
    stem.parent.mkdir(parents=True, exist_ok=True)
    source = stem.with_suffix(".dot")
    source.write_text(diagram_graphviz(diagram))
    paths = [source]
    for fmt in ("svg", "png"):
        target = stem.with_suffix(f".{fmt}")
        subprocess.run([dot, f"-T{fmt}", str(source), "-o", str(target)], check=True)
        paths.append(target)
    return paths


def diagram_svg(diagram, max_depth: int = 2) -> str:
    """The diagram's graph as SVG text (for a notebook:
    IPython.display.SVG(diagram_svg(loop.diagram)))."""
    return subprocess.run([_dot(), "-Tsvg"], input=diagram_graphviz(diagram, max_depth),
                          capture_output=True, text=True, check=True).stdout
