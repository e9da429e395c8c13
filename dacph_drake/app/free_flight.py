"""A passive free-flight check of the ground truth: under torques a_k cos(w_k t) the total
momentum must stay zero and the kinetic energy equal the torques' work."""
from dataclasses import dataclass
from typing import Sequence

import numpy as np
from pydrake.multibody.plant import MultibodyPlant
from pydrake.systems.framework import (Context, ContinuousState, DiagramBuilder,
                                       LeafSystem)
from pydrake.systems.primitives import Sine

from dacph_drake.dynamics.plant import (AddFreeFloatingArm, ArmCoordinates, SetArmAtRest,
                               total_momentum)
from dacph_drake.scenario.planar_arm import RobotParams
from dacph_drake.scenario.simulator import MakeSimulator
from dacph_drake.scenario.simulator import FixedStepConfig


class WorkMeter(LeafSystem):
    """Continuous state W, dW/dt = tau^T qdot (inputs ``tau`` and ``state``, the plant's).

    Args:
        plant: The free-floating arm (finalized)."""

    def __init__(self, plant: MultibodyPlant):
        super().__init__()
        self._joint_v = plant.num_positions() + ArmCoordinates.FromPlant(plant).joint_v
        self._tau = self.DeclareVectorInputPort("tau", plant.num_actuators())
        self._state = self.DeclareVectorInputPort("state", plant.num_multibody_states())
        self.DeclareContinuousState(1)

    def DoCalcTimeDerivatives(self, context: Context,
                              derivatives: ContinuousState) -> None:
        """d/dt W = tau . qdot, the power the joint torques put in.

        Args:
            context: This system's context.
            derivatives: Where d/dt W goes."""
        power = self._tau.Eval(context) @ self._state.Eval(context)[self._joint_v]
        derivatives.get_mutable_vector().SetAtIndex(0, power)


@dataclass
class FreeFlightResult:
    """The outcome of run_free_flight.

    Attributes:
        max_momentum: max over samples of |(h_A_z, h_L_x, h_L_y)|_inf.
        kinetic_energy: The kinetic energy at the end [J].
        work: The work done by the torques [J].
        min_clearance: The smallest signed distance between non-adjacent bodies [m]."""
    max_momentum: float     # max over samples of |(h_A_z, h_L_x, h_L_y)|_inf
    kinetic_energy: float   # [J] at the end
    work: float             # [J] done by the torques
    min_clearance: float    # [m] smallest signed distance between non-adjacent bodies


def run_free_flight(robot: RobotParams, duration: float, amplitudes: Sequence[float],
                    frequencies: Sequence[float], q0: Sequence[float],
                    integration_scheme: str = "runge_kutta3", step: float = 2.5e-4,
                    time_step: float = 0.0) -> FreeFlightResult:
    """Simulates ``duration`` seconds of free flight from rest.

    Args:
        robot: The arm.
        duration: The simulated time [s].
        amplitudes: The torques' amplitudes a_k [N m] (n).
        frequencies: The torques' frequencies w_k [rad/s] (n).
        q0: The initial joint angles [rad] (n).
        integration_scheme: The fixed-step integrator (FixedStepConfig).
        step: Its step [s].
        time_step: > 0: Drake's discrete plant with this step [s] (W then not tracked)."""
    n = robot.num_links
    builder = DiagramBuilder()
    plant, scene_graph = AddFreeFloatingArm(builder, robot, time_step)
    torque = builder.AddSystem(Sine(np.asarray(amplitudes, float),
                                    np.asarray(frequencies, float),
                                    np.full(n, np.pi / 2), n))
    builder.Connect(torque.get_output_port(0), plant.get_actuation_input_port())
    meter = builder.AddSystem(WorkMeter(plant))
    builder.Connect(torque.get_output_port(0), meter.get_input_port(0))
    builder.Connect(plant.get_state_output_port(), meter.get_input_port(1))
    simulator = MakeSimulator(builder.Build(), FixedStepConfig(integration_scheme, step))
    context = simulator.get_mutable_context()
    plant_context = plant.GetMyContextFromRoot(context)
    sg_context = scene_graph.GetMyContextFromRoot(context)
    SetArmAtRest(plant, plant_context, q0)
    worst = {"momentum": 0.0, "clearance": np.inf}

    def monitor(root_context):
        worst["momentum"] = max(worst["momentum"],
                                np.max(np.abs(total_momentum(plant, plant_context))))
        query = scene_graph.get_query_output_port().Eval(sg_context)
        for pair in query.ComputeSignedDistancePairwiseClosestPoints(1.0):
            worst["clearance"] = min(worst["clearance"], pair.distance)

    simulator.set_monitor(monitor)
    simulator.AdvanceTo(duration)
    return FreeFlightResult(
        max_momentum=worst["momentum"],
        kinetic_energy=plant.CalcKineticEnergy(plant_context),
        work=meter.GetMyContextFromRoot(context).get_continuous_state_vector()[0],
        min_clearance=worst["clearance"])
