"""The ground truth's actuator: the RHS of the port (docs/equations.md E19)."""
from typing import Dict, Sequence, Tuple

import numpy as np
from pydrake.multibody.plant import MultibodyPlant
from pydrake.systems.framework import BasicVector, Context, InputPort, LeafSystem

from dacph_drake.dynamics.reduced_model import ReducedOrderModel
from dacph_drake.dynamics.uncertainty import TrueRhsModel
from dacph_drake.kernels.loop import (NON_FINITE, STOPPED, pack_true_rhs, stack_packs,
                                      true_matrices_of_trials, true_torques)
from dacph_drake.scenario.planar_arm import RobotParams
from dacph_drake.dynamics.plant import MakeArmPlant, trial_coordinates
from dacph_drake.scenario import Phases, Uncertainty


RUNAWAY_RATE = 50.0     # [rad/s]: a trial whose joint or base rate exceeds it stops


class TrueRhsSystem(LeafSystem):
    """Base of the true RHSs: a stopped or unsound trial gets zero torque in the kernel."""

    def DeclareTrueRhsPorts(self, n: int, state_size: int, trials: int = 1
                            ) -> Tuple[InputPort, InputPort, InputPort]:
        """Declares the ports (DeclareTrueRhsPorts; returns its inputs) and running flags.

        Args:
            n: The number of joints.
            state_size: The size of the plant's state.
            trials: The number of trials of the batch."""
        self._n, self._trials = n, trials
        # 1 for a trial that runs, 0 for one stopped (Stop): its torque is zero.
        self._running = self.DeclareNumericParameter(BasicVector(np.ones(trials)))
        self._unsound = {}                      # trial -> (reason, first time)
        self._verdicts = np.zeros(trials + 1, np.int64)      # the kernel's, per call
        self._all_running, self._any_stopped = np.ones(trials), False
        return DeclareTrueRhsPorts(self, n, state_size, trials)

    def Stop(self, context: Context, trial: int) -> None:
        """Zeroes trial ``trial``'s torque from now on: it stays put while the others run.

        Args:
            context: This system's context.
            trial: The trial's index in the batch."""
        context.get_mutable_numeric_parameter(self._running).SetAtIndex(trial, 0.0)
        self._any_stopped = True

    def Unsound(self) -> Dict[int, Tuple[str, float]]:
        """Trial -> (reason, first time [s]) of trials gone unsound (torque zero since)."""
        return dict(self._unsound)

    def _Running(self, context) -> np.ndarray:
        """The trials' running flags (Stop), for the kernel."""
        if not self._any_stopped:
            return self._all_running
        return context.get_numeric_parameter(self._running).get_value()

    def _Record(self, context) -> None:
        """Records the trials whose kernel verdict is unsound."""
        if self._verdicts[-1] <= STOPPED:
            return
        t = context.get_time()
        for trial in np.flatnonzero(self._verdicts[:-1] > STOPPED):
            self._unsound.setdefault(int(trial), (
                f"non-finite plant state or torque at t = {t:.4f} s"
                if self._verdicts[trial] == NON_FINITE else
                f"runaway: a rate exceeded {RUNAWAY_RATE} rad/s at t = {t:.4f} s", t))


class TrueRhs(TrueRhsSystem):
    """tau = B~(x) u - D~(x) qdot + d(t) (E19), x = (q, p), p = M(q) qdot of the true robot
    (H(q_full) v's joint rows); one stateless kernel for all trials; also ``true_matrices``.

    Args:
        plant: The batch's ground truth (finalized).
        truths: Each trial's true arm (RobotParams).
        uncertainties: Each trial's true RHS (scenario.uncertainty).
        phases: Each trial's phases."""

    def __init__(self, *, plant: MultibodyPlant, truths: Sequence[RobotParams],
                 uncertainties: Sequence[Uncertainty], phases: Sequence[Phases]):
        super().__init__()
        models = [ReducedOrderModel(MakeArmPlant(truth)) for truth in truths]
        n = models[0].num_joints
        self._indices = np.array([coordinates.StateIndices()
                                  for coordinates in trial_coordinates(plant)])
        self._packs, self._offsets = stack_packs([
            pack_true_rhs(*model.trigonometric_representation,
                          TrueRhsModel(uncertainty, phase).kernel_arguments)
            for model, uncertainty, phase in zip(models, uncertainties, phases,
                                                 strict=True)])
        self._u, self._state, self._disturbance_model = self.DeclareTrueRhsPorts(
            n, plant.num_positions() + plant.num_velocities(), len(models))

    def _CalcTau(self, context, output):
        output.SetFromVector(true_torques(
            context.get_time(), self._state.Eval(context), self._indices,
            self._u.Eval(context), self._disturbance_model.Eval(context),
            self._packs, self._offsets, self._Running(context), RUNAWAY_RATE,
            self._verdicts))
        self._Record(context)

    def _CalcMatrices(self, context, output):
        output.SetFromVector(true_matrices_of_trials(
            context.get_time(), self._state.Eval(context), self._indices, self._packs,
            self._offsets, self._n))


def DeclareTrueRhsPorts(system: LeafSystem, n: int, state_size: int, trials: int = 1
                        ) -> Tuple[InputPort, InputPort, InputPort]:
    """Declares a true RHS's ports and returns its inputs ``u``, ``state``,
    ``disturbance_model``; outputs ``tau``, ``true_matrices`` (on time, inputs, parameters).

    Args:
        system: The true RHS that declares them.
        n: The number of joints.
        state_size: The size of the plant's state.
        trials: The number of trials of the batch."""
    u = system.DeclareVectorInputPort("u", trials * n)
    state = system.DeclareVectorInputPort("state", state_size)
    disturbance_model = system.DeclareVectorInputPort("disturbance_model",
                                                      trials * (3 + 5 * n))
    system.DeclareVectorOutputPort("tau", trials * n, system._CalcTau,
                                   prerequisites_of_calc={
        system.time_ticket(), u.ticket(), state.ticket(), disturbance_model.ticket(),
        system.all_parameters_ticket()})
    system.DeclareVectorOutputPort(
        "true_matrices", trials * (n * n + n), system._CalcMatrices,
        prerequisites_of_calc={system.time_ticket(), state.ticket()})
    return u, state, disturbance_model
