"""Every path fails by name and loses nothing (the reliability issue's categories),
planar and described arms alike: damaged saved files are named (exit 2), an
interrupted `dacph verify` saves its run and leaves no lock behind, a described
arm's bad description or start is refused before anything runs, a run driven into
the base stops "collision", settings of the wrong kind set from Python are named,
and relative paths in a scenario file are the file's."""
import json
import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from dacph_drake.app.cli import main
from dacph_drake.scenario.errors import ConfigError
from dacph_drake.loop.simulate import simulate
from dacph_drake.assembly.scenario_files import load_scenario

ROBOTS = ["short", "satellite_3dof"]
MODELS = Path(__file__).resolve().parents[1] / "dacph_drake" / "models"


@pytest.fixture(scope="module")
def saved_runs(tmp_path_factory):
    """A DAC and a model-based run of each robot, saved as dacph simulate does."""
    runs = {}
    for scenario in ROBOTS:
        out = tmp_path_factory.mktemp(scenario)
        for controller in ("dac", "model-based"):
            simulate(load_scenario(scenario), controller, duration=0.2, out_dir=out)
        runs[scenario] = out
    return runs


def _truncated(path: Path) -> None:
    path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])


def _not_utf8(path: Path) -> None:
    path.write_bytes(b"\x00\xff garbage: [\n")


def _without_status(path: Path) -> None:
    path.write_text(json.dumps({"controller": "dac"}))


DAMAGE = [("logs_dac.npz", _truncated, "logs_dac.npz is damaged (BadZipFile"),
          ("run_dac.json", _truncated, "run_dac.json is damaged ("),
          ("run_dac.json", _without_status, "run_dac.json is damaged (no status, "
                                            "final_time)"),
          ("scenario.yaml", _not_utf8, "scenario.yaml: cannot be read ('utf-8' codec")]


@pytest.mark.parametrize("command", ["report", "verify", "animate"])
@pytest.mark.parametrize("name, damage, message", DAMAGE,
                         ids=[f"{d[0]}-{d[1].__name__}" for d in DAMAGE])
