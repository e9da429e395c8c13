"""Failures are named and nothing is lost: bad input exits 2 with one line naming the
setting, a bad --out is refused before any simulation time is spent, and SIGINT or
SIGTERM of a running `dacph simulate` leave a readable run directory marked
interrupted."""
import json
import re
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
from dacph_drake.scenario.built_in import short_scenario
from test_scenario import BAD_SCENARIO_FILES


@pytest.mark.parametrize("argv, message", [
    (["simulate", "shrot", "--out", "OUT"], "scenario 'shrot': no such file"),
    (["simulate", "short", "--out", "OUT", "--duration", "-1"],
     "duration = -1.0 is out of range; allowed: > 0 s"),
    (["simulate", "short", "--out", "OUT", "--duration", "nan"], "duration = nan"),
    (["simulate", "BAD", "--out", "OUT"], "q0[0] = nan is not finite"),
    (["verify", "shrot"], "scenario 'shrot': no such file"),
    (["diagram", "shrot"], "scenario 'shrot': no such file"),
    (["reproduce", "shrot", "--out", "OUT"], "scenario 'shrot': no such file"),
    (["simulate", "short", "--out", "FILE"], "is an existing file; allowed: a directory"),
    (["simulate", "short", "--out", "OUT", "--checkpoint", "0"],
     "checkpoint_seconds (--checkpoint) = 0.0 is out of range; allowed: > 0 s"),
    (["simulate", "LATIN1", "--out", "OUT"], "cannot be read ('utf-8' codec"),
    (["simulate", "LATIN1_DESCRIBED", "--out", "OUT"], "cannot be read ('utf-8' codec"),
    (["free-flight", "--duration", "nan"], "--duration = nan is out of range; allowed: > 0"),
    (["free-flight", "--duration", "-1"], "--duration = -1.0 is out of range; allowed: > 0"),
    (["free-flight", "--duration", "0"], "--duration = 0.0 is out of range; allowed: > 0"),
    (["diagram", "short", "--controller", "dac", "--out", "FILE"],
     "is an existing file; allowed: a directory"),
    (["diagram", "short", "--controller", "dac", "--out", "/proc/dacph"],
     "cannot be created"),
    (["sweep", "BAD_SWEEP", "--out", "OUT"], "malformed YAML at line 2, column 9"),
    (["sweep", "SWEEP", "--out", "FILE"], "is an existing file; allowed: a directory"),
    (["reproduce", "short", "--out", "FILE"], "is an existing file; allowed: a directory"),
    (["animate", "RUN", "--out", "OUT"], "is a directory; allowed: an HTML file"),
    (["animate", "RUN", "--out", "/proc/dacph.html"], "cannot be written"),
    (["sweep", "SWEEP", "--out", "OUT", "--dask", "foo://x"],
     "--dask foo://x is not a scheduler address (unknown address scheme 'foo'"),
    (["sweep", "SWEEP", "--out", "OUT", "--dask", "tcp://127.0.0.1:1"],
     "--dask tcp://127.0.0.1:1: no scheduler answered within 10 s"),
])
def test_cli_bad_input_exits_2_naming_the_setting(tmp_path, capsys, argv, message):
    bad = tmp_path / "bad.yaml"
    bad.write_text("q0: [.nan, 1.0]\n")
    existing = tmp_path / "file"
    existing.write_text("")
    (tmp_path / "latin1.yaml").write_bytes("# caf\xe9\nseed: 1\n".encode("latin-1"))
    (tmp_path / "latin1_described.yaml").write_bytes(
        "# caf\xe9\nrobot: !DescribedArm {description: satellite_3dof}\n".encode("latin-1"))
    (tmp_path / "bad_sweep.yaml").write_text("trials: [1, 2\nscenario: short\n")
    if "RUN" in argv:
        simulate(short_scenario(), "dac", duration=0.05, out_dir=tmp_path / "run")
        (tmp_path / "out").mkdir()
    replace = {"OUT": str(tmp_path / "out"), "BAD": str(bad), "FILE": str(existing),
               "RUN": str(tmp_path / "run"),
               "LATIN1": str(tmp_path / "latin1.yaml"),
               "LATIN1_DESCRIBED": str(tmp_path / "latin1_described.yaml"),
               "BAD_SWEEP": str(tmp_path / "bad_sweep.yaml"),
               "SWEEP": str(Path(__file__).parents[1] / "sweeps" / "short_sweep.yaml")}
    assert main([replace.get(a, a) for a in argv]) == 2
    err = capsys.readouterr().err
    assert err.startswith("dacph: error: ") and message in err, err
    assert len(err.strip().splitlines()) == 1


