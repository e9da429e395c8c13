"""The controller registry is the one place a controller is named: every command,
the reproduction and the sweeps take their controllers from it."""
import numpy as np
import pytest

from dacph_drake import controllers
from dacph_drake.cli import main
from dacph_drake.errors import ConfigError


def test_every_command_offers_exactly_the_registered_controllers(capsys):
    names = tuple(controllers.REGISTRY)
    from dacph_drake.montecarlo.definition import Sweep
    from dacph_drake.reproduce import CONTROLLERS
    assert CONTROLLERS == names
    assert tuple(Sweep().controllers) == names
    for command in (["simulate", "short", "--out", "x"], ["diagram", "short"],
                    ["animate", "run"]):
        with pytest.raises(SystemExit):
            main([*command, "--controller", "no-such-controller"])
        assert "{" + ",".join(names) + "}" in capsys.readouterr().err


def test_every_registered_controller_builds_a_closed_loop():
    from dacph_drake.diagrams import ClosedLoop
    from dacph_drake.scenario import short_scenario
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
    from dacph_drake.diagrams import assemble_closed_loop

    def add(scenario, loop, controller):
        damper = controller.builder.AddNamedSystem(
            "damper", Gain(-0.01, scenario.robot.num_links))
        controller.Input(damper.get_input_port(), "qdot")
        controller.builder.ExportOutput(damper.get_output_port(), "u")
        return {"damper": damper}
    return assemble_closed_loop(scenario, "hold_still", add)


def test_a_new_controller_is_one_function_and_one_registry_line(monkeypatch):
    from dacph_drake.run import simulate
    from dacph_drake.scenario import short_scenario
    monkeypatch.setitem(controllers.REGISTRY, "hold-still", controllers.Controller(
        "test_controllers:build_hold_still_diagram", "a joint damper"))
    result = simulate(short_scenario(), "hold-still", duration=0.2)
    assert result.status == "ok" and result.final_time == pytest.approx(0.2)
    assert {"state", "tau", "u"} <= set(result.logs)
    # u = -0.01 qdot, logged from the controller's own output.
    n = short_scenario().robot.num_links
    qdot = result.logs["state"][:, -n:]
    assert np.allclose(result.logs["u"], -0.01 * qdot)
