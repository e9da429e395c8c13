"""What every axis's extension test asks of a scenario file: `dacph simulate`,
`dacph verify`, `dacph reproduce` and `dacph report` take it, and a 2-trial sweep of
it runs (in this process, where a test's registrations hold)."""
import json
from pathlib import Path

from dacph_drake.app.cli import main

TINY_PHASES = "phases: {warmup: 0.2, linear: 0.3, nonlinear: 0.3, disturbance: 0.3}\n"


def runs_in_every_command(tmp_path: Path, scenario_file: Path) -> Path:
    """Runs the file through every command; returns the reproduction's directory.

    Args:
        tmp_path: A scratch directory.
        scenario_file: The scenario file."""
    from dacph_drake.montecarlo.definition import load_sweep
    from dacph_drake.montecarlo.executors import InProcessExecutor
    from dacph_drake.montecarlo.runner import run_sweep
    from dacph_drake.montecarlo.summary import write_summary
    single = tmp_path / "single"
    assert main(["simulate", str(scenario_file), "--out", str(single)]) == 0
    assert json.loads((single / "run_dac.json").read_text())["status"] == "ok"
    assert main(["verify", str(single)]) in (0, 1)
    assert (single / "verification.json").is_file()
    out = tmp_path / "reproduced"
    assert main(["reproduce", str(scenario_file), "--out", str(out)]) == 0
    assert main(["report", str(out)]) == 0
    (tmp_path / "sweep.yaml").write_text(
        f"scenario: {scenario_file.name}\ntrials: 2\ncontrollers: [dac]\n"
        "distributions:\n  delta_D_scale: !Uniform {min: 0.5, max: 1.5}\n")
    definition = load_sweep(tmp_path / "sweep.yaml")
    rows = run_sweep(definition, tmp_path / "sweep", InProcessExecutor(), 1)
    assert [row["runs"]["dac"]["status"] for row in rows] == ["ok", "ok"]
    assert write_summary(tmp_path / "sweep", definition)["controllers"]["dac"][
        "succeeded"] == 2
    return out
