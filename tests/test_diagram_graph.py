"""The rendered diagram graphs in diagrams/ are those of the shipped scenarios."""
from pathlib import Path

import pytest

from dacph_drake.controllers import NAMES, build_closed_loop
from dacph_drake.graph import diagram_graphviz
from dacph_drake.scenario import load_scenario

DIAGRAMS = Path(__file__).resolve().parents[1] / "diagrams"


@pytest.mark.parametrize("name", ["paper", "short"])
@pytest.mark.parametrize("controller", list(NAMES))
def test_rendered_graphs_are_in_sync(name, controller):
    loop = build_closed_loop(controller, load_scenario(DIAGRAMS / f"{name}.yaml"))
    stem = DIAGRAMS / f"{name}_{controller.replace('-', '_')}"
    assert stem.with_suffix(".dot").read_text() == diagram_graphviz(loop.diagram), \
        f"run: dacph diagram diagrams/{name}.yaml"
    for suffix in (".svg", ".png"):
        assert stem.with_suffix(suffix).stat().st_size > 1000
    text = stem.with_suffix(".dot").read_text()
    for system in loop.systems:
        assert f"name={system}" in text
