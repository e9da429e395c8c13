"""The model-based baseline's RHS (SPEC section 7): static inversion of the nominal RHS."""
import numpy as np
from pydrake.systems.framework import LeafSystem

from dacph_drake.scenario import Scenario


class ModelBasedInverter(LeafSystem):
    """u = B0^-1 (tau_c^r + D0 qdot); stateless (output ``u`` depends on the inputs
    ``tau_request`` and ``state`` only)."""

    def __init__(self, scenario: Scenario, num_positions: int):
        super().__init__()
        n = scenario.robot.num_links
        self._B0_inv = np.linalg.inv(np.diag(scenario.uncertainty.B0))
        self._D0 = np.asarray(scenario.uncertainty.D0, float)
        self._joint_v = slice(num_positions + 3, 2 * num_positions)
        self._tau_request = self.DeclareVectorInputPort("tau_request", n)
        self._state = self.DeclareVectorInputPort("state", 2 * num_positions)
        self.DeclareVectorOutputPort(
            "u", n, self._CalcU,
            prerequisites_of_calc={self._tau_request.ticket(), self._state.ticket()})

    def _CalcU(self, context, output):
        qdot = self._state.Eval(context)[self._joint_v]
        output.SetFromVector(self._B0_inv @ (self._tau_request.Eval(context)
                                             + self._D0 * qdot))
