"""Closed loops of spatial robots (description files). Today: the model-based LHS
loop, the ground truth (a MultibodyPlant from the description, free quaternion
base) driven by the AttitudeController's torque directly (nominal RHS: B = I,
D = 0, no disturbance). The DAC loop for spatial robots (RHS integrator, port
observer, learner) is not built yet."""
from dataclasses import dataclass, field
from typing import Dict

from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import Diagram, DiagramBuilder
from pydrake.systems.primitives import LogVectorOutput, VectorLogSink

from dacph_drake.description import AddRobotFromDescription, MakeRobotPlant
from dacph_drake.floating_model import FloatingBaseModel
from dacph_drake.plant import AddStateSplitter, SetArmAtRest
from dacph_drake.simulation import MakeSimulator
from dacph_drake.spatial_potential import BaseClearancePotential
from dacph_drake.spatial_scenario import SpatialScenario
from dacph_drake.systems.attitude_controller import AttitudeController


@dataclass
class SpatialLoop:
    diagram: Diagram
    scenario: SpatialScenario
    plant: object                   # the ground truth
    model: FloatingBaseModel        # the controller's model (of the same description)
    controller: AttitudeController
    loggers: Dict[str, VectorLogSink] = field(default_factory=dict)

    def CreateSimulator(self) -> Simulator:
        """A Simulator with the scenario's settings, the arm at rest at q0 and the
        base at the origin (zero momentum)."""
        simulator = MakeSimulator(self.diagram, self.scenario.simulator)
        SetArmAtRest(self.plant, self.plant.GetMyContextFromRoot(
            simulator.get_mutable_context()), self.scenario.q0)
        return simulator


def build_spatial_model_based_diagram(scenario: SpatialScenario) -> SpatialLoop:
    """plant -> state splitter -> AttitudeController -> plant actuation; the
    plant's state and the controller's attitude_log logged every log_period."""
    model = FloatingBaseModel(MakeRobotPlant(scenario.robot))
    scenario.Validate(model.num_joints)
    builder = DiagramBuilder()
    plant, _ = AddRobotFromDescription(builder, scenario.robot)
    plant.set_name("plant")
    splitter = AddStateSplitter(builder, plant)
    potential = (BaseClearancePotential(
        description=scenario.robot, model=model, gain=scenario.potential.gain,
        margin=scenario.potential.margin) if scenario.potential.gain > 0 else None)
    controller = builder.AddNamedSystem("attitude_controller", AttitudeController(
        model=model, reference=scenario.reference, gains=scenario.gains,
        period=scenario.lhs_period, q0=scenario.q0, potential=potential,
        eta=scenario.potential.eta))
    for signal in ("base_pose", "base_velocity", "q", "qdot"):
        builder.Connect(splitter.GetOutputPort(signal), controller.GetInputPort(signal))
    builder.Connect(controller.GetOutputPort("tau_request"),
                    plant.get_actuation_input_port())
    loggers = {"state": LogVectorOutput(plant.get_state_output_port(), builder,
                                        scenario.log_period),
               "attitude_log": LogVectorOutput(controller.GetOutputPort("attitude_log"),
                                               builder, scenario.log_period)}
    diagram = builder.Build()
    diagram.set_name("spatial_model_based_closed_loop")
    return SpatialLoop(diagram=diagram, scenario=scenario, plant=plant, model=model,
                       controller=controller, loggers=loggers)
