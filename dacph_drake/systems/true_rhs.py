"""The ground truth's actuator: the RHS of the port (paper eq. "RHS", SPEC section 7)."""
import numpy as np
from pydrake.systems.framework import LeafSystem

from dacph_drake.plant import ArmCoordinates, MakeArmPlant
from dacph_drake.scenario import Scenario
from dacph_drake.uncertainty import TrueRhsModel


class TrueRhs(LeafSystem):
    """tau = B~(x) u - D~(x) qdot + d, with x = (q, p), p = M(q) qdot of the true
    robot. Stateless: output ``tau`` depends only on the inputs ``u``, ``state`` (the
    plant's), ``disturbance`` and time (the phases), so it adds no delay.

    p is the joint rows of H(q_full) v: at zero momentum this equals M(q) qdot exactly
    (the base rows of H v are the conserved momentum).
    Output ``true_matrices``: [vec(B~) (row-major), diag(D~)] for the metrics."""

    def __init__(self, scenario: Scenario):
        super().__init__()
        n = scenario.robot.num_links
        self._plant = MakeArmPlant(scenario.robot)
        self._plant_context = self._plant.CreateDefaultContext()
        self._nq = self._plant.num_positions()
        # The layout every controller system reads: base (x, y, theta0) first.
        assert np.array_equal(ArmCoordinates.FromPlant(self._plant).joint_v,
                              np.arange(3, self._nq))
        self._model = TrueRhsModel(scenario.uncertainty, scenario.phases)
        self._u = self.DeclareVectorInputPort("u", n)
        self._state = self.DeclareVectorInputPort("state", 2 * self._nq)
        self._d = self.DeclareVectorInputPort("disturbance", n)
        tickets = {self.time_ticket(), self._u.ticket(), self._state.ticket(),
                   self._d.ticket()}
        self.DeclareVectorOutputPort("tau", n, self._CalcTau, prerequisites_of_calc=tickets)
        self.DeclareVectorOutputPort(
            "true_matrices", n * n + n, self._CalcMatrices,
            prerequisites_of_calc={self.time_ticket(), self._state.ticket()})

    def _Matrices(self, context):
        x = self._state.Eval(context)
        nq = self._nq
        self._plant.SetPositions(self._plant_context, x[:nq])
        p = self._plant.CalcMassMatrix(self._plant_context)[3:] @ x[nq:]
        B, D = self._model.Matrices(context.get_time(), x[3:nq], p)
        return B, D, x[nq + 3:]

    def _CalcTau(self, context, output):
        B, D, qdot = self._Matrices(context)
        output.SetFromVector(B @ self._u.Eval(context) - D * qdot
                             + self._d.Eval(context))

    def _CalcMatrices(self, context, output):
        B, D, _ = self._Matrices(context)
        output.SetFromVector(np.concatenate([B.reshape(-1), D]))
