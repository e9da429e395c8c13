"""The controllers every command knows, registered once.

A controller is a Diagram with a fixed port contract (inputs: named plant signals
such as ``q``, ``qdot``, ``base_pose``; outputs: ``u`` and the logs it offers), and
its entry here is a function ``build(scenario) -> diagrams.ClosedLoop`` that calls
``diagrams.assemble_closed_loop(scenario, name, add)``, where ``add(scenario, loop,
controller)`` adds the controller's systems to ``controller.builder`` and returns them
by name (see diagrams.build_model_based_diagram, the shortest). REGISTRY maps
its name to that function, as "module:function" so that the command line can list
the names without loading Drake; `dacph simulate --controller`, `dacph diagram`,
`dacph animate`, `dacph reproduce` (which runs every registered controller), the
sweep's `controllers:` and `run.simulate` all take their names from here. To add a
controller, write that function and add one entry below."""
import importlib
from dataclasses import dataclass

from dacph_drake.errors import ConfigError


@dataclass(frozen=True)
class Controller:
    builder: str            # "module:function" returning a diagrams.ClosedLoop
    description: str        # one line, for --help and the README


REGISTRY = {
    "dac": Controller("dacph_drake.diagrams:build_dac_diagram",
                      "DAC-pH: LHS sliding mode, port observer, RHS integrator, learner"),
    "dac-nominal": Controller("dacph_drake.diagrams:build_dac_nominal_diagram",
                              "DAC-pH with the learner off (the learning ablation)"),
    "model-based": Controller("dacph_drake.diagrams:build_model_based_diagram",
                              "the LHS controller with u = B0^-1 (tau_c^r + D0 qdot)"),
}
NAMES = tuple(REGISTRY)


def require_controller(name: str) -> Controller:
    """The registered controller ``name`` (ConfigError listing the names otherwise)."""
    if name not in REGISTRY:
        raise ConfigError(f"controller = {name!r}; allowed: {', '.join(NAMES)}")
    return REGISTRY[name]


def build_closed_loop(name: str, scenario):
    """The ClosedLoop of controller ``name`` for ``scenario``."""
    module, function = require_controller(name).builder.split(":")
    return getattr(importlib.import_module(module), function)(scenario)
