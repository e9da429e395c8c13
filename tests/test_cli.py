"""The command line's own options."""
import pytest

from dacph_drake.app.cli import main


def test_version_prints_the_installed_version(capsys):
    from importlib.metadata import version
    with pytest.raises(SystemExit) as stop:
        main(["--version"])
    assert stop.value.code == 0
    assert capsys.readouterr().out.strip() == f"dacph {version('dacph-drake')}"


def _commands():
    from dacph_drake.app.cli import make_parser
    parser = make_parser()
    subparsers = next(a for a in parser._actions
                      if isinstance(a, __import__("argparse")._SubParsersAction))
    return parser, subparsers.choices


def test_every_argument_of_every_command_has_help(capsys):
    """A walk over the parser: each command and each of its arguments explains itself,
    and each command's --help prints and exits 0."""
    parser, commands = _commands()
    assert set(commands) >= {"simulate", "report", "export", "verify", "sweep",
                             "reproduce", "animate", "diagram", "free-flight"}
    for action in parser._actions:
        assert action.help, action.dest
    for name, command in commands.items():
        assert command.description or any(
            choice.dest == name for choice in next(
                a for a in parser._actions if hasattr(a, "_choices_actions")
            )._choices_actions if choice.help), name
        for action in command._actions:
            assert action.help and action.help.strip(), f"dacph {name} {action.dest}"
        with pytest.raises(SystemExit) as stop:
            main([name, "--help"])
        assert stop.value.code == 0
        assert "`" not in capsys.readouterr().out
    assert "`" not in parser.format_help()          # no raw RST
    assert "animation_CONTROLLER" not in commands["simulate"].format_help()
    assert "animation_model_based.html" in commands["simulate"].format_help()


def test_bare_dacph_lists_the_commands(capsys):
    assert main([]) == 2
    err = capsys.readouterr().err
    assert "simulate" in err and "reproduce" in err and "--quiet" in err


@pytest.mark.parametrize("argv, suggestion", [
    (["simulate", "short", "--out", "OUT", "--controller", "dca"], "did you mean 'dac'?"),
    (["simulat", "short"], "did you mean 'simulate'?"),
    (["export", "RUN", "--format", "cvs"], "did you mean 'csv'?"),
])
def test_a_mistyped_choice_names_the_closest(capsys, argv, suggestion):
    with pytest.raises(SystemExit) as stop:
        main(argv)
    assert stop.value.code == 2
    assert suggestion in capsys.readouterr().err


