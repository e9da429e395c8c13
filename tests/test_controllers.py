"""The controller registry is the one place a controller is named: every command,
the reproduction and the sweeps take their controllers from it."""
import numpy as np
import pytest

from dacph_drake import controllers
from dacph_drake.app.cli import main
from dacph_drake.scenario.errors import ConfigError


def test_every_command_offers_exactly_the_registered_controllers(capsys):
    names = tuple(controllers.REGISTRY)
    from dacph_drake.montecarlo.definition import Sweep
    from dacph_drake.app.reproduce import CONTROLLERS
    assert CONTROLLERS == names
    assert tuple(Sweep().controllers) == names
    for command in (["simulate", "short", "--out", "x"], ["diagram", "short"],
                    ["animate", "run"]):
        with pytest.raises(SystemExit):
            main([*command, "--controller", "no-such-controller"])
        assert "{" + ",".join(names) + "}" in capsys.readouterr().err


def test_every_registered_controller_builds_a_closed_loop():
    from dacph_drake.controllers.closed_loop import ClosedLoop
    from dacph_drake.scenario.built_in import short_scenario
    for name in controllers.REGISTRY:
        loop = controllers.build_closed_loop(name, short_scenario())
        assert isinstance(loop, ClosedLoop) and loop.diagram is not None


def test_an_unknown_controller_is_named():
    with pytest.raises(ConfigError, match=r"controller = 'pid'; allowed: dac, "
                                          r"dac-nominal, model-based"):
        controllers.build_closed_loop("pid", None)


def build_hold_still_diagram(scenario):
    """A new controller written against the port contract: u = -0.01 qdot (a joint
    damper), in a few lines."""
    from pydrake.systems.primitives import Gain
    from dacph_drake.controllers.closed_loop import assemble_closed_loop

    def add(loop, controller):
        damper = controller.builder.AddNamedSystem(
            "damper", Gain(-0.01, loop.robot.num_joints))
        controller.Input(damper.get_input_port(), "qdot")
        controller.builder.ExportOutput(damper.get_output_port(), "u")
        return {"damper": damper}
    return assemble_closed_loop(scenario, "hold_still", add)


def test_a_new_controller_is_one_function_and_one_registry_line(monkeypatch):
    from dacph_drake.loop.simulate import simulate
    from dacph_drake.scenario.built_in import short_scenario
    monkeypatch.setitem(controllers.REGISTRY, "hold-still", controllers.Controller(
        "test_controllers:build_hold_still_diagram", "a joint damper"))
    result = simulate(short_scenario(), "hold-still", duration=0.2)
    assert result.status == "ok" and result.final_time == pytest.approx(0.2)
    assert {"state", "tau", "u"} <= set(result.logs)
    # u = -0.01 qdot, logged from the controller's own output.
    n = short_scenario().robot.truth.num_links
    qdot = result.logs["state"][:, -n:]
    assert np.allclose(result.logs["u"], -0.01 * qdot)


def build_dac_well_damped_diagram(scenario):
    """A new controller as a researcher writes one, in its own module: DAC-pH whose
    RHS loop decays as fast as its period allows (rhs.gain_rule well_damped)."""
    import copy
    from dacph_drake.controllers.dac import build_dac_diagram
    variant = copy.deepcopy(scenario)
    variant.rhs.gain_rule = "well_damped"
    return build_dac_diagram(variant)


def _register(monkeypatch, name: str, entry) -> None:
    """controllers.REGISTRY[name] = entry, as an added line there would be seen by
    the modules that read the names at import."""
    import dacph_drake.app.cli
    import dacph_drake.montecarlo.definition
    import dacph_drake.app.reproduce
    monkeypatch.setitem(controllers.REGISTRY, name, entry)
    names = tuple(controllers.REGISTRY)
    monkeypatch.setattr(controllers, "NAMES", names)
    for module in (dacph_drake.app.cli, dacph_drake.montecarlo.definition,
                   dacph_drake.app.reproduce):
        monkeypatch.setattr(module, "CONTROLLERS", names)


def _tiny(robot: str):
    """A planar or a described arm's scenario of 0.2 + 0.3 + 0.3 + 0.3 s."""
    from dacph_drake.scenario import Phases
    from dacph_drake.assembly.scenario_files import load_scenario
    scenario = load_scenario({"planar": "short", "described": "satellite_3dof"}[robot])
    scenario.phases = Phases(warmup=0.2, linear=0.3, nonlinear=0.3, disturbance=0.3)
    return scenario


@pytest.mark.parametrize("robot", ["planar", "described"])
def test_a_new_controller_appears_in_every_command(robot, tmp_path, monkeypatch,
                                                   capsys):
    """One function and one registry entry: `dacph simulate --controller`, `dacph
    reproduce` (its ablation rows and the comparison panel's legend), a sweep's
    summary and `dacph verify --controller` take it, on a planar and on a described
    arm alike."""
    import json
    from dacph_drake.app.figures import make_panels
    from dacph_drake.montecarlo.definition import load_sweep
    from dacph_drake.montecarlo.executors import InProcessExecutor
    from dacph_drake.montecarlo.runner import run_sweep
    from dacph_drake.montecarlo.summary import write_summary
    from dacph_drake.loop.run_store import load_logs
    from dacph_drake.assembly.scenario_files import load_scenario, save_scenario
    name = "dac-well-damped"
    _register(monkeypatch, name, controllers.Controller(
        "test_controllers:build_dac_well_damped_diagram",
        "DAC-pH with the well-damped gain rule"))
    scenario = _tiny(robot)
    save_scenario(scenario, tmp_path / "s.yaml")
    single = tmp_path / "single"
    assert main(["simulate", str(tmp_path / "s.yaml"), "--out", str(single),
                 "--controller", name]) == 0
    assert json.loads((single / f"run_{name}.json").read_text())["status"] == "ok"
    assert main(["verify", str(single), "--controller", name]) in (0, 1)
    assert (single / "verification.json").is_file()
    out = tmp_path / "reproduced"
    assert main(["reproduce", str(tmp_path / "s.yaml"), "--out", str(out)]) == 0
    ablation = json.loads((out / "metrics.json").read_text())["ablation"]
    assert f"RMS alpha~, {name}" in [row["metric"] for row in ablation]
    runs = {c: load_logs(out, c) for c in controllers.NAMES}
    panel = make_panels(runs, load_scenario(out / "scenario.yaml"))[
        {"planar": "e_dac_vs_model_based",
         "described": "e_attitude_dac_vs_model_based"}[robot]]
    legend = [text.get_text() for ax in panel.axes if ax.get_legend()
              for text in ax.get_legend().get_texts()]
    assert name in legend
    (tmp_path / "sweep.yaml").write_text(
        f"scenario: s.yaml\ntrials: 1\ncontrollers: [{name}]\ndistributions:\n"
        "  delta_D_scale: !Uniform {min: 0.5, max: 1.5}\n")
    definition = load_sweep(tmp_path / "sweep.yaml")
    rows = run_sweep(definition, tmp_path / "sweep", InProcessExecutor(), 1)
    assert rows[0]["runs"][name]["status"] == "ok"
    summary = write_summary(tmp_path / "sweep", definition)
    assert summary["controllers"][name]["succeeded"] == 1
