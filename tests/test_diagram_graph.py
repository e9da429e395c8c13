"""The rendered diagram graphs in diagrams/ are those of the shipped scenarios
(scenarios/)."""
from pathlib import Path

import pytest

from dacph_drake.controllers import NAMES, build_closed_loop
from dacph_drake.app.graph import diagram_graphviz
from dacph_drake.assembly.scenario_files import load_scenario

DIAGRAMS = Path(__file__).resolve().parents[1] / "diagrams"
SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"


@pytest.mark.parametrize("name", ["paper", "short"])
@pytest.mark.parametrize("controller", list(NAMES))
def test_rendered_graphs_are_in_sync(name, controller):
    loop = build_closed_loop(controller, load_scenario(SCENARIOS / f"{name}.yaml"))
    stem = DIAGRAMS / f"{name}_{controller.replace('-', '_')}"
    assert stem.with_suffix(".dot").read_text() == diagram_graphviz(loop.diagram), \
        f"run: dacph diagram scenarios/{name}.yaml --out diagrams"
    for suffix in (".svg", ".png"):
        assert stem.with_suffix(suffix).stat().st_size > 1000
    text = stem.with_suffix(".dot").read_text()
    for system in loop.systems:
        assert f"name={system}" in text


def test_dacph_diagram_writes_to_the_current_directory(tmp_path, monkeypatch):
    """Without --out, the files go to the current directory, never next to the
    scenario file (in a checkout, that would overwrite the committed graphs)."""
    from dacph_drake.app.cli import main
    before = {p.name: p.stat().st_mtime_ns for p in SCENARIOS.iterdir()}
    monkeypatch.chdir(tmp_path)
    assert main(["diagram", str(SCENARIOS / "short.yaml"), "--controller",
                 "model-based"]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "short_model_based.dot", "short_model_based.png", "short_model_based.svg"]
    assert {p.name: p.stat().st_mtime_ns for p in SCENARIOS.iterdir()} == before


@pytest.mark.parametrize("controller", list(NAMES))
def test_rendered_spatial_graphs_are_in_sync(controller):
    loop = build_closed_loop(controller, load_scenario(SCENARIOS / "satellite_6dof.yaml"))
    stem = DIAGRAMS / f"satellite_6dof_{controller.replace('-', '_')}"
    assert stem.with_suffix(".dot").read_text() == diagram_graphviz(loop.diagram), \
        "run: dacph diagram scenarios/satellite_6dof.yaml --out diagrams"
    for system in loop.systems:
        assert f"name={system}" in stem.with_suffix(".dot").read_text()
