"""The controller registry is the one place a controller is named: every command,
the reproduction and the sweeps take their controllers from it."""
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