@pytest.mark.parametrize("robot", ROBOTS)
def test_a_damaged_saved_file_is_named(saved_runs, tmp_path, capsys, robot, name, damage,
                                       message, command):
    run = tmp_path / "run"
    shutil.copytree(saved_runs[robot], run)
    damage(run / name)
    assert main([command, str(run)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("dacph: error: ") and message in err, err
    assert len(err.strip().splitlines()) == 1, err


def test_a_damaged_sweep_manifest_is_named(tmp_path, capsys):
    sweep = Path(__file__).resolve().parents[1] / "sweeps" / "short_sweep.yaml"
    for text, message in (("{broken", "manifest.json is damaged (Expecting property "),
                          ("[1, 2]", "manifest.json is damaged (no fingerprint, "
                                     "sessions)")):
        (tmp_path / "manifest.json").write_text(text)
        assert main(["sweep", str(sweep), "--out", str(tmp_path), "--report"]) == 2
        err = capsys.readouterr().err
        assert message in err and len(err.strip().splitlines()) == 1, err


def _interrupt(argv, sig, after=1.0):
    """Runs `dacph ARGV`, sends ``sig`` ``after`` seconds into its progress bar;
    returns (exit status, stderr)."""
    process = subprocess.Popen(
        [sys.executable, "-m", "dacph_drake.app.cli", *argv],
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    started, seen = threading.Event(), []

    def watch():
        for chunk in iter(lambda: process.stderr.read1(64), b""):
            seen.append(chunk)
            if b"%|" in b"".join(seen[-2:]):
                started.set()
    reader = threading.Thread(target=watch, daemon=True)
    reader.start()
    assert started.wait(300), "the simulation did not start"
    time.sleep(after)
    process.send_signal(sig)
    status = process.wait(120)
    reader.join(10)
    return status, b"".join(seen).decode(errors="replace")


@pytest.mark.parametrize("robot", ROBOTS)
def test_an_interrupted_verify_saves_its_run_and_no_lock(tmp_path, robot):
    out = tmp_path / "run"
    status, err = _interrupt(["verify", robot, "--out", str(out)], signal.SIGINT)
    assert status == 130 and "Traceback" not in err, err
    assert "interrupted" in err and "not verified" in err, err
    meta = json.loads((out / "run_dac.json").read_text())
    assert meta["status"] == "interrupted" and "SIGINT" in meta["reason"]
    assert not list(out.glob(".run_*.lock"))
    assert main(["verify", str(out)]) == 1              # a readable run, not finished


def test_a_lock_is_released_and_removed(tmp_path):
    """ReleaseRun removes the lock file while holding the lock: a writer that
    opened the old file meanwhile takes the lock on the path's new file."""
    from dacph_drake.loop.run_store import LockRun, ReleaseRun
    first = LockRun(tmp_path, "dac")
    with pytest.raises(ConfigError, match="another process is writing a dac run"):
        LockRun(tmp_path, "dac")
    ReleaseRun(first)
    assert not (tmp_path / ".run_dac.lock").exists()
    second = LockRun(tmp_path, "dac")
    assert (tmp_path / ".run_dac.lock").exists()
    ReleaseRun(second)


def _satellite_3dof_urdf(tmp_path, change) -> Path:
    path = tmp_path / "arm.urdf"
    path.write_text(change((MODELS / "satellite_3dof.urdf").read_text()))
    return path


def _massless_last_link(urdf: str) -> str:
    start = urdf.rindex("<inertial>")
    end = urdf.index("</inertial>", start)
    return (urdf[:start] + '<inertial><mass value="0"/><inertia ixx="0" iyy="0" '
            'izz="0" ixy="0" ixz="0" iyz="0"/>' + urdf[end:])


@pytest.mark.parametrize("change, message", [
    (_massless_last_link, r"joint 'joint3' moves no inertia \(the bodies beyond it have "
                          r"no mass"),
    (lambda urdf: urdf.replace('"end_effector"', '"tool"'),
     r"arm.urdf has no frame named 'end_effector'; allowed: a description with one"),
    (lambda urdf: urdf.replace('name="joint1" type="continuous"',
                               'name="joint1" type="prismatic"'),
     r"q0 has 3 entries; allowed: 2 \(one per joint\)"),
], ids=["massless link", "no end effector", "prismatic joint (locked)"])
def test_a_bad_description_is_named_before_anything_runs(tmp_path, capsys, change,
                                                         message):
    urdf = _satellite_3dof_urdf(tmp_path, change)
    scenario = tmp_path / "s.yaml"
    scenario.write_text(f"robot: !DescribedArm {{description: {urdf.name}}}\n"
                        "q0: [0.3, -0.8, 1.6]\n")
    assert main(["simulate", str(scenario), "--out", str(tmp_path / "out")]) == 2
    err = [line for line in capsys.readouterr().err.splitlines()
           if not line.startswith("dacph: note: ")]
    assert len(err) == 1 and err[0].startswith("dacph: error: "), err
    assert __import__("re").search(message, err[0]), err[0]
    assert not (tmp_path / "out" / "run_dac.json").exists()


def test_paths_in_a_scenario_file_are_the_files(tmp_path, monkeypatch):
    folder = tmp_path / "robot"
    folder.mkdir()
    _satellite_3dof_urdf(folder, lambda urdf: urdf)
    (folder / "packages").mkdir()
    (folder / "s.yaml").write_text(
        "robot: !DescribedArm\n  description: arm.urdf\n  package_paths: [packages]\n"
        "q0: [0.3, -0.8, 1.6]\n")
    monkeypatch.chdir(tmp_path)                     # not the file's folder
    scenario = load_scenario("robot/s.yaml")
    assert scenario.robot.description == str(folder / "arm.urdf")
    assert scenario.robot.package_paths == [str(folder / "packages")]
    shipped = load_scenario(str(MODELS.parents[1] / "scenarios" / "satellite_3dof.yaml"))
    assert shipped.robot.description == "satellite_3dof"        # a name stays a name


def test_a_run_directory_of_the_previous_release_with_a_relative_path_still_loads(
        tmp_path, monkeypatch):
    """The previous release read a relative description against the working
    directory and saved it so in the run directory's scenario.yaml: from that
    directory the run still loads, with the fingerprint it was saved with."""
    from dacph_drake.loop.run_store import load_run, scenario_fingerprint
    _satellite_3dof_urdf(tmp_path, lambda urdf: urdf)
    monkeypatch.chdir(tmp_path)
    scenario = load_scenario("satellite_3dof")
    scenario.robot.description = "arm.urdf"          # as the previous release kept it
    out = tmp_path / "runs" / "old"
    simulate(scenario, "model-based", duration=0.05, out_dir=out)
    assert "description: arm.urdf" in (out / "scenario.yaml").read_text()
    _, loaded, meta = load_run(out, "model-based")
    assert loaded.robot.description == "arm.urdf"
    assert scenario_fingerprint(loaded) == meta["scenario_fingerprint"]
    assert main(["animate", str(out), "--controller", "model-based"]) == 0


@pytest.mark.parametrize("robot", ROBOTS)
@pytest.mark.parametrize("section, value, message", [
    ("uncertainty.B0", "letters", r"uncertainty.B0\[0\] = 'l' is not a number"),
    ("uncertainty.D0", 0.1, "uncertainty.D0 = 0.1 is not a list"),
    ("rhs.Td", "2", "rhs.Td = '2' is not a number"),
    ("disturbance.scale", None, "disturbance.scale = None is not a number"),
    ("q0", np.array([np.nan, 1.0, 0.5]), r"q0\[0\] = nan is not finite"),
])
def test_settings_of_the_wrong_kind_from_python_are_named(robot, section, value,
                                                          message):
    scenario = load_scenario(robot)
    if isinstance(value, str) and section == "uncertainty.B0":
        value = list(value)[: len(scenario.q0)]
    if section == "q0":
        value = value[: len(scenario.q0)]
    owner, name = (scenario, section) if "." not in section else (
        getattr(scenario, section.split(".")[0]), section.split(".")[1])
    setattr(owner, name, value)
    with pytest.raises(ConfigError, match=message):
        simulate(scenario, "dac", duration=0.05)


def test_a_described_start_inside_the_base_is_refused():
    scenario = load_scenario("satellite_3dof")
    scenario.q0 = [0.0, 2.0, 2.0]
    with pytest.raises(ConfigError, match=r"q0 = \[0.0, 2.0, 2.0\] puts the arm into "
                                          r"the base \(clearance -0.4\d+ m\)"):
        simulate(scenario, "model-based", duration=0.05)


def test_a_described_run_in_contact_stops_with_the_named_reason(monkeypatch, tmp_path):
    """The described ground truth has no contact either: its run's monitor measures
    the links' clearance (DescribedRobot.Clearance) and stops a run that reaches the
    base, with its logs saved. A start inside the base, let through the build-time
    check here, stops at the first check."""
    from dacph_drake.loop.simulate import MONITOR_PERIOD
    from dacph_drake.robots.described import DescribedRobot
    monkeypatch.setattr(DescribedRobot, "RequireRunnableStart", lambda robot: None)
    scenario = load_scenario("satellite_3dof")
    scenario.q0 = [0.0, 2.0, 2.0]
    result = simulate(scenario, "model-based", duration=0.5, out_dir=tmp_path)
    assert result.status == "diverged"
    assert result.reason.startswith(f"collision: a link touched the base at t = "
                                    f"{MONITOR_PERIOD:.4f} s (clearance -0.")
    assert json.loads((tmp_path / "run_model-based.json").read_text())["status"] == \
        "diverged"


@pytest.mark.parametrize("links", [4, 6])
def test_larger_planar_arms_build_fast_and_run_dac_through_every_phase(tmp_path, links):
    """A file naming only an n-link robot.truth (assembly.registry.sized_defaults
    sizes the rest, robots.planar.planar_arm_scenario) builds its DAC diagram in
    seconds (the inertia bounds searched, not a 73^n grid) and runs DAC through the
    short scenario's four phases (scripts/bench_links.py tabulates 2 to 8 links):
    once the start's transient of phase 1 is over, tracking within 1e-3 rad
    (measured: 5e-6 to 6e-4 rad)."""
    path = tmp_path / "arm.yaml"
    path.write_text("robot: !PlanarArm\n  truth:\n    links:\n" + "".join(
        "      - {mass: 1.0, length: 0.5, inertia: 0.02, com: 0.25}\n"
        for _ in range(links))
        + "phases: {warmup: 2.0, linear: 8.0, nonlinear: 8.0, disturbance: 8.0}\n")
    scenario = load_scenario(path)
    assert len(scenario.q0) == links and scenario.robot.nominal == scenario.robot.truth
    from dacph_drake.controllers import build_closed_loop
    start = time.perf_counter()
    build_closed_loop("dac", scenario)
    assert time.perf_counter() - start < 30
    result = simulate(scenario, "dac")
    assert result.status == "ok", result.reason
    assert result.final_time == pytest.approx(scenario.duration)
    from dacph_drake.loop.metrics import run_metrics
    metrics = run_metrics(result.logs, scenario)
    assert metrics["phase1.tracking_error_rms"] < 0.05
    assert all(metrics[f"phase{k}.tracking_error_rms"] < 1e-3 for k in (2, 3))


@pytest.mark.parametrize("robot", ROBOTS)
@pytest.mark.parametrize("setting", ["task.gains.Lambda", "task.reference"])
def test_a_run_driven_to_blow_up_stops_diverged_with_its_logs(tmp_path, robot, setting):
    """Gains or a reference far beyond the arm's means stop as "diverged" with the
    reason and the logs up to then saved, exit 1. Where the state blows up within
    the steps between two checks of the monitor (planar, Lambda = 1e6: the torque is
    zeroed at the runaway, but at 1e6 rad/s the explicit step itself diverges and
    Drake's own check fails), the run still ends "diverged" with the runaway's
    reason, not a Drake assertion (loop.simulate.advance_in_chunks)."""
    scenario = load_scenario(robot)
    if setting == "task.gains.Lambda":
        scenario.task.gains.Lambda = 1e6
    elif robot == "short":
        scenario.task.reference.amplitudes = [1e3, 0.0]
    else:
        scenario.task.reference.amplitude = 1e3
    out = tmp_path / "run"
    assert main_simulate(scenario, out) == 1
    meta = json.loads((out / "run_dac.json").read_text())
    assert meta["status"] == "diverged" and meta["reason"], meta
    with np.load(out / "logs_dac.npz") as logs:
        assert len(logs["time"]) >= 1 and np.all(np.isfinite(logs["state"]))


def main_simulate(scenario, out: Path) -> int:
    """`dacph simulate` of a scenario object: saved to a file first."""
    from dacph_drake.assembly.scenario_files import save_scenario
    path = out.parent / "scenario.yaml"
    save_scenario(scenario, path)
    return main(["simulate", str(path), "--out", str(out), "--duration", "2"])
