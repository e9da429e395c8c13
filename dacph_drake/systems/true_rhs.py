"""The ground truth's actuator: the RHS of the port (docs/equations.md E19)."""
from typing import Dict, Sequence, Tuple

import numpy as np
from pydrake.multibody.plant import MultibodyPlant
from pydrake.systems.framework import BasicVector, Context, InputPort, LeafSystem

from dacph_drake.dynamics.reduced_model import ReducedOrderModel
from dacph_drake.dynamics.uncertainty import TrueRhsModel
from dacph_drake.kernels.loop import (NON_FINITE, STOPPED, pack_true_rhs, stack_packs,
                                      true_matrices_of_trials, true_torques)
from dacph_drake.arm_parameters import RobotParams
from dacph_drake.dynamics.plant import MakeArmPlant, trial_coordinates
from dacph_drake.scenario import Phases, Uncertainty


RUNAWAY_RATE = 50.0     # [rad/s]: a trial whose joint or base rate exceeds it stops


class TrueRhsSystem(LeafSystem):
    """What every true RHS (TrueRhs, SpatialTrueRhs) does for the trials of its
    batch beside its torque, at every evaluation (every integrator stage), inside
    its kernel: a trial stopped by the run (Stop) gets zero torque, and so does a
    trial whose state or torque goes unsound, which is reported (Unsound), so that
    a NaN of one trial never reaches the plant that the others share."""

    def DeclareTrueRhsPorts(self, n: int, state_size: int, trials: int = 1
                            ) -> Tuple[InputPort, InputPort, InputPort]:
        """DeclareTrueRhsPorts, and the trials' running flags.

        Args:
            n: The number of joints.
            state_size: The size of the plant's state.
            trials: The number of trials of the batch.

        Returns:
            The input ports (``u``, ``state``, ``disturbance_model``)."""
        self._n, self._trials = n, trials
        # 1 for a trial that runs, 0 for one stopped (Stop): its torque is zero.
        self._running = self.DeclareNumericParameter(BasicVector(np.ones(trials)))
        self._unsound = {}                      # trial -> (reason, first time)
        self._verdicts = np.zeros(trials + 1, np.int64)      # the kernel's, per call
        self._all_running, self._any_stopped = np.ones(trials), False
        return DeclareTrueRhsPorts(self, n, state_size, trials)

    def Stop(self, context: Context, trial: int) -> None:
        """Zeroes a trial's torque from now on.

        From now on in ``context``, trial ``trial``'s torque is zero, whatever its
        inputs hold: a trial of a batch that stopped (loop.simulate) stays where it
        is while the others run on.

        Args:
            context: This system's context.
            trial: The trial's index in the batch."""
        context.get_mutable_numeric_parameter(self._running).SetAtIndex(trial, 0.0)
        self._any_stopped = True

    def Unsound(self) -> Dict[int, Tuple[str, float]]:
        """The trials whose state or torque went unsound (a non-finite value, or a
        rate beyond RUNAWAY_RATE), with the reason and the first time it was;
        their torque has been zero since. The monitor of a run reads it; it is a
        record of this diagram's simulation, not part of its state."""
        return dict(self._unsound)

    def _Running(self, context) -> np.ndarray:
        """The trials' running flags (Stop), for the kernel: read from the context
        once a trial has stopped, all ones before."""
        if not self._any_stopped:
            return self._all_running
        return context.get_numeric_parameter(self._running).get_value()

    def _Record(self, context) -> None:
        """Records the trials whose verdict (self._verdicts, written by the
        kernel: kernels.loop.RUNNING ...; its last entry the largest) is unsound."""
        if self._verdicts[-1] <= STOPPED:
            return
        t = context.get_time()
        for trial in np.flatnonzero(self._verdicts[:-1] > STOPPED):
            self._unsound.setdefault(int(trial), (
                f"non-finite plant state or torque at t = {t:.4f} s"
                if self._verdicts[trial] == NON_FINITE else
                f"runaway: a rate exceeded {RUNAWAY_RATE} rad/s at t = {t:.4f} s", t))


class TrueRhs(TrueRhsSystem):
    """tau = B~(x) u - D~(x) qdot + d(t), with x = (q, p), p = M(q) qdot of the true
    robot, for every trial of a batch (one trial: a single run). Stateless: output
    ``tau`` depends only on the inputs ``u``, ``state`` (the batch's plant's, each
    trial's part read through plant.trial_coordinates) and time (the phases and
    d(t)), so it adds no delay. It feeds the plant's actuation input and runs at
    every integrator stage, as one compiled kernel for all trials
    (kernels.loop.true_torques) that evaluates d(t) from input
    ``disturbance_model`` (DisturbanceSource's constant parameters).

    p is the joint rows of H(q_full) v (kernels.arm.joint_momentum): at zero momentum
    this equals M(q) qdot exactly (the base rows of H v are the conserved momentum).
    Output ``true_matrices``: [vec(B~) (row-major), diag(D~)] per trial, for the
    metrics. ``plant`` is the batch's ground truth (finalized); ``truths`` each
    trial's arm (RobotParams), whose mass matrix's closed form (ReducedOrderModel)
    is fitted once here; ``uncertainties`` and ``phases`` each trial's. Port sizes
    are the trials' signals stacked in trial order.

    Args:
        plant: The batch's ground truth (finalized).
        truths: Each trial's true arm (RobotParams).
        uncertainties: Each trial's true RHS (scenario.uncertainty).
        phases: Each trial's phases.
    """

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
    """Declares the ports every true RHS has (TrueRhsSystem).

    Inputs ``u`` (n per trial), ``state`` (the plant's, ``state_size``) and
    ``disturbance_model`` (DisturbanceSource's parameters); outputs ``tau`` (n per
    trial, system._CalcTau) and ``true_matrices`` (n * n + n per trial,
    system._CalcMatrices), each depending only on time, the inputs it reads and
    (tau) the parameters.

    Args:
        system: The true RHS that declares them.
        n: The number of joints.
        state_size: The size of the plant's state.
        trials: The number of trials of the batch.

    Returns:
        The three input ports (``u``, ``state``, ``disturbance_model``)."""
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
