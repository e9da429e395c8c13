"""The closed loop every controller and robot shares: the ground truth (plant, state
splitter, true RHS, disturbance) closed by a controller, every output logged. A controller
is a Diagram: its inputs named plant signals (plant.STATE_SIGNALS), its outputs ``u`` (the
true RHS's input) and its logs."""
from dataclasses import dataclass, field, fields
from typing import Callable, Dict, List, Sequence, Tuple

from pydrake.common.yaml import yaml_dump_typed
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import Diagram, DiagramBuilder, InputPort, OutputPort, System
from pydrake.systems.primitives import (DiscreteTimeDelay, FirstOrderLowPassFilter,
                                        LogVectorOutput, VectorLogSink)

from dacph_drake.scenario.errors import ConfigError
from dacph_drake.gain_rule import c_lower_bound
from dacph_drake.dynamics.plant import (STATE_SIGNALS, AddStateSplitter, SetArmsAtRest,
                                        trial_coordinates)
from dacph_drake.assembly.registry import robots_of
from dacph_drake.robots.robot import Robot
from dacph_drake.scenario import Excitation, Scenario
from dacph_drake.scenario.simulator import MakeSimulator
from dacph_drake.systems.disturbance import DisturbanceSource
from dacph_drake.systems.sensors import Sensors


@dataclass
class ClosedLoop:
    """A built closed loop of a batch of trials, their signals stacked in trial order.

    Attributes:
        diagram: The Drake diagram.
        scenarios: Each trial's scenario, as built.
        robots: Each trial's Robot (robots.robots_of(scenarios)).
        plant: The ground-truth MultibodyPlant.
        scene_graph: Its SceneGraph.
        loggers: Signal name -> its VectorLogSink.
        systems: System name -> the system (the ground truth's and the controller's)."""
    diagram: Diagram
    scenarios: List[Scenario]
    robots: List[Robot]
    plant: object
    scene_graph: object
    loggers: Dict[str, VectorLogSink] = field(default_factory=dict)
    systems: Dict[str, object] = field(default_factory=dict)

    @property
    def scenario(self) -> Scenario:
        """The first trial's scenario: the settings every trial shares."""
        return self.scenarios[0]

    @property
    def robot(self) -> Robot:
        """The first trial's Robot."""
        return self.robots[0]

    @property
    def trials(self) -> int:
        return len(self.scenarios)

    @property
    def model(self):
        """The first trial's controller (nominal) reduced model (robots.ReducedModel)."""
        return self.robot.model

    @property
    def c_min_nominal(self) -> float:
        """eq. (48) with beta_hat = 1: the RHS decay rate the LHS asks for."""
        Kd_max, lambda_min_M = self.robot.task.GainRuleRates(self.robot)
        return c_lower_bound(self.scenario.rhs.Td, Kd_max, lambda_min_M, 1.0)

    def CreateSimulator(self) -> Simulator:
        """A Simulator of this loop (scenario.simulator), at rest at q0, base at origin."""
        simulator = MakeSimulator(self.diagram, self.scenario.simulator)
        SetArmsAtRest(self.plant, self.plant.GetMyContextFromRoot(
            simulator.get_mutable_context()), [s.q0 for s in self.scenarios])
        return simulator


class ControllerBuilder:
    """A controller's DiagramBuilder; Input(port, signal): one input, read by many ports."""

    def __init__(self):
        self.builder = DiagramBuilder()
        self._inputs = set()

    def Input(self, port: InputPort, signal: str) -> None:
        """Feeds an internal port from the controller's input ``signal`` (exported once).

        Args:
            port: An input port of a system in ``builder``.
            signal: A plant signal: q, qdot, base_pose or base_velocity."""
        if signal in self._inputs:
            self.builder.ConnectInput(signal, port)
        else:
            self.builder.ExportInput(port, signal)
            self._inputs.add(signal)


