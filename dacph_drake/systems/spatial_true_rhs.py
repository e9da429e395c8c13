"""The ground truth's actuator for a robot from a description file: the RHS of the
port (docs/equations.md E19), as TrueRhs is for the planar arms."""
import numpy as np
from pydrake.multibody.plant import MultibodyPlant

from dacph_drake.kernels.loop import pack_true_rhs, spatial_true_torque, true_matrices
from dacph_drake.dynamics.plant import ArmCoordinates, effort_limits, joint_damping
from dacph_drake.scenario import Phases, Uncertainty
from dacph_drake.systems.true_rhs import RUNAWAY_RATE, TrueRhsSystem
from dacph_drake.dynamics.uncertainty import TrueRhsModel


class SpatialTrueRhs(TrueRhsSystem):
    """tau = B~(x) u - D~(x) qdot + d(t), with x = (q, p) and p the joint rows of
    H(q_full) v, which at zero momentum is M(q) qdot exactly (the base rows of H v
    are the conserved momentum). B~, D~ (uncertainty.TrueRhsModel) and d(t)
    (DisturbanceSource's parameters, input ``disturbance_model``) are the planar
    ground truth's compiled kernels, which hold for any number of joints.

    Stateless: output ``tau`` depends only on the inputs ``u``, ``state`` (the
    plant's) and time, so it adds no delay; it feeds the plant's actuation input.
    u is clipped to the actuators' effort limits (scenario.DescribedArm.effort_limits;
    output ``saturated``: 1 for each joint whose command was clipped).
    Output ``true_matrices`` = [vec(B~) (row-major), diag(D~)] for the metrics, D~
    with the description's joint damping, which the plant applies itself
    (scenario.DescribedArm.joint_damping "keep"; zero otherwise).
    ``plant`` is the ground truth (finalized); the scratch context for its mass
    matrix is made here."""

    def __init__(self, *, plant: MultibodyPlant, uncertainty: Uncertainty,
                 phases: Phases):
        super().__init__()
        self._plant = plant
        self._context = plant.CreateDefaultContext()
        coordinates = ArmCoordinates.FromPlant(plant)
        self._q_index = coordinates.joint_q
        self._v_index = coordinates.joint_v
        self._nq = plant.num_positions()
        n = coordinates.num_joints
        self._joint_damping = joint_damping(plant, self._v_index)
        self._effort_limit = effort_limits(plant, self._v_index)
        self._uncertainty = TrueRhsModel(uncertainty, phases).kernel_arguments
        self._packed = pack_true_rhs((), (), self._uncertainty)
        self._u, self._state, self._disturbance_model = self.DeclareTrueRhsPorts(
            n, plant.num_positions() + plant.num_velocities())
        self.DeclareVectorOutputPort("saturated", n, self._CalcSaturated,
                                     prerequisites_of_calc={self._u.ticket()})

    def _StateAndMassMatrix(self, context):
        """(x, H): the input plant state and the plant's mass matrix there."""
        x = self._state.Eval(context)
        self._plant.SetPositionsAndVelocities(self._context, x)
        return x, self._plant.CalcMassMatrix(self._context)

    def _Matrices(self, context):
        """(B~, diag D~, qdot) at the context's time and input state."""
        x, H = self._StateAndMassMatrix(context)
        v = x[self._nq:]
        p = (H @ v)[self._v_index]
        B, D = true_matrices(context.get_time(), x[self._q_index], p, *self._uncertainty)
        return B, D, v[self._v_index]

    def _CalcTau(self, context, output):
        x, H = self._StateAndMassMatrix(context)
        output.SetFromVector(spatial_true_torque(
            context.get_time(), x, H, self._q_index, self._v_index,
            self._u.Eval(context), self._effort_limit,
            self._disturbance_model.Eval(context), self._packed,
            self._Running(context), RUNAWAY_RATE, self._verdicts))
        self._Record(context)

    def _CalcSaturated(self, context, output):
        output.SetFromVector((np.abs(self._u.Eval(context)) > self._effort_limit)
                             .astype(float))

    def _CalcMatrices(self, context, output):
        B, D, _ = self._Matrices(context)
        output.SetFromVector(np.concatenate([B.reshape(-1), D + self._joint_damping]))
