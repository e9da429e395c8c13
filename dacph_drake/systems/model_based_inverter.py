"""The model-based baseline's RHS: static inversion of the nominal RHS (docs/equations.md)."""
from typing import Sequence

import numpy as np
from pydrake.systems.framework import Diagram, DiagramBuilder
from pydrake.systems.primitives import MatrixGain, Multiplexer

from dacph_drake.scenario import Uncertainty


class ModelBasedInverter(Diagram):
    """u = B0^-1 (tau_c^r + D0 qdot) per trial; stateless, inputs ``tau_request``, ``qdot``;
    Drake's C++ primitives, so no Python call per integrator stage.

    Args:
        uncertainties: Each trial's uncertainty (its nominal B0 and D0)."""

    def __init__(self, *, uncertainties: Sequence[Uncertainty]):
        super().__init__()
        inverses = [np.linalg.inv(np.diag(u.B0)) for u in uncertainties]
        n, trials = len(inverses[0]), len(inverses)
        size = n * trials
        gain = np.zeros((size, 2 * size))
        for i, (B0_inv, u) in enumerate(zip(inverses, uncertainties)):
            rows = slice(i * n, (i + 1) * n)
            gain[rows, rows] = B0_inv
            gain[rows, size + i * n:size + (i + 1) * n] = B0_inv @ np.diag(u.D0)
        builder = DiagramBuilder()
        stack = builder.AddNamedSystem("stack", Multiplexer([size, size]))
        inversion = builder.AddNamedSystem("inversion", MatrixGain(gain))
        builder.Connect(stack.get_output_port(), inversion.get_input_port())
        builder.ExportInput(stack.get_input_port(0), "tau_request")
        builder.ExportInput(stack.get_input_port(1), "qdot")
        builder.ExportOutput(inversion.get_output_port(), "u")
        builder.BuildInto(self)
