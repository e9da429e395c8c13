"""The controllers every command knows: REGISTRY, name -> "module:function" (listed without
loading Drake) and its look in figures. A controller's ``build(*scenarios)`` calls
``closed_loop.assemble_closed_loop(scenarios[0], name, add, scenarios[1:])``, ``add``
adding its systems by name (the LHS via ``AddLhsSide``); model_based.py is the shortest."""
import importlib
from dataclasses import dataclass
from typing import TYPE_CHECKING

from dacph_drake.scenario.errors import require_one_of

if TYPE_CHECKING:
    from dacph_drake.controllers.closed_loop import ClosedLoop
    from dacph_drake.scenario import Scenario


@dataclass(frozen=True)
class Controller:
    """A registered controller.

    Args:
        builder: "module:function" of a function: scenarios -> closed_loop.ClosedLoop.
        description: One line, for --help.
        label: Its name in legends (empty: the registered name).
        color: Its matplotlib colour in figures.
        linestyle: Its matplotlib line style in figures."""
    builder: str
    description: str
    label: str = ""
    color: str = "C7"
    linestyle: str = "-."


REGISTRY = {
    "dac": Controller("dacph_drake.controllers.dac:build_dac_diagram",
                      "DAC-pH: LHS sliding mode, port observer, RHS integrator, learner",
                      "DAC-pH", "C0", "-"),
    "dac-nominal": Controller("dacph_drake.controllers.dac:build_dac_nominal_diagram",
                              "DAC-pH with the learner off (the learning ablation)",
                              "dac-nominal", "C4", ":"),
    "model-based": Controller("dacph_drake.controllers.model_based:"
                              "build_model_based_diagram",
                              "the LHS controller with u = B0^-1 (tau_c^r + D0 qdot)",
                              "model-based", "C1", "--"),
}
NAMES = tuple(REGISTRY)
# The controller the tables compare the others with (the paper's DAC-pH), the same
# with its learner off (the learning ablation), and the paper's baseline.
REFERENCE, ABLATION, BASELINE = "dac", "dac-nominal", "model-based"


def require_controller(name: str) -> Controller:
    """The registered Controller ``name``.

    Args:
        name: A name of REGISTRY.

    Raises:
        ConfigError: Listing the registered names."""
    require_one_of("controller", name, REGISTRY)
    return REGISTRY[name]


def build_closed_loop(name: str, *scenarios: "Scenario") -> "ClosedLoop":
    """Builds the closed loop (closed_loop.ClosedLoop) of a registered controller.

    Args:
        name: A name of REGISTRY.
        *scenarios: One scenario (a single run) or several (a batch in one diagram)."""
    module, function = require_controller(name).builder.split(":")
    return getattr(importlib.import_module(module), function)(*scenarios)
