"""The ground truth's actuator for a robot from a description file: the RHS of the
port (docs/equations.md E19), as TrueRhs is for the planar arms."""
from typing import Sequence

import numpy as np
from pydrake.multibody.plant import MultibodyPlant

from dacph_drake.dynamics.kinematic_tree import KinematicTree
from dacph_drake.dynamics.plant import effort_limits, trial_coordinates
from dacph_drake.dynamics.uncertainty import TrueRhsModel
from dacph_drake.kernels.loop import (add_friction, pack_true_rhs, spatial_true_torques,
                                      stack_packs, true_matrices)
from dacph_drake.kernels.spatial import joint_momentum
from dacph_drake.scenario import Phases, Uncertainty
from dacph_drake.systems.true_rhs import RUNAWAY_RATE, TrueRhsSystem


class SpatialTrueRhs(TrueRhsSystem):
    """tau = B~(x) u - D~(x) qdot + d(t) (E19) for a robot from a description file, as
    TrueRhs (p by kernels.spatial.joint_momentum). u is clipped to the effort limits (output
    ``saturated``: 1 per clipped joint); the joints' Coulomb friction f, which Drake's plant
    does not model, acts as f tanh(qdot / FRICTION_VELOCITY), a part of D~ qdot. Output
    ``true_matrices``: [vec(B~), diag(D~)] beyond the joint damping b the plant applies.

    Args:
        plant: The batch's ground truth (finalized).
        arms: Each trial's arm as a plant of its own (kinematic tree, default inertias).
        uncertainties: Each trial's true RHS (scenario.uncertainty).
        phases: Each trial's phases.
        frictions: Each trial's joint Coulomb friction f (n) [N m] (none: zero)."""

    def __init__(self, *, plant: MultibodyPlant, arms: Sequence[MultibodyPlant],
                 uncertainties: Sequence[Uncertainty], phases: Sequence[Phases],
                 frictions: Sequence[np.ndarray] = ()):
        super().__init__()
        coordinates = trial_coordinates(plant)
        nq = plant.num_positions()
        self._indices = np.array([np.concatenate([
            c.base_q, nq + c.base_v, c.joint_q, nq + c.joint_v]) for c in coordinates])
        n = coordinates[0].num_joints
        self._effort_limit = np.array([effort_limits(plant, c.joint_v)
                                       for c in coordinates])
        trees = [KinematicTree.FromPlant(arm) for arm in arms]
        tree = trees[0]
        self._topology = (tree.base_subspace, tree.parent, tree.joint)
        self._frames = tuple(np.array([getattr(t, name) for t in trees])
                             for name in ("X_PF", "axis", "X_MC"))
        self._below = tree.below
        self._frictions = (np.array(frictions, float) if len(frictions)
                           else np.zeros((len(arms), n)))
        self._inertias = tuple(np.array(x) for x in zip(*(
            t.Inertias(arm.CreateDefaultContext()) for t, arm in zip(trees, arms))))
        self._uncertainties = [TrueRhsModel(uncertainty, phase).kernel_arguments
                               for uncertainty, phase in zip(uncertainties, phases,
                                                             strict=True)]
        self._packs, self._offsets = stack_packs([
            pack_true_rhs((), (), uncertainty) for uncertainty in self._uncertainties])
        self._u, self._state, self._disturbance_model = self.DeclareTrueRhsPorts(
            n, plant.num_positions() + plant.num_velocities(), len(coordinates))
        self.DeclareVectorOutputPort("saturated", n * len(coordinates),
                                     self._CalcSaturated,
                                     prerequisites_of_calc={self._u.ticket()})

    def _CalcTau(self, context, output):
        output.SetFromVector(spatial_true_torques(
            context.get_time(), self._state.Eval(context), self._indices,
            *self._topology, *self._frames, self._below, *self._inertias, self._frictions,
            self._u.Eval(context), self._effort_limit,
            self._disturbance_model.Eval(context), self._packs, self._offsets,
            self._Running(context), RUNAWAY_RATE, self._verdicts))
        self._Record(context)

    def _CalcSaturated(self, context, output):
        output.SetFromVector((np.abs(self._u.Eval(context)) > self._effort_limit.reshape(-1))
                             .astype(float))

    def _CalcMatrices(self, context, output):
        x, t, n = self._state.Eval(context), context.get_time(), self._n
        matrices = []
        for i, uncertainty in enumerate(self._uncertainties):
            arm = x[self._indices[i]]
            q, qdot = arm[13:13 + n], arm[13 + n:]
            p = joint_momentum(*self._topology, self._frames[0][i], self._frames[1][i],
                               self._frames[2][i], self._below,
                               *(inertia[i] for inertia in self._inertias), arm[:7],
                               arm[7:13], q, qdot)
            B, D = true_matrices(t, q, p, *uncertainty)
            add_friction(self._frictions[i], qdot, D)
            matrices += [B.reshape(-1), D]
        output.SetFromVector(np.concatenate(matrices))