def test_a_mistyped_scenario_name_names_the_closest(tmp_path, capsys):
    assert main(["simulate", "satelite_6dof", "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "did you mean 'satellite_6dof'?" in err and len(err.splitlines()) == 1


def test_notes_are_shown_once():
    import logging
    from dacph_drake.app.cli import _Once
    once = _Once()
    record = logging.LogRecord("drake", logging.WARNING, "", 0, "a %s", ("note",), None)
    again = logging.LogRecord("x", logging.WARNING, "", 0, "a note", (), None)
    other = logging.LogRecord("x", logging.WARNING, "", 0, "another", (), None)
    assert [once.filter(r) for r in (record, again, other)] == [True, False, True]


def test_a_single_run_leaves_its_panels_and_metrics(tmp_path, capsys):
    """dacph simulate writes the run's panels (PNG) and metrics.json; report takes the
    directory alone; the metrics print under the scenario's phase names, with units."""
    import json
    from dacph_drake.loop.metrics import run_metrics
    from dacph_drake.loop.run_store import load_run
    out = tmp_path / "run"
    assert main(["simulate", "short", "--out", str(out), "--duration", "3"]) == 0
    printed = capsys.readouterr().out
    assert "  phase1: linear, 2-10 s" in printed and "  phase2: nonlinear, 10-18 s" in printed
    assert "    phase1.tracking_error_rms" in printed and " rad\n" in printed
    pngs = sorted(p.name for p in (out / "figures").glob("*.png"))
    assert "a_uncertainty_and_errors.png" in pngs and "f_inputs_and_states.png" in pngs
    summary = json.loads((out / "metrics.json").read_text())
    logs, scenario, _ = load_run(out, "dac")
    assert set(summary["metrics"]["dac"]) == set(run_metrics(logs, scenario))
    assert summary["table"] == []           # no baseline beside it: no paper table
    for path in [out / "figures", out / "metrics.json"]:
        (path / "a_uncertainty_and_errors.png" if path.is_dir() else path).unlink()
    assert main(["report", str(out)]) == 0
    assert (out / "figures" / "a_uncertainty_and_errors.png").is_file()
    assert (out / "metrics.json").is_file()
    assert "the comparison with the paper needs the dac and model-based runs" in (
        capsys.readouterr().out)


def test_quiet_prints_the_outcome_only(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["--quiet", "simulate", "short", "--out", str(out), "--controller",
                 "model-based", "--duration", "3"]) == 0
    captured = capsys.readouterr()
    assert "phase1." not in captured.out and "s/s" not in captured.err
    assert captured.out.splitlines()[0].startswith("model-based: ok")
    assert (out / "figures" / "e_dac_vs_model_based.png").is_file()


def test_a_rerun_replaces_every_output_of_the_run_it_replaces(tmp_path, capsys):
    """The report, the replay and verify's report of the replaced run go; verify's
    report of another controller's run stays."""
    import json
    out = tmp_path / "run"
    assert main(["simulate", "short", "--out", str(out), "--duration", "2.5",
                 "--animate"]) == 0
    (out / "verification.json").write_text(json.dumps({"controller": "dac"}))
    (out / "verification.md").write_text("stale")
    before = (out / "metrics.json").stat().st_mtime_ns
    assert main(["simulate", "short", "--out", str(out), "--duration", "2.5"]) == 0
    assert not (out / "animation_dac.html").exists()
    assert not (out / "verification.json").exists() and not (out / "verification.md").exists()
    assert (out / "metrics.json").stat().st_mtime_ns != before
    (out / "verification.json").write_text(json.dumps({"controller": "dac-nominal"}))
    assert main(["simulate", "short", "--out", str(out), "--duration", "2.5"]) == 0
    assert (out / "verification.json").exists()


@pytest.mark.parametrize("fmt", ["csv", "parquet"])
def test_export_writes_a_table_pandas_reads(tmp_path, capsys, fmt):
    import pandas as pd
    from dacph_drake.scenario.built_in import satellite_3dof_scenario
    from dacph_drake.loop.simulate import simulate
    result = simulate(satellite_3dof_scenario(), "dac", duration=0.3,
                      out_dir=tmp_path / "run")
    assert main(["export", str(tmp_path / "run"), "--format", fmt]) == 0
    path = tmp_path / "run" / f"logs_dac.{fmt}"
    frame = pd.read_csv(path, index_col="time") if fmt == "csv" else pd.read_parquet(path)
    assert len(frame) == len(result.logs["time"])
    assert frame["attitude_error_norm"].to_numpy() == pytest.approx(
        result.signals["attitude_error_norm"], rel=1e-12)
    assert main(["export", str(tmp_path / "run"), "--signals", "u", "e_tau", "--out",
                 str(tmp_path / "u.csv")]) == 0
    assert list(pd.read_csv(tmp_path / "u.csv", index_col="time").columns) == [
        "u[0]", "u[1]", "u[2]", "e_tau[0]", "e_tau[1]", "e_tau[2]"]
    assert main(["export", str(tmp_path / "run"), "--signals", "atitude_error"]) == 2
    err = capsys.readouterr().err
    assert "--signals: 'atitude_error' is not a signal of this run; did you mean" in err
    assert len(err.splitlines()) == 1


def test_a_ctrl_c_as_the_program_exits_keeps_its_status():
    """Once ``dacph`` has its exit status, a SIGINT (Ctrl-C while a sweep's pool is torn
    down at exit) leaves it: the process ends with the command's status, not by the
    signal (Python resets its own SIGINT handler to the default one as it finalizes)."""
    import signal as signals
    import subprocess
    import sys
    script = ("import os, signal, sys\n"
              "from dacph_drake.app.cli import console_main\n"
              "sys.argv = ['dacph', '--version']\n"
              "status = console_main()\n"
              "os.kill(os.getpid(), signal.SIGINT)\n"
              "sys.exit(status)\n")
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, (done.returncode, done.stderr[-1000:])
    assert done.returncode != -signals.SIGINT
