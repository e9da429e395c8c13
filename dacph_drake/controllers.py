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

from dacph_drake.errors import require_one_of


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
# The same controllers for spatial robots (spatial_diagrams.py; `dacph spatial
# --controller`), each returning a spatial_diagrams.SpatialLoop.
SPATIAL_REGISTRY = {
    "dac": Controller("dacph_drake.spatial_diagrams:build_spatial_dac_diagram",
                      REGISTRY["dac"].description),
    "dac-nominal": Controller(
        "dacph_drake.spatial_diagrams:build_spatial_dac_nominal_diagram",
        REGISTRY["dac-nominal"].description),
    "model-based": Controller(
        "dacph_drake.spatial_diagrams:build_spatial_model_based_diagram",
        REGISTRY["model-based"].description),
}


def require_controller(name: str, registry=REGISTRY) -> Controller:
    """The registered controller ``name`` (ConfigError listing the names otherwise)."""
    require_one_of("controller", name, registry)
    return registry[name]


def build_closed_loop(name: str, scenario, registry=REGISTRY):
    """The loop of controller ``name`` for ``scenario`` (a ClosedLoop; a
    SpatialLoop with registry=SPATIAL_REGISTRY)."""
    module, function = require_controller(name, registry).builder.split(":")
    return getattr(importlib.import_module(module), function)(scenario)
