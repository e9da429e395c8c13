"""The ground truth's actuator: the RHS of the port (docs/equations.md E19)."""
import numpy as np
from pydrake.multibody.plant import MultibodyPlant
from pydrake.systems.framework import LeafSystem

from dacph_drake.dynamics.reduced_model import ReducedOrderModel
from dacph_drake.dynamics.uncertainty import TrueRhsModel
from dacph_drake.kernels.arm import joint_momentum
from dacph_drake.kernels.loop import pack_true_rhs, true_matrices, true_torque
from dacph_drake.dynamics.plant import ArmCoordinates
from dacph_drake.scenario import Phases, Uncertainty


class TrueRhs(LeafSystem):
    """tau = B~(x) u - D~(x) qdot + d(t), with x = (q, p), p = M(q) qdot of the true
    robot. Stateless: output ``tau`` depends only on the inputs ``u``, ``state`` (the
    plant's, read through plant.ArmCoordinates) and time (the phases and d(t)), so it adds no delay. It feeds the
    plant's actuation input and runs at every integrator stage, as one compiled
    kernel (kernels.loop.true_torque) that evaluates d(t) from input
    ``disturbance_model`` (DisturbanceSource's constant parameters).

    p is the joint rows of H(q_full) v (kernels.arm.joint_momentum): at zero momentum
    this equals M(q) qdot exactly (the base rows of H v are the conserved momentum).
    Output ``true_matrices``: [vec(B~) (row-major), diag(D~)] for the metrics.
    ``plant`` is the planar ground truth (finalized): its mass matrix's closed form
    (ReducedOrderModel) is fitted once here."""

    def __init__(self, *, plant: MultibodyPlant, uncertainty: Uncertainty,
                 phases: Phases):
        super().__init__()
        model = ReducedOrderModel(plant)
        n = model.num_joints
        self._coordinates = ArmCoordinates.FromPlant(model.plant)
        self._indices = self._coordinates.StateIndices()
        self._representation = model.trigonometric_representation
        self._uncertainty = TrueRhsModel(uncertainty, phases).kernel_arguments
        self._packed = pack_true_rhs(*self._representation, self._uncertainty)
        self._u, self._state, self._disturbance_model = DeclareTrueRhsPorts(
            self, n, model.plant.num_positions() + model.plant.num_velocities())

    def _CalcTau(self, context, output):
        output.SetFromVector(true_torque(context.get_time(), self._state.Eval(context),
                                         self._indices, self._u.Eval(context),
                                         self._disturbance_model.Eval(context),
                                         self._packed))

    def _CalcMatrices(self, context, output):
        base_pose, q, base_velocity, qdot = self._coordinates.Split(
            self._state.Eval(context))
        B, D = true_matrices(context.get_time(), q,
                             joint_momentum(base_pose[2], base_velocity, q, qdot,
                                            *self._representation),
                             *self._uncertainty)
        output.SetFromVector(np.concatenate([B.reshape(-1), D]))


def DeclareTrueRhsPorts(system: LeafSystem, n: int, state_size: int):
    """The ports every true RHS has (TrueRhs, SpatialTrueRhs): inputs ``u`` (n),
    ``state`` (the plant's, ``state_size``) and ``disturbance_model``
    (DisturbanceSource's parameters); outputs ``tau`` (n, system._CalcTau) and
    ``true_matrices`` (n * n + n, system._CalcMatrices), each depending only on
    time and the inputs it reads. Returns the three input ports."""
    u = system.DeclareVectorInputPort("u", n)
    state = system.DeclareVectorInputPort("state", state_size)
    disturbance_model = system.DeclareVectorInputPort("disturbance_model", 3 + 5 * n)
    system.DeclareVectorOutputPort("tau", n, system._CalcTau, prerequisites_of_calc={
        system.time_ticket(), u.ticket(), state.ticket(), disturbance_model.ticket()})
    system.DeclareVectorOutputPort(
        "true_matrices", n * n + n, system._CalcMatrices,
        prerequisites_of_calc={system.time_ticket(), state.ticket()})
    return u, state, disturbance_model
