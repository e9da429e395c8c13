"""`dacph reproduce --quick --animate` end to end (the session's run, conftest): every
panel, the table (whose numbers match the logs) and an HTML animation that a real
headless Chromium shows offline."""
import json

import numpy as np
import pytest

from dacph_drake.app.figures import DAC_PANELS
from dacph_drake.loop.metrics import run_metrics
from dacph_drake.app.reproduce import CONTROLLERS, PAPER_ROWS, ablation_rows, flat_metrics
from dacph_drake.tasks.end_effector_angle import END_EFFECTOR_ANGLE
from dacph_drake.loop.run_store import load_logs
from dacph_drake.assembly.scenario_files import load_scenario
from headless_chromium import run_chromium


def test_reproduce_writes_panels_table_scenario_and_animation(quick_reproduction):
    status, out = quick_reproduction
    assert status == 0
    for panel in DAC_PANELS + END_EFFECTOR_ANGLE.panels:
        for suffix in ("png", "pdf"):
            path = out / "figures" / f"{panel}.{suffix}"
            assert path.stat().st_size > 10_000, path
    assert (out / "metrics.md").read_text().count("\n| ") == len(PAPER_ROWS) + 1
    assert (out / "animation_dac.html").stat().st_size > 100_000
    load_scenario(out / "scenario.yaml")          # the directory alone reproduces it


def test_table_numbers_match_the_logs(quick_reproduction):
    _, out = quick_reproduction
    summary = json.loads((out / "metrics.json").read_text())
    scenario = load_scenario(out / "scenario.yaml")
    metrics = {c: run_metrics(load_logs(out, c), scenario) for c in CONTROLLERS}
    flat = flat_metrics(metrics)
    assert [row["key"] for row in summary["table"]] == [r.key for r in PAPER_ROWS]
    for row in summary["table"]:
        assert row["this_project"] == pytest.approx(flat[row["key"]], rel=1e-12)
    reduction = 1 - metrics["dac"]["tracking_error_rms"] / \
        metrics["model-based"]["tracking_error_rms"]
    assert summary["table"][0]["this_project"] == pytest.approx(reduction)
    assert summary["table"][0]["paper"] == 0.775


def test_ablation_numbers_match_the_logs(quick_reproduction):
    """ablation.md / metrics.json["ablation"]: one row per ablation_rows entry, each
    phase's value equal to the metric recomputed from the saved logs."""
    _, out = quick_reproduction
    summary = json.loads((out / "metrics.json").read_text())
    scenario = load_scenario(out / "scenario.yaml")
    metrics = {c: run_metrics(load_logs(out, c), scenario) for c in CONTROLLERS}
    rows = ablation_rows(metrics)
    assert [row["metric"] for row in summary["ablation"]] == [r.label for r in rows]
    for row in summary["ablation"]:
        controller, name = row["key"].split(".", 1)
        for phase, value in zip(("phase1", "phase2", "phase3"), row["phases"]):
            expected = metrics[controller][f"{phase}.{name}"]
            if row["over"]:
                over_controller, over_name = row["over"].split(".", 1)
                expected /= metrics[over_controller][f"{phase}.{over_name}"]
            assert value == pytest.approx(expected, rel=1e-12), (row["metric"], phase)
    text = (out / "ablation.md").read_text()
    assert text.count("\n| ") == len(rows) + 1


def test_animation_shows_the_robot_offline_in_headless_chromium(quick_reproduction,
                                                                tmp_path):
    """The page loads with the network blocked (an unreachable proxy) and its
    screenshot shows the grey base, the two coloured links and the red alpha_d bar."""
    import matplotlib.image
    _, out = quick_reproduction
    shot = tmp_path / "shot.png"
    run_chromium((out / "animation_dac.html").resolve().as_uri(), f"--screenshot={shot}",
                 virtual_time_ms=8000)
    image = matplotlib.image.imread(shot)[..., :3]
    saturated = image.max(axis=2) - image.min(axis=2) > 0.3     # coloured pixels
    red = (image[..., 0] > 0.7) & (image[..., 1] < 0.35) & (image[..., 2] < 0.35)
    grey = (np.abs(image - image.mean(axis=2, keepdims=True)).max(axis=2) < 0.03) & \
        (image.mean(axis=2) > 0.7) & (image.mean(axis=2) < 0.9)
    assert saturated.sum() > 2000, "no coloured links in the screenshot"
    assert red.sum() > 50, "no alpha_d bar in the screenshot"
    assert grey.sum() > 2000, "no base in the screenshot"


def test_animation_explains_itself(quick_reproduction, tmp_path):
    """The overlay names what is drawn and, while the recording plays, shows the
    simulated time and the phase (read from the page's DOM after 20 s of virtual
    time; the time has moved on from 0), and the screenshot shows the overlay's box with text in it."""
    import re
    import matplotlib.image
    from dacph_drake.robots.viewers import OVERLAY_BACKGROUND
    _, out = quick_reproduction
    page = (out / "animation_dac.html").resolve().as_uri()
    dom = run_chromium(page, "--dump-dom", virtual_time_ms=20000)
    time_shown = float(re.search(r'id="dacph-time">t = ([0-9.]+) s<', dom).group(1))
    assert 0.0 < time_shown <= 26.0
    assert re.search(r'id="dacph-phase">(Warm-up|Phase [123])', dom)
    for entry in ("base", "link 1", "link 2", "desired end-effector direction",
                  "measured end-effector direction"):
        assert entry in dom, entry
    shot = tmp_path / "shot.png"
    run_chromium(page, f"--screenshot={shot}", virtual_time_ms=20000)
    image = matplotlib.image.imread(shot)[..., :3]
    background = np.array([int(OVERLAY_BACKGROUND[i:i + 2], 16) for i in (1, 3, 5)]) / 255
    box = np.abs(image - background).max(axis=2) < 0.02
    rows, columns = np.nonzero(box)
    assert box.sum() > 10_000, "no overlay box in the screenshot"
    inside = image[rows.min():rows.max(), columns.min():columns.max()]
    assert (inside.mean(axis=2) < 0.3).sum() > 300, "no text in the overlay"


def test_writing_an_animation_starts_no_announced_server(quick_reproduction, tmp_path,
                                                         caplog, capsys):
    """Only a file is written: no "Meshcat listening for connections" message."""
    from dacph_drake.app.cli import main
    _, out = quick_reproduction
    assert main(["animate", str(out), "--out", str(tmp_path / "a.html")]) == 0
    assert (tmp_path / "a.html").stat().st_size > 100_000
    captured = capsys.readouterr()
    assert "listening" not in caplog.text + captured.out + captured.err


def test_tables_say_which_phases_a_run_never_reached():
    from dacph_drake.app.reproduce import NOT_REACHED, ablation_markdown
    text = ablation_markdown([{"metric": "RMS |x|", "unit": "rad",
                               "phases": [2e-5, float("nan"), float("nan")]}], "t")
    assert text.count(NOT_REACHED) == 2 and "nan" not in text and "2e-05 rad" in text