# Files that load but cannot run: refused when the diagram is built, before any
# simulated time, with the setting named.
UNRUNNABLE_SCENARIO_FILES = [
    ("q0: [2.5, 0.5]\n", r"q0 = \[2.5, 0.5\] puts the arm into the base"),
    ("task: {gains: {min_task_singular_value: 0.9}}\n",
     r"q0 = \[0.3, 1.0\] is near a singularity of the task Jacobian D \(\|\|D\(q0\)\|\| = "
     r"0.832\); allowed: .* task.gains.min_task_singular_value = 0.9"),
    ("periods: {rhs: 0.0005}\n", r"periods.rhs = 0.0005 s cannot realize"),
    ("rhs: {beta_max: 100.0}\n", r"periods.rhs = 0.00025 s cannot realize .* up to "
                                  r"\d+.\d 1/s at rhs.beta_max = 100, .* or a smaller "
                                  r"rhs.beta_max"),
]


@pytest.mark.parametrize("text, message", BAD_SCENARIO_FILES + UNRUNNABLE_SCENARIO_FILES)
def test_every_bad_scenario_file_exits_2_with_one_line(tmp_path, capsys, text, message):
    """The whole bad-input table through `dacph simulate`: exit 2, one line that names
    the setting, and no run directory left behind by a refused run."""
    path = tmp_path / "s.yaml"
    path.write_text(text)
    out = tmp_path / "out"
    assert main(["simulate", str(path), "--out", str(out)]) == 2
    err = [line for line in capsys.readouterr().err.splitlines()
           if not line.startswith("dacph: note: ")]
    assert len(err) == 1 and err[0].startswith("dacph: error: "), err
    assert re.search(message, err[0]), err[0]
    assert not (out / "run_dac.json").exists()


def test_a_file_without_a_robot_section_says_so(tmp_path, caplog):
    from dacph_drake.assembly.scenario_files import load_scenario
    path = tmp_path / "s.yaml"
    path.write_text("seed: 3\n")
    with caplog.at_level("WARNING"):
        assert load_scenario(path).robot == short_scenario().robot
    assert "no robot: section; using the defaults" in caplog.text
    caplog.clear()
    with caplog.at_level("WARNING"):
        load_scenario("scenarios/short.yaml")
    assert caplog.text == ""


def test_out_dir_is_checked_before_the_simulation(tmp_path):
    existing = tmp_path / "file"
    existing.write_text("")
    start = time.perf_counter()
    with pytest.raises(ConfigError, match="is an existing file"):
        simulate(short_scenario(), "dac", out_dir=existing)
    assert time.perf_counter() - start < 1.0        # refused before the diagram is built


# A planar and a described arm's scenario: every reliability behaviour holds for both.
SCENARIOS = ["short", "satellite_3dof"]


