"""The model-based baseline's RHS (docs/equations.md, SPEC settings): static inversion of the nominal RHS."""
import numpy as np
from pydrake.systems.framework import Diagram, DiagramBuilder
from pydrake.systems.primitives import MatrixGain, Multiplexer

from dacph_drake.scenario import Scenario


class ModelBasedInverter(Diagram):
    """u = B0^-1 (tau_c^r + D0 qdot); stateless (output ``u`` depends on the inputs
    ``tau_request`` and ``qdot`` only).

    It feeds the true RHS, which the integrator evaluates at every stage, so it is
    built from Drake's C++ primitives (no Python call per stage): a Multiplexer
    stacks [tau_c^r; qdot] and a MatrixGain applies [B0^-1 | B0^-1 diag(D0)].
    ``scenario``: B0 and D0 from its ``uncertainty`` section."""

    def __init__(self, scenario: Scenario):
        super().__init__()
        n = len(scenario.uncertainty.B0)
        B0_inv = np.linalg.inv(np.diag(scenario.uncertainty.B0))
        gain = np.hstack([B0_inv, B0_inv @ np.diag(scenario.uncertainty.D0)])
        builder = DiagramBuilder()
        stack = builder.AddNamedSystem("stack", Multiplexer([n, n]))
        inversion = builder.AddNamedSystem("inversion", MatrixGain(gain))
        builder.Connect(stack.get_output_port(), inversion.get_input_port())
        builder.ExportInput(stack.get_input_port(0), "tau_request")
        builder.ExportInput(stack.get_input_port(1), "qdot")
        builder.ExportOutput(inversion.get_output_port(), "u")
        builder.BuildInto(self)
