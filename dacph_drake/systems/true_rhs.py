"""The ground truth's actuator: the RHS of the port (paper eq. "RHS", SPEC section 7)."""
import numpy as np
from pydrake.systems.framework import LeafSystem

from dacph_drake.kernels.arm import joint_momentum
from dacph_drake.kernels.loop import pack_true_rhs, true_matrices, true_torque
from dacph_drake.plant import ArmCoordinates, MakeArmPlant
from dacph_drake.reduced_model import ReducedOrderModel
from dacph_drake.scenario import Scenario
from dacph_drake.uncertainty import TrueRhsModel


class TrueRhs(LeafSystem):
    """tau = B~(x) u - D~(x) qdot + d(t), with x = (q, p), p = M(q) qdot of the true
    robot. Stateless: output ``tau`` depends only on the inputs ``u``, ``state`` (the
    plant's) and time (the phases and d(t)), so it adds no delay. It feeds the
    plant's actuation input and runs at every integrator stage, as one compiled
    kernel (kernels.loop.true_torque) that evaluates d(t) from input
    ``disturbance_model`` (DisturbanceSource's constant parameters).

    p is the joint rows of H(q_full) v (kernels.arm.joint_momentum): at zero momentum
    this equals M(q) qdot exactly (the base rows of H v are the conserved momentum).
    Output ``true_matrices``: [vec(B~) (row-major), diag(D~)] for the metrics."""

    def __init__(self, scenario: Scenario):
        super().__init__()
        n = scenario.robot.num_links
        model = ReducedOrderModel(MakeArmPlant(scenario.robot))
        nq = model.plant.num_positions()
        # The layout every controller system reads: base (x, y, theta0) first.
        assert np.array_equal(ArmCoordinates.FromPlant(model.plant).joint_v,
                              np.arange(3, nq))
        self._nq = nq
        self._representation = model.trigonometric_representation
        self._uncertainty = TrueRhsModel(scenario.uncertainty, scenario.phases).kernel_arguments
        self._u = self.DeclareVectorInputPort("u", n)
        self._state = self.DeclareVectorInputPort("state", 2 * nq)
        self._disturbance_model = self.DeclareVectorInputPort("disturbance_model",
                                                              3 + 5 * n)
        self._packed = None        # pack_true_rhs(...), once the model is known
        tickets = {self.time_ticket(), self._u.ticket(), self._state.ticket()}
        self.DeclareVectorOutputPort("tau", n, self._CalcTau, prerequisites_of_calc=tickets)
        self.DeclareVectorOutputPort(
            "true_matrices", n * n + n, self._CalcMatrices,
            prerequisites_of_calc={self.time_ticket(), self._state.ticket()})

    def _CalcTau(self, context, output):
        if self._packed is None:   # the parameters of d(t) are constant
            self._packed = pack_true_rhs(*self._representation,
                                         self._disturbance_model.Eval(context),
                                         self._uncertainty)
        output.SetFromVector(true_torque(context.get_time(), self._state.Eval(context),
                                         self._u.Eval(context), self._packed))

    def _CalcMatrices(self, context, output):
        x = self._state.Eval(context)
        B, D = true_matrices(context.get_time(), x[3:self._nq],
                             joint_momentum(x, *self._representation), *self._uncertainty)
        output.SetFromVector(np.concatenate([B.reshape(-1), D]))