def _interrupt_simulate(out, sig, extra=(), after=1.0, scenario="short"):
    """Starts `dacph simulate SCENARIO` (with ``extra`` arguments), sends ``sig``
    ``after`` seconds into the progress bar, and returns the exit status."""
    process = subprocess.Popen(
        [sys.executable, "-m", "dacph_drake.app.cli", "simulate", scenario, "--out", str(out),
         *extra],
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    started = threading.Event()

    def watch():
        seen = b""
        for chunk in iter(lambda: process.stderr.read1(64), b""):
            seen = seen[-64:] + chunk
            if b"%|" in seen:                   # the progress bar (tqdm) is drawn
                started.set()
    threading.Thread(target=watch, daemon=True).start()
    assert started.wait(300), "the simulation did not start"
    time.sleep(after)
    process.send_signal(sig)
    return process.wait(120)


@pytest.mark.parametrize("scenario", SCENARIOS)
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_an_interrupted_run_saves_what_it_has(tmp_path, sig, scenario):
    from dacph_drake.loop.run_store import scenario_fingerprint
    from dacph_drake.assembly.scenario_files import load_scenario
    out = tmp_path / "run"
    assert _interrupt_simulate(out, sig, scenario=scenario) == 130
    meta = json.loads((out / "run_dac.json").read_text())
    assert meta["status"] == "interrupted" and sig.name in meta["reason"]
    assert 0 < meta["final_time"] < load_scenario(scenario).duration
    assert meta["scenario_fingerprint"] == scenario_fingerprint(load_scenario(scenario))
    with np.load(out / "logs_dac.npz") as logs:
        assert logs["time"][-1] <= meta["final_time"] and len(logs["time"]) > 10
    assert (out / "scenario.yaml").is_file()


def test_an_interrupt_inside_a_compiled_kernel_is_an_interrupt(tmp_path, monkeypatch):
    """SIGINT landing inside a numba kernel's call reaches the loop as a SystemError
    caused by the KeyboardInterrupt (seen as exit 1 and no saved run in about 1 of
    5 interrupted CLI runs): the run still ends "interrupted" and saves what it
    has; where the run is not interruptible (sweeps) the KeyboardInterrupt itself
    goes up."""
    import dacph_drake.loop.simulate as module

    def interrupted_kernel(simulator, duration, check, after_chunk):
        simulator.AdvanceTo(0.05)
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as e:
            raise SystemError("CPUDispatcher(...) returned a result with an "
                              "exception set") from e
    monkeypatch.setattr(module, "advance_in_chunks", interrupted_kernel)
    result = simulate(short_scenario(), "model-based", duration=1.0,
                      out_dir=tmp_path / "run", interruptible=True)
    assert result.status == "interrupted" and "SIGINT" in result.reason
    assert (tmp_path / "run" / "logs_model-based.npz").is_file()
    with pytest.raises(KeyboardInterrupt):
        simulate(short_scenario(), "model-based", duration=1.0)


def test_report_refuses_runs_that_do_not_belong_together(tmp_path):
    """A DAC run and a model-based run of another scenario, or of another duration,
    in one directory: report names the problem instead of printing a table."""
    from dacph_drake.app.reproduce import report
    scenario = short_scenario()
    other = short_scenario()
    other.disturbance.scale = 2.0
    mixed, durations = tmp_path / "mixed", tmp_path / "durations"
    simulate(scenario, "dac", duration=0.3, out_dir=mixed)
    with pytest.raises(ConfigError, match="holds a dac run of another scenario"):
        simulate(other, "model-based", duration=0.3, out_dir=mixed)   # refused up front
    simulate(other, "model-based", duration=0.3, out_dir=tmp_path / "other")
    for name in ("logs_model-based.npz", "run_model-based.json", "scenario.yaml"):
        # mixed by hand, as an earlier release let a second run do
        (mixed / name).write_bytes((tmp_path / "other" / name).read_bytes())
    with pytest.raises(ConfigError, match="the dac run was made from another scenario"):
        report(mixed)
    simulate(scenario, "dac", duration=0.3, out_dir=durations)
    simulate(scenario, "model-based", duration=0.2, out_dir=durations)
    with pytest.raises(ConfigError, match=r"different durations \(dac 0.3 s, "
                                          r"model-based 0.2 s\)"):
        report(durations)
    assert main(["report", str(durations)]) == 2


@pytest.mark.parametrize("scenario", SCENARIOS)
def test_a_second_writer_of_the_same_run_is_refused(tmp_path, scenario):
    import fcntl
    from dacph_drake.assembly.scenario_files import load_scenario
    out = tmp_path / "run"
    out.mkdir()
    with open(out / ".run_dac.lock", "w") as held:            # a run in progress
        fcntl.flock(held, fcntl.LOCK_EX | fcntl.LOCK_NB)
        with pytest.raises(ConfigError, match="another process is writing a dac run"):
            simulate(load_scenario(scenario), "dac", duration=0.1, out_dir=out)
    result = simulate(load_scenario(scenario), "dac", duration=0.1, out_dir=out)
    assert result.status == "ok"                                            # released


def test_runs_of_two_robots_never_share_a_directory(tmp_path, capsys):
    """A described arm's run into a planar run's directory, the reverse, and either
    into a directory of the older spatial layout (run.json, logs.npz) are refused
    before any simulated time, and the directory's runs stay readable."""
    from dacph_drake.loop.run_store import load_run
    from dacph_drake.assembly.scenario_files import load_scenario
    planar, described = tmp_path / "planar", tmp_path / "described"
    simulate(short_scenario(), "dac", duration=0.1, out_dir=planar)
    simulate(load_scenario("satellite_3dof"), "model-based", duration=0.1,
             out_dir=described)
    for scenario, out, other in (("satellite_3dof", planar, "dac"),
                                 ("short", described, "model-based")):
        assert main(["simulate", scenario, "--out", str(out), "--controller",
                     "dac-nominal", "--duration", "0.1"]) == 2
        assert f"holds a {other} run of another scenario" in capsys.readouterr().err
        assert not (out / "run_dac-nominal.json").exists()
        assert load_run(out, other)[2]["status"] == "ok"
    older = tmp_path / "older"
    older.mkdir()
    (older / "run.json").write_text("{}")
    with pytest.raises(ConfigError, match="holds a run of the older spatial layout"):
        simulate(load_scenario("satellite_3dof"), "dac", duration=0.1, out_dir=older)


def test_metrics_of_phases_a_run_never_reached_say_so(tmp_path, capsys):
    assert main(["simulate", "short", "--out", str(tmp_path / "run"),
                 "--duration", "3"]) == 0
    lines = capsys.readouterr().out.splitlines()
    phase2 = [line for line in lines if line.strip().startswith("phase2.")]
    assert phase2 and all("not reached (the run ended at 3 s)" in line for line in phase2)
    assert not any(line.strip().startswith("phase1.") and "not reached" in line
                   for line in lines)


@pytest.mark.parametrize("text, message", [
    ("q0: [0.3, 1.0\ntask: {gains: {Kd: 0.5}}\n",
     "malformed YAML at line 2, column 5: expected ',' or ']', but got ':'"),
    ("q0: 0.3\n", "q0 = 0.3 is not a list"),
    ("task: 3\n", "task = 3 is not a mapping"),
    ("robot: {truth: {links: [{mass: heavy}]}}\n",
     "robot.truth.links[0].mass = 'heavy' is not a number"),
    ("task: {reference: {periods: [30.0, eleven]}}\n",
     "task.reference.periods[1] = 'eleven' is not a number"),
])
def test_malformed_files_get_one_line_naming_the_place(tmp_path, capsys, text, message):
    path = tmp_path / "s.yaml"
    path.write_text(text)
    assert main(["simulate", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1, err


def test_numbers_without_a_dot_still_load(tmp_path):
    from dacph_drake.assembly.scenario_files import load_scenario
    path = tmp_path / "s.yaml"
    path.write_text("learner: {eps: 1e-8}\n")
    assert load_scenario(path).learner.eps == 1e-8


@pytest.mark.parametrize("command", ["report", "verify", "animate"])
def test_an_incomplete_run_directory_names_the_missing_file(tmp_path, capsys, command):
    run = tmp_path / "run"
    run.mkdir()
    (run / "scenario.yaml").write_text("seed: 0\n")
    assert main([command, str(run)]) == 2
    err = capsys.readouterr().err
    assert "logs_dac.npz is missing" in err and len(err.strip().splitlines()) == 1, err


@pytest.mark.parametrize("q0", [[2.5, 0.5], [1.5, 2.9]])
def test_a_start_inside_the_base_is_refused(q0):
    """Such a run used to "diverge" at t = 0.0003 s with a runaway message that never
    named the collision."""
    from dacph_drake.controllers.dac import build_dac_diagram
    scenario = short_scenario()
    scenario.q0 = q0
    with pytest.raises(ConfigError, match=r"q0 = .* puts the arm into the base "
                                          r"\(clearance -0.\d+ m\)"):
        build_dac_diagram(scenario)


def test_the_rhs_period_check_applies_to_the_integrator_only():
    """The model-based baseline has no RHS integrator, so a coarse periods.rhs that
    the DAC diagram refuses is allowed for it."""
    from dacph_drake.controllers.dac import build_dac_diagram
    from dacph_drake.controllers.model_based import build_model_based_diagram
    scenario = short_scenario()
    scenario.periods.rhs = 5e-4
    with pytest.raises(ConfigError, match="periods.rhs = 0.0005 s cannot realize"):
        build_dac_diagram(scenario)
    assert build_model_based_diagram(scenario).diagram is not None


@pytest.mark.parametrize("scenario", SCENARIOS)
def test_a_killed_run_keeps_its_last_checkpoint(tmp_path, scenario):
    """kill -9 cannot be caught: what survives is the last checkpoint, a readable
    directory whose run.json says the run had not finished."""
    from dacph_drake.assembly.scenario_files import load_scenario
    out = tmp_path / "run"
    assert _interrupt_simulate(out, signal.SIGKILL, ["--checkpoint", "0.5"],
                               after=4.0, scenario=scenario) == -signal.SIGKILL
    meta = json.loads((out / "run_dac.json").read_text())
    assert meta["status"] == "incomplete" and "had not finished" in meta["reason"]
    assert 0 < meta["final_time"] < load_scenario(scenario).duration
    with np.load(out / "logs_dac.npz") as logs:
        assert abs(logs["time"][-1] - meta["final_time"]) <= 0.011
    assert main(["verify", str(out)]) == 1          # run_finished fails, with a report


def test_a_run_in_contact_stops_with_the_named_reason(monkeypatch):
    """The ground truth has no collision geometry: the run's monitor checks the
    links' kinematic clearance every loop.simulate.MONITOR_PERIOD. A start inside the base,
    let through the build-time check here, stops at the first check."""
    from dacph_drake.robots.planar import PlanarRobot
    from dacph_drake.loop.simulate import MONITOR_PERIOD
    monkeypatch.setattr(PlanarRobot, "RequireRunnableStart", lambda robot: None)
    scenario = short_scenario()
    scenario.q0 = [2.5, 0.5]
    scenario.robot.potential.base_gain = 1e-12       # no field to blow up inside the base
    result = simulate(scenario, "model-based", duration=0.5)
    assert result.status == "diverged"
    assert result.reason.startswith(f"collision: a link touched the base at t = "
                                    f"{MONITOR_PERIOD:.4f} s (clearance -0.")


def test_logs_of_a_run_stopped_between_two_loggers_are_cut_to_a_common_length():
    """SIGINT can arrive while the loggers publish at one instant: some then hold one
    sample more than others, and the metrics would index them with a mask of the
    wrong length. The saved logs hold only the samples every logger has."""
    from types import SimpleNamespace
    from dacph_drake.loop.simulate import collect_logs

    def logger(rows):
        log = SimpleNamespace(data=lambda: np.arange(2.0 * rows).reshape(2, rows),
                              sample_times=lambda: 0.01 * np.arange(rows))
        return SimpleNamespace(FindLog=lambda context: log)
    loop = SimpleNamespace(loggers={"state": logger(269), "estimates": logger(268)})
    logs = collect_logs(loop, None)
    assert {name: len(data) for name, data in logs.items()} == \
        {"state": 268, "estimates": 268, "time": 268}
    np.testing.assert_array_equal(logs["time"], 0.01 * np.arange(268))


def test_progress_to_a_log_file_stays_a_few_lines(capsys):
    """Progress bars (tqdm) written to a non-terminal stderr are redrawn at most once
    a minute: a run and a 50-trial sweep each leave a handful of lines."""
    from dacph_drake.montecarlo.runner import _Progress
    from dacph_drake.loop.simulate import simulate
    simulate(short_scenario(), "model-based", duration=2.0, progress=True)
    err = capsys.readouterr().err
    segments = [s for s in re.split(r"[\r\n]", err) if s.strip()]
    assert 1 <= len(segments) <= 4 and "100%" in segments[-1], segments
    bar = _Progress(50, 0, enabled=True)
    for trial in range(50):
        bar.update({"status": "ok" if trial % 10 else "failed"})
    bar.close()
    segments = [s for s in re.split(r"[\r\n]", capsys.readouterr().err) if s.strip()]
    assert 1 <= len(segments) <= 4 and "50/50" in segments[-1], segments
    assert "failed=5" in segments[-1]


def test_live_meshcat_shows_the_run_without_changing_it():
    """simulate(meshcat=...) draws the robot and both orientation bars into Meshcat
    while it runs; the logs are bit for bit those of a run without it."""
    from dacph_drake.robots.viewers import DESIRED_PATH, MEASURED_PATH, QuietMeshcat
    from dacph_drake.loop.simulate import simulate
    meshcat = QuietMeshcat()
    watched = simulate(short_scenario(), "model-based", duration=0.5, meshcat=meshcat)
    for path in ("/drake/visualizer", DESIRED_PATH, MEASURED_PATH):
        assert meshcat.HasPath(path), path
    plain = simulate(short_scenario(), "model-based", duration=0.5)
    for name, log in plain.logs.items():
        assert np.array_equal(log, watched.logs[name]), name


def test_realtime_rate_setting_is_checked(capsys):
    assert main(["simulate", "short", "--out", "x", "--realtime-rate", "-1"]) == 2
    assert "--realtime-rate = -1.0 is out of range; allowed: >= 0" in capsys.readouterr().err


def _short_run(tmp_path, name="run", controller="dac"):
    simulate(short_scenario(), controller, duration=0.3, out_dir=tmp_path / name)
    return tmp_path / name


@pytest.mark.parametrize("damage, message", [
    (lambda run: np.savez(run / "logs_dac.npz", time=np.zeros(3)),
     r"logs_dac.npz is damaged \(no state, u, tau, lhs_log\)"),
    (lambda run: np.savez(run / "logs_dac.npz", **{
        **dict(np.load(run / "logs_dac.npz")), "u": np.zeros((2, 2))}),
     r"logs_dac.npz is damaged \(u not one sample per time\)"),
    (lambda run: (run / "run_dac.json").write_text(json.dumps(
        {**json.loads((run / "run_dac.json").read_text()), "status": 5})),
     r"run_dac.json is damaged \(status 5, final_time .*status one of ok, diverged"),
    (lambda run: (run / "run_dac.json").write_text(json.dumps(
        {**json.loads((run / "run_dac.json").read_text()), "final_time": "soon"})),
     r"run_dac.json is damaged \(status 'ok', final_time 'soon'\)"),
])
@pytest.mark.parametrize("command", ["report", "verify", "animate", "export"])
def test_a_damaged_run_file_is_named(tmp_path, capsys, damage, message, command):
    run = _short_run(tmp_path)
    damage(run)
    assert main([command, str(run)]) == 2
    err = capsys.readouterr().err
    assert re.search(message, err) and len(err.strip().splitlines()) == 1, err


@pytest.mark.parametrize("command", ["report", "verify"])
def test_a_run_that_no_longer_matches_its_scenario_is_refused(tmp_path, capsys, command):
    """An edited scenario.yaml, and a described arm's run copied over a planar run's:
    verify refuses them as report does, instead of a wrong PASS or a shape error."""
    from dacph_drake.scenario.built_in import satellite_3dof_scenario
    edited = _short_run(tmp_path, "edited")
    text = (edited / "scenario.yaml").read_text()
    (edited / "scenario.yaml").write_text(text.replace("seed: 0", "seed: 1"))
    copied = _short_run(tmp_path, "copied")
    simulate(satellite_3dof_scenario(), "dac", duration=0.3, out_dir=tmp_path / "spatial")
    for name in ("logs_dac.npz", "run_dac.json"):
        (copied / name).write_bytes((tmp_path / "spatial" / name).read_bytes())
    for run in (edited, copied):
        assert main([command, str(run)]) == 2
        err = capsys.readouterr().err
        assert "the dac run was made from another scenario than scenario.yaml" in err
        assert len(err.strip().splitlines()) == 1, err


def test_python_simulate_checks_the_seed():
    for seed, message in [(-1, "seed = -1 is out of range"),
                          (1.5, "seed = 1.5 is not an integer")]:
        scenario = short_scenario()
        scenario.seed = seed
        with pytest.raises(ConfigError, match=message):
            simulate(scenario, "dac", duration=0.01)


def test_a_sweep_never_writes_into_a_run_directory(tmp_path, capsys):
    run = _short_run(tmp_path)
    before = {p.name: p.read_bytes() for p in run.iterdir() if p.is_file()}
    sweep = Path(__file__).parents[1] / "sweeps" / "short_sweep.yaml"
    assert main(["sweep", str(sweep), "--out", str(run), "--workers", "0"]) == 2
    err = capsys.readouterr().err
    assert "holds a run (logs_dac.npz, run_dac.json, scenario.yaml)" in err, err
    assert {p.name: p.read_bytes() for p in run.iterdir() if p.is_file()} == before


def _urdf(tmp_path, old: str, new: str) -> Path:
    source = Path(__file__).parent / "data" / "arms" / "coupled_light_joints.urdf"
    text = source.read_text()
    assert old in text
    (tmp_path / "arm.urdf").write_text(text.replace(old, new, 1))
    scenario = tmp_path / "s.yaml"
    scenario.write_text("robot: !DescribedArm\n  description: arm.urdf\n"
                        "  end_effector: {frame: tool}\n")
    return scenario


@pytest.mark.parametrize("old, new, message", [
    ('<mass value="0.393133"/>', '<mass value="-0.393133"/>',
     r"arm.urdf:1: a link's mass or inertia is not physical \(Drake: condition "
     r"'mass > 0' failed\); allowed: mass > 0"),
    ('<joint name="joint3" type="revolute">', '<joint name="joint3" type="floating">',
     r"2 free bodies: the base 'root' and 'link3' \(a floating joint"),
])
def test_a_description_drake_would_change_is_refused(tmp_path, capsys, old, new,
                                                     message):
    scenario = _urdf(tmp_path, old, new)
    assert main(["simulate", str(scenario), "--out", str(tmp_path / "out")]) == 2
    err = [line for line in capsys.readouterr().err.splitlines()
           if not line.startswith("dacph: note: ")]
    assert len(err) == 1 and re.search(message, err[0]), err


def test_a_run_cut_before_its_events_says_so(caplog):
    """Events after the phases' end are refused (the scenario table); a --duration
    that ends the run before an event runs, with a note naming it."""
    from dacph_drake.scenario import ActuatorFault
    scenario = short_scenario()
    scenario.uncertainty.faults = [ActuatorFault(time=12.0, joint=2, gain=0.5)]
    with caplog.at_level("WARNING"):
        simulate(scenario, "model-based", duration=0.1)
    assert ("the run ends at 0.1 s, before uncertainty.faults[0].time = 12 s: never in "
            "effect in this run") in caplog.text
    caplog.clear()
    with caplog.at_level("WARNING"):
        simulate(scenario, "model-based", duration=12.5)
    assert "never in effect" not in caplog.text


def test_a_live_run_leaves_its_meshcat_to_the_thread_that_made_it():
    """simulate(meshcat=...) leaves nothing that holds the Meshcat behind it: deleted on
    the thread that made it, the Meshcat is gone, so a garbage collection on another
    thread afterwards cannot destroy it there (Drake aborts the process when it does:
    the tutorial notebook's kernel died that way at random)."""
    script = """
import gc, threading
from pydrake.geometry import StartMeshcat
from dacph_drake.scenario.built_in import short_scenario
from dacph_drake.loop.simulate import simulate
meshcat = StartMeshcat()
run = simulate(short_scenario(), "model-based", duration=0.1, meshcat=meshcat)
del meshcat, run
worker = threading.Thread(target=gc.collect)
worker.start()
worker.join()
print("collected elsewhere, still alive")
"""
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    assert "collected elsewhere, still alive" in done.stdout