def assemble_closed_loop(scenario: Scenario, name: str,
                         add_controller: Callable[[ClosedLoop, ControllerBuilder], Dict],
                         more_trials: Sequence[Scenario] = ()) -> ClosedLoop:
    """Closes the ground truth with a controller, every output logged at periods.log.

    Args:
        scenario: The (first) trial's scenario.
        name: The controller's name: the diagram is ``{name}_closed_loop``.
        add_controller: ``add_controller(loop, controller_builder)`` adds the controller's
            systems to controller_builder.builder and returns them by name.
        more_trials: The batch's other trials (one diagram for all).

    Raises:
        ConfigError: Trials differ in a diagram-shaping setting, or a q0 cannot start."""
    scenarios = [scenario, *more_trials]
    RequireOneDiagram(scenarios)
    robots = robots_of(scenarios)
    for robot in robots:
        robot.RequireRunnableStart()
    family = type(robots[0])
    builder = DiagramBuilder()
    plant, scene_graph = family.AddGroundTruth(builder, robots)
    plant.set_name("plant")
    splitter = AddStateSplitter(builder, plant)
    truth = builder.AddNamedSystem("true_rhs", family.MakeTrueRhs(plant, robots))
    disturbance = builder.AddNamedSystem("disturbance", DisturbanceSource(
        settings=[s.disturbance for s in scenarios],
        starts=[s.disturbance_start for s in scenarios]))
    builder.Connect(plant.get_state_output_port(), truth.GetInputPort("state"))
    builder.Connect(disturbance.GetOutputPort("disturbance_model"),
                    truth.GetInputPort("disturbance_model"))
    builder.Connect(truth.GetOutputPort("tau"), plant.get_actuation_input_port())
    loop = ClosedLoop(diagram=None, scenarios=scenarios, robots=robots, plant=plant,
                      scene_graph=scene_graph,
                      systems={"state_splitter": splitter, "true_rhs": truth,
                               "disturbance": disturbance})
    controller_builder = ControllerBuilder()
    loop.systems.update(add_controller(loop, controller_builder))
    controller = controller_builder.builder.Build()
    controller.set_name(f"{name}_controller")
    builder.AddSystem(controller)
    measured = AddSensors(builder, loop, splitter)
    for i in range(controller.num_input_ports()):
        port = controller.get_input_port(i)
        builder.Connect(measured.GetOutputPort(port.get_name()), port)
    builder.Connect(AddActuation(builder, loop, controller.GetOutputPort("u")),
                    truth.GetInputPort("u"))
    logged = [("state", plant.get_state_output_port())]
    logged += [(truth.get_output_port(i).get_name(), truth.get_output_port(i))
               for i in range(truth.num_output_ports())]      # tau, true_matrices, ...
    logged += [("disturbance", disturbance.GetOutputPort("disturbance"))]
    logged += [(controller.get_output_port(i).get_name(), controller.get_output_port(i))
               for i in range(controller.num_output_ports())]
    for signal, port in logged:
        loop.loggers[signal] = LogVectorOutput(port, builder, loop.scenario.periods.log)
        loop.loggers[signal].set_name(f"log_{signal}")
    loop.diagram = builder.Build()
    loop.diagram.set_name(f"{name}_closed_loop")
    return loop


def DelayLine(period: float, samples: int, size: int) -> DiscreteTimeDelay:
    """A delay of ``samples`` periods on a signal that a discrete system updates at the
    same instants: Drake's DiscreteTimeDelay holds what it samples for a period before
    its delay line starts, so ``samples - 1`` steps of it delay such a signal by
    ``samples`` periods (tests/test_sensing.py).

    Args:
        period: The sample period [s].
        samples: The delay [periods], >= 1.
        size: The signal's size."""
    return DiscreteTimeDelay(period, samples - 1, size)


def AddSensors(builder: DiagramBuilder, loop: ClosedLoop, splitter: System) -> System:
    """The system whose outputs (plant.STATE_SIGNALS) the controller reads: the state
    splitter itself, or with sensing.enabled the systems.sensors.Sensors it feeds.

    Args:
        builder: The closed loop's builder.
        loop: The loop being built (its systems get ``sensors``).
        splitter: The state splitter (AddStateSplitter)."""
    sensing = loop.scenario.sensing
    if not sensing.enabled:
        return splitter
    coordinates = trial_coordinates(loop.plant)[0]
    sensors = builder.AddNamedSystem("sensors", Sensors(
        settings=sensing, num_joints=coordinates.num_joints,
        base_positions=len(coordinates.base_q), period=loop.scenario.periods.rhs,
        seeds=[s.seed for s in loop.scenarios]))
    for name in STATE_SIGNALS:
        builder.Connect(splitter.GetOutputPort(name), sensors.GetInputPort(name))
    loop.systems["sensors"] = sensors
    return sensors


def AddActuation(builder: DiagramBuilder, loop: ClosedLoop, u: OutputPort) -> OutputPort:
    """The command as the actuators deliver it: u itself, or with sensing.enabled u
    sensing.rhs_delay + sensing.unmodelled_delay samples of periods.rhs late (a
    computation delay) through a first-order lag of time constant sensing.actuator_lag
    (the actuators' bandwidth).

    Args:
        builder: The closed loop's builder.
        loop: The loop being built (its systems get ``rhs_delay``, ``actuator_lag``).
        u: The controller's command output."""
    sensing, size = loop.scenario.sensing, u.size()
    samples = sensing.rhs_delay + sensing.unmodelled_delay
    if sensing.enabled and samples > 0:
        delay = builder.AddNamedSystem("rhs_delay", DelayLine(
            loop.scenario.periods.rhs, samples, size))
        builder.Connect(u, delay.get_input_port())
        u = delay.get_output_port()
        loop.systems["rhs_delay"] = delay
    if sensing.enabled and sensing.actuator_lag > 0:
        lag = builder.AddNamedSystem("actuator_lag", FirstOrderLowPassFilter(
            sensing.actuator_lag, size))
        builder.Connect(u, lag.get_input_port())
        u = lag.get_output_port()
        loop.systems["actuator_lag"] = lag
    return u


