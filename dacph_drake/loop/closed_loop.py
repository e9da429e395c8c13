"""The closed loop every controller and every robot shares: the ground truth
(plant, state splitter, true RHS, disturbance) closed by a controller, logged.

A controller is a Diagram with a fixed port contract: its inputs are named plant
signals (plant.STATE_SIGNALS, from the state splitter), its outputs are ``u`` (the
input of the true RHS) and the logs it offers; every output is logged. A
controller's module (controllers/) builds it with assemble_closed_loop and a
function adding its systems to a ControllerBuilder; the robot
(robots.robot_of(scenario)) supplies the ground truth, the controller's model and
the LHS controller."""
from dataclasses import dataclass, field
from typing import Dict

from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import Diagram, DiagramBuilder
from pydrake.systems.primitives import LogVectorOutput, VectorLogSink

from dacph_drake.gain_rule import c_lower_bound
from dacph_drake.dynamics.plant import AddStateSplitter, SetArmAtRest
from dacph_drake.robots import Robot, robot_of
from dacph_drake.scenario import Scenario
from dacph_drake.loop.simulator import MakeSimulator
from dacph_drake.systems.disturbance import DisturbanceSource


@dataclass
class ClosedLoop:
    """A built closed loop: its diagram, the parts a user reads, and
    CreateSimulator() to run it with the scenario's settings."""
    diagram: Diagram
    scenario: Scenario              # the scenario it was built from
    robot: Robot                    # robots.robot_of(scenario)
    plant: object                   # the ground-truth MultibodyPlant
    scene_graph: object
    loggers: Dict[str, VectorLogSink] = field(default_factory=dict)
    systems: Dict[str, object] = field(default_factory=dict)

    @property
    def model(self):
        """The controller's (nominal) reduced model (robots.ReducedModel)."""
        return self.robot.model

    @property
    def c_min_nominal(self) -> float:
        """eq. (48) with beta_hat = 1: the RHS decay rate the LHS asks for."""
        Kd_max, lambda_min_M = self.robot.GainRuleRates()
        return c_lower_bound(self.scenario.rhs.Td, Kd_max, lambda_min_M, 1.0)

    def CreateSimulator(self) -> Simulator:
        """A Simulator of this loop with the scenario's simulator settings
        (scenario.simulator, Drake's SimulatorConfig) and initial state: the base at
        the origin, the joints at q0, everything at rest (zero momentum)."""
        simulator = MakeSimulator(self.diagram, self.scenario.simulator)
        SetArmAtRest(self.plant, self.plant.GetMyContextFromRoot(
            simulator.get_mutable_context()), self.scenario.q0)
        return simulator


class ControllerBuilder:
    """A DiagramBuilder for a controller: Input(port, signal) exports ``port`` as the
    controller's input ``signal`` (several internal ports may read one signal)."""

    def __init__(self):
        self.builder = DiagramBuilder()
        self._inputs = set()

    def Input(self, port, signal: str) -> None:
        if signal in self._inputs:
            self.builder.ConnectInput(signal, port)
        else:
            self.builder.ExportInput(port, signal)
            self._inputs.add(signal)


def assemble_closed_loop(scenario: Scenario, name: str, add_controller) -> ClosedLoop:
    """The ground truth of ``scenario``'s robot (plant, state splitter, true RHS,
    disturbance) closed by the controller that ``add_controller(loop,
    controller_builder)`` builds into its ControllerBuilder (returning its named
    systems); every signal of the ground truth and every output of the controller
    is logged at periods.log. The diagram is named ``{name}_closed_loop``."""
    robot = robot_of(scenario)
    robot.RequireRunnableStart()
    builder = DiagramBuilder()
    plant, scene_graph = robot.AddGroundTruth(builder)
    plant.set_name("plant")
    splitter = AddStateSplitter(builder, plant)
    truth = builder.AddNamedSystem("true_rhs", robot.MakeTrueRhs(plant))
    disturbance = builder.AddNamedSystem(
        "disturbance", DisturbanceSource(scenario.disturbance, scenario.disturbance_start))
    builder.Connect(plant.get_state_output_port(), truth.GetInputPort("state"))
    builder.Connect(disturbance.GetOutputPort("disturbance_model"),
                    truth.GetInputPort("disturbance_model"))
    builder.Connect(truth.GetOutputPort("tau"), plant.get_actuation_input_port())
    loop = ClosedLoop(diagram=None, scenario=scenario, robot=robot, plant=plant,
                      scene_graph=scene_graph,
                      systems={"state_splitter": splitter, "true_rhs": truth,
                               "disturbance": disturbance})
    controller_builder = ControllerBuilder()
    loop.systems.update(add_controller(loop, controller_builder))
    controller = controller_builder.builder.Build()
    controller.set_name(f"{name}_controller")
    builder.AddSystem(controller)
    for i in range(controller.num_input_ports()):
        port = controller.get_input_port(i)
        builder.Connect(splitter.GetOutputPort(port.get_name()), port)
    builder.Connect(controller.GetOutputPort("u"), truth.GetInputPort("u"))
    logged = [("state", plant.get_state_output_port())]
    logged += [(truth.get_output_port(i).get_name(), truth.get_output_port(i))
               for i in range(truth.num_output_ports())]      # tau, true_matrices, ...
    logged += [("disturbance", disturbance.GetOutputPort("disturbance"))]
    logged += [(controller.get_output_port(i).get_name(), controller.get_output_port(i))
               for i in range(controller.num_output_ports())]
    for signal, port in logged:
        loop.loggers[signal] = LogVectorOutput(port, builder, scenario.periods.log)
        loop.loggers[signal].set_name(f"log_{signal}")
    loop.diagram = builder.Build()
    loop.diagram.set_name(f"{name}_closed_loop")
    return loop


def AddLhsSide(loop: ClosedLoop, controller: ControllerBuilder, excitation,
               identify: bool):
    """The robot's LHS controller (robots.Robot.AddLhsController), its request and
    log exported as the controller's outputs ``tau_request`` and the robot's log
    name; with ``identify``, the InertialIdentifier fed from the controller's state
    inputs, feeding the LHS, its estimate the output ``inertial_parameters``.
    Returns (the LHS controller, the named systems)."""
    robot, builder = loop.robot, controller.builder
    systems = robot.AddLhsController(controller, excitation, identify)
    lhs = systems[robot.lhs_name]
    builder.ExportOutput(lhs.GetOutputPort("tau_request"), "tau_request")
    builder.ExportOutput(lhs.GetOutputPort(robot.lhs_log), robot.lhs_log)
    identifier = systems.get("inertial_identifier")
    if identifier is not None:
        for signal in ("base_pose", "base_velocity", "q", "qdot"):
            controller.Input(identifier.GetInputPort(signal), signal)
        builder.Connect(identifier.GetOutputPort("inertial_parameters"),
                        lhs.GetInputPort("inertial_parameters"))
        builder.ExportOutput(identifier.GetOutputPort("inertial_parameters"),
                             "inertial_parameters")
    return lhs, systems