# What the trials of one batch may each have of their own; every other setting
# shapes the diagram (periods, gains, the simulator) and is shared.
PER_TRIAL_SETTINGS = ("robot", "q0", "uncertainty", "disturbance", "seed")


def DiagramSettings(scenario: Scenario) -> str:
    """The settings that shape a scenario's diagram (all but PER_TRIAL_SETTINGS), as
    YAML: trials with equal ones can share a batch's diagram.

    Args:
        scenario: The scenario."""
    return "".join(f"{setting.name}:{yaml_dump_typed(getattr(scenario, setting.name))}"
                   for setting in fields(scenario)
                   if setting.name not in PER_TRIAL_SETTINGS)


def RequireOneDiagram(scenarios: Sequence[Scenario]) -> None:
    """Requires a batch's trials to share the diagram's settings, compared as YAML.

    Args:
        scenarios: The batch's trials.

    Raises:
        ConfigError: Naming the first setting (beyond PER_TRIAL_SETTINGS) that differs."""
    first = scenarios[0]
    for i, scenario in enumerate(scenarios[1:], start=1):
        for setting in fields(first):
            if (setting.name not in PER_TRIAL_SETTINGS
                    and yaml_dump_typed(getattr(scenario, setting.name))
                    != yaml_dump_typed(getattr(first, setting.name))):
                raise ConfigError(
                    f"trial {i}'s {setting.name} differs from trial 0's; allowed: the "
                    f"trials of one batch differ only in {', '.join(PER_TRIAL_SETTINGS)}")


def AddLhsSide(loop: ClosedLoop, controller: ControllerBuilder, excitation: Excitation,
               identify: bool) -> Tuple[object, Dict]:
    """Adds the task's LHS (tau_request and its log exported); returns (lhs, its systems).
    With sensing.enabled and sensing.lhs_delay > 0 the systems hold ``lhs_delay``, the
    request sensing.lhs_delay LHS periods late (LhsRequest gives the port to read).

    Args:
        loop: The loop being built (its robots: the trials').
        controller: The controller's ControllerBuilder.
        excitation: The learner's excitation tau_pe(t) (amplitude 0: off).
        identify: Add an InertialIdentifier from the state inputs into the LHS (outputs
            ``inertial_parameters``, ``identification_log``, ``model_error``)."""
    task, builder = loop.robot.task, controller.builder
    systems = task.AddLhsController(controller, loop.robots, excitation, identify)
    lhs = systems[task.lhs_name]
    builder.ExportOutput(lhs.GetOutputPort("tau_request"), "tau_request")
    builder.ExportOutput(lhs.GetOutputPort(task.log_name), task.log_name)
    sensing = loop.scenario.sensing
    if sensing.enabled and sensing.lhs_delay > 0:
        request = lhs.GetOutputPort("tau_request")
        delay = systems["lhs_delay"] = builder.AddNamedSystem("lhs_delay", DelayLine(
            loop.scenario.periods.lhs, sensing.lhs_delay, request.size()))
        builder.Connect(request, delay.get_input_port())
    identifier = systems.get("inertial_identifier")
    if identifier is not None:
        for signal in ("base_pose", "base_velocity", "q", "qdot"):
            controller.Input(identifier.GetInputPort(signal), signal)
        builder.Connect(identifier.GetOutputPort("inertial_parameters"),
                        lhs.GetInputPort("inertial_parameters"))
        builder.ExportOutput(identifier.GetOutputPort("inertial_parameters"),
                             "inertial_parameters")
        builder.ExportOutput(identifier.GetOutputPort("identification_log"),
                             "identification_log")
        builder.ExportOutput(identifier.GetOutputPort("model_error"), "model_error")
    return lhs, systems


def LhsRequest(lhs: System, systems: Dict) -> OutputPort:
    """The LHS's request tau_c^r as the RHS side receives it (AddLhsSide's delay, if any).

    Args:
        lhs: The LHS controller (AddLhsSide).
        systems: AddLhsSide's systems."""
    delay = systems.get("lhs_delay")
    return delay.get_output_port() if delay is not None else lhs.GetOutputPort("tau_request")
