"""Closed-loop diagrams: ``build_dac_diagram(scenario)``,
``build_dac_nominal_diagram(scenario)`` (the learning ablation) and
``build_model_based_diagram(scenario)``, each returning a ClosedLoop (the Diagram and
the handles a user needs)."""
from dataclasses import dataclass, field
from typing import Dict

import numpy as np
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import Diagram, DiagramBuilder
from pydrake.systems.primitives import (ConstantVectorSource, LogVectorOutput,
                                        VectorLogSink)

from dacph_drake.errors import ConfigError
from dacph_drake.gain_rule import c_lower_bound, check_rhs_period
from dacph_drake.plant import (AddFreeFloatingArm, AddStateSplitter, MakeArmPlant,
                               SetArmAtRest)
from dacph_drake.potential import BaseRepulsionPotential
from dacph_drake.reduced_model import ReducedOrderModel, mass_matrix_bounds
from dacph_drake.reference import OrientationReference
from dacph_drake.scenario import Excitation, Scenario
from dacph_drake.simulation import MakeSimulator
from dacph_drake.systems.disturbance import DisturbanceSource
from dacph_drake.systems.inertial_identifier import InertialIdentifier
from dacph_drake.systems.learner import RhsLearner
from dacph_drake.systems.lhs_controller import LhsController
from dacph_drake.systems.model_based_inverter import ModelBasedInverter
from dacph_drake.systems.port_observer import PortObserver
from dacph_drake.systems.regression_filter import RegressionFilter
from dacph_drake.systems.rhs_integrator import RhsIntegrator
from dacph_drake.systems.true_rhs import TrueRhs


@dataclass
class ClosedLoop:
    """A built closed loop: its diagram, the parts a user reads, and
    CreateSimulator() to run it with the scenario's settings."""
    diagram: Diagram
    scenario: Scenario              # the scenario it was built from
    plant: object                   # the ground-truth MultibodyPlant
    scene_graph: object
    model: ReducedOrderModel        # the controller's (nominal) reduced model
    potential: BaseRepulsionPotential
    lambda_min_M: float             # inf_q lambda_min(M) of the nominal robot
    lambda_max_M: float
    c_min_nominal: float            # eq. (48) with beta_hat = 1
    loggers: Dict[str, VectorLogSink] = field(default_factory=dict)
    systems: Dict[str, object] = field(default_factory=dict)

    def CreateSimulator(self) -> Simulator:
        """A Simulator of this loop with the scenario's simulator settings
        (scenario.simulator, Drake's SimulatorConfig) and initial state: the base at
        the origin, the joints at q0, everything at rest (zero momentum)."""
        simulator = MakeSimulator(self.diagram, self.scenario.simulator)
        SetArmAtRest(self.plant, self.plant.GetMyContextFromRoot(
            simulator.get_mutable_context()), self.scenario.q0)
        return simulator


def _RequireRunnableStart(scenario: Scenario, model: ReducedOrderModel) -> None:
    """ConfigError unless the run can start at q0: every link of the ground-truth arm
    lies outside the base (clearance of the link outline > 0, as
    potential.BaseRepulsionPotential measures it), and the controller's task
    Jacobian D(q0) (1 x n, d alpha / d qdot) is far enough from singular for
    D+ = D^T / (D D^T): ||D(q0)|| >= lhs.min_task_singular_value."""
    q0 = np.asarray(scenario.q0, float)
    clearance = BaseRepulsionPotential(scenario.robot, scenario.potential).MinClearance(q0)
    if clearance <= 0:
        raise ConfigError(f"q0 = {list(scenario.q0)} puts the arm into the base "
                          f"(clearance {clearance:.3f} m); allowed: a configuration "
                          "with every link outside the base")
    sigma = float(np.linalg.norm(model.Evaluate(q0, np.zeros_like(q0)).D))
    if sigma < scenario.lhs.min_task_singular_value:
        raise ConfigError(
            f"q0 = {list(scenario.q0)} is near a singularity of the task Jacobian D "
            f"(||D(q0)|| = {sigma:.3g}); allowed: a q0 with ||D(q0)|| >= "
            f"lhs.min_task_singular_value = {scenario.lhs.min_task_singular_value:g}")


# A controller is a Diagram with a fixed port contract: its inputs are named plant
# signals (plant.STATE_SIGNALS, from the state splitter), its outputs are ``u`` (the
# input of the true RHS) and the logs it offers; assemble_closed_loop logs every
# output. A controller's entry in controllers.REGISTRY is a function
# build(scenario) -> ClosedLoop that calls assemble_closed_loop with a function adding
# the controller's systems to a ControllerBuilder.


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
    """The ground truth (plant, state splitter, true RHS, disturbance) closed by the
    controller that ``add_controller(scenario, loop, controller_builder)`` builds into
    its ControllerBuilder (returning its named systems); every signal of the
    ground truth and every output of the controller is logged at periods.log."""
    scenario.Validate()
    model = ReducedOrderModel(MakeArmPlant(scenario.nominal_robot))
    _RequireRunnableStart(scenario, model)
    builder = DiagramBuilder()
    plant, scene_graph = AddFreeFloatingArm(builder, scenario.robot)
    plant.set_name("plant")
    splitter = AddStateSplitter(builder, plant)
    lambda_min, lambda_max = mass_matrix_bounds(model)
    truth, disturbance = AddActuation(builder, plant, TrueRhs(scenario), scenario)
    loop = ClosedLoop(
        diagram=None, scenario=scenario, plant=plant, scene_graph=scene_graph,
        model=model, potential=BaseRepulsionPotential(scenario.nominal_robot,
                                                      scenario.potential),
        lambda_min_M=lambda_min, lambda_max_M=lambda_max,
        c_min_nominal=c_lower_bound(scenario.rhs.Td, scenario.lhs.Kd, lambda_min, 1.0),
        systems={"state_splitter": splitter, "true_rhs": truth,
                 "disturbance": disturbance})
    controller_builder = ControllerBuilder()
    loop.systems.update(add_controller(scenario, loop, controller_builder))
    loop.loggers.update(CloseLoop(builder, controller_builder, name, plant, splitter,
                                  truth, disturbance, scenario.periods.log))
    loop.diagram = builder.Build()
    loop.diagram.set_name(f"{name}_closed_loop")
    return loop


def AddActuation(builder: DiagramBuilder, plant, truth, scenario):
    """Adds the true RHS ``truth`` (TrueRhs or SpatialTrueRhs) as "true_rhs" and the
    DisturbanceSource of ``scenario`` as "disturbance", wired plant state -> truth ->
    plant actuation. Returns (truth, disturbance)."""
    truth = builder.AddNamedSystem("true_rhs", truth)
    disturbance = builder.AddNamedSystem(
        "disturbance", DisturbanceSource(scenario.disturbance, scenario.disturbance_start))
    builder.Connect(plant.get_state_output_port(), truth.GetInputPort("state"))
    builder.Connect(disturbance.GetOutputPort("disturbance_model"),
                    truth.GetInputPort("disturbance_model"))
    builder.Connect(truth.GetOutputPort("tau"), plant.get_actuation_input_port())
    return truth, disturbance


def CloseLoop(builder: DiagramBuilder, controller_builder: ControllerBuilder, name: str,
              plant, splitter, truth, disturbance, log_period: float
              ) -> Dict[str, VectorLogSink]:
    """Builds the controller (``{name}_controller``) into ``builder``, feeds its
    inputs from the state splitter's signals of the same names and its output ``u``
    to the true RHS ``truth``, and logs every log_period: the plant's state, tau and
    true_matrices of the truth, d(t), and every output of the controller. Returns
    the loggers by signal name."""
    controller = controller_builder.builder.Build()
    controller.set_name(f"{name}_controller")
    builder.AddSystem(controller)
    for i in range(controller.num_input_ports()):
        port = controller.get_input_port(i)
        builder.Connect(splitter.GetOutputPort(port.get_name()), port)
    builder.Connect(controller.GetOutputPort("u"), truth.GetInputPort("u"))
    logged = [("state", plant.get_state_output_port()),
              ("tau", truth.GetOutputPort("tau")),
              ("true_matrices", truth.GetOutputPort("true_matrices")),
              ("disturbance", disturbance.GetOutputPort("disturbance"))]
    logged += [(controller.get_output_port(i).get_name(), controller.get_output_port(i))
               for i in range(controller.num_output_ports())]
    loggers = {}
    for signal, port in logged:
        loggers[signal] = LogVectorOutput(port, builder, log_period)
        loggers[signal].set_name(f"log_{signal}")
    return loggers


def _AddLhsController(scenario: Scenario, loop: ClosedLoop, controller: ControllerBuilder,
                      excitation: Excitation, identify: bool = False
                      ) -> Dict[str, object]:
    """The LHS controller both controllers share, its state inputs exported and its
    request and log as the controller's outputs ``tau_request`` and ``lhs_log``;
    with ``identify``, fed by an InertialIdentifier (scenario.inertia) whose
    estimate is the controller's output ``inertial_parameters``. Returns the named
    systems ("lhs_controller", "inertial_identifier")."""
    builder = controller.builder
    identifier = (builder.AddNamedSystem("inertial_identifier", InertialIdentifier(
        plant=loop.model.plant, settings=scenario.inertia,
        period=scenario.periods.learner_sample)) if identify else None)
    lhs = builder.AddNamedSystem("lhs_controller", LhsController(
        model=loop.model, potential=loop.potential,
        reference=OrientationReference(scenario.reference,
                                       float(np.sum(scenario.q0))),   # theta0(0) = 0
        gains=scenario.lhs, period=scenario.periods.lhs, excitation=excitation,
        lambda_min_M=loop.lambda_min_M,
        inertial_parameters=identifier.parameters if identify else None))
    for signal in ("base_pose", "q", "qdot"):
        controller.Input(lhs.GetInputPort(signal), signal)
    for output in ("tau_request", "lhs_log"):
        builder.ExportOutput(lhs.GetOutputPort(output), output)
    if not identify:
        return {"lhs_controller": lhs}
    ConnectIdentifier(controller, identifier, lhs)
    return {"lhs_controller": lhs, "inertial_identifier": identifier}


def ConnectIdentifier(controller: ControllerBuilder, identifier, lhs) -> None:
    """Feeds the InertialIdentifier ``identifier`` from the controller's state
    inputs and the LHS controller ``lhs`` from it, and exports its estimate as the
    controller's output ``inertial_parameters`` (planar and spatial loops)."""
    for signal in ("base_pose", "base_velocity", "q", "qdot"):
        controller.Input(identifier.GetInputPort(signal), signal)
    controller.builder.Connect(identifier.GetOutputPort("inertial_parameters"),
                               lhs.GetInputPort("inertial_parameters"))
    controller.builder.ExportOutput(identifier.GetOutputPort("inertial_parameters"),
                                    "inertial_parameters")


def build_dac_diagram(scenario: Scenario, learning: bool = True) -> ClosedLoop:
    """Plant + true RHS + disturbance, closed by the DAC-pH controller: the LHS
    sliding-mode controller (chi from the RHS loop, plus scenario.excitation), the
    port observer, the RHS integrator and the learner (in regularized mode behind a
    RegressionFilter). With ``learning`` False the learner keeps its initial
    weights, so the integrator runs on the nominal RHS (B0, D0): the dac-nominal
    ablation, otherwise the same diagram."""
    return assemble_closed_loop(scenario, "dac" if learning else "dac_nominal",
                     lambda scenario, loop, controller: _AddDacController(
                         scenario, loop, controller, learning))


def _AddDacController(scenario: Scenario, loop: ClosedLoop, controller: ControllerBuilder,
                      learning: bool):
    lhs_side = _AddLhsController(scenario, loop, controller, scenario.excitation,
                                 identify=scenario.inertia.identify)
    return {**lhs_side, **AddRhsChain(
        scenario, loop.model, controller, lhs_side["lhs_controller"],
        Kd_max=scenario.lhs.Kd, lambda_min_M=loop.lambda_min_M, learning=learning,
        identifier=lhs_side.get("inertial_identifier"))}


def AddRhsChain(scenario, model, controller: ControllerBuilder, lhs, *, Kd_max: float,
                lambda_min_M: float, learning: bool,
                rhs_period_name: str = "periods.rhs",
                identifier: InertialIdentifier = None) -> Dict[str, object]:
    """The DAC controller's RHS side, shared by planar and spatial robots: the port
    observer, the regression filter (regularized mode), the learner and the RHS
    integrator, wired to the LHS controller ``lhs`` (its outputs ``reduced_model``
    and ``tau_request``, its input ``chi``) and to the controller's inputs q, qdot;
    exports ``u``, ``tau_observed``, ``rhs_log``, ``learner_log``, ``estimates``.
    ``scenario`` has the sections rhs, periods, learner, uncertainty, stress and
    seed (Scenario, SpatialScenario); ``model`` has num_joints and Momentum(q, qdot).
    The gain rule (eq. 48) uses Kd_max / lambda_min_M, the LHS's fastest rate over 2;
    the RHS period is checked for the largest c it allows
    (gain_rule.check_rhs_period; ``rhs_period_name`` names the setting in its
    error). With the LHS's InertialIdentifier ``identifier``, the learner also
    watches the model the observer uses (Learner.model_change). Returns the named
    systems."""
    rhs_settings, periods, settings = scenario.rhs, scenario.periods, scenario.learner
    check_rhs_period(periods, (1 + rhs_settings.c_margin) * c_lower_bound(
                         rhs_settings.Td, Kd_max, lambda_min_M, 1.0),
                     (1 + rhs_settings.c_margin) * c_lower_bound(
                         rhs_settings.Td, Kd_max, lambda_min_M, rhs_settings.beta_max),
                     rhs_settings.beta_max, rhs_period_name)
    builder = controller.builder
    regularized = settings.mode == "regularized"
    observer = builder.AddNamedSystem("port_observer", PortObserver(
        num_joints=model.num_joints, sample_period=periods.rhs,
        noise_std=rhs_settings.observer_noise, seed=scenario.seed,
        anti_alias_cutoff=settings.band[1] if regularized else 0.0))
    prefilter = (builder.AddNamedSystem("regression_filter", RegressionFilter(
        settings=settings, num_joints=model.num_joints,
        period=periods.learner_sample)) if regularized else None)
    learner = builder.AddNamedSystem("learner", RhsLearner(
        model=model, settings=settings, period=periods.learner,
        sample_period=periods.learner_sample, B0=scenario.uncertainty.B0,
        D0=scenario.uncertainty.D0, seed=scenario.seed, q0=scenario.q0,
        learning=learning,
        watch_model=identifier is not None))
    if identifier is not None:
        builder.Connect(identifier.GetOutputPort("model_epoch"),
                        learner.GetInputPort("model_epoch"))
    rhs = builder.AddNamedSystem("rhs_integrator", RhsIntegrator(
        model=model, network=learner.exported, settings=rhs_settings,
        Kd_max=Kd_max, lambda_min_M=lambda_min_M, B0=scenario.uncertainty.B0,
        D0=scenario.uncertainty.D0, period=periods.rhs,
        model_period=periods.learner_sample, stress=scenario.stress))
    # The data path, in order: plant -> port observer -> (band-pass) -> learner ->
    # RHS integrator -> u (to the true RHS); the LHS's request and model feed in.
    for signal in ("q", "qdot"):
        controller.Input(observer.GetInputPort(signal), signal)
    for system in (observer, learner, rhs):      # M for p = M qdot, the observer's
        builder.Connect(lhs.GetOutputPort("reduced_model"),
                        system.GetInputPort("reduced_model"))
    builder.Connect(rhs.GetOutputPort("u"), observer.GetInputPort("u"))
    port_sample = observer.GetOutputPort("port_sample")
    if prefilter is not None:
        builder.Connect(port_sample, prefilter.GetInputPort("port_sample"))
        port_sample = prefilter.GetOutputPort("filtered_sample")
    builder.Connect(port_sample, learner.GetInputPort("port_sample"))
    builder.Connect(port_sample, rhs.GetInputPort("port_sample"))
    for signal in ("q", "qdot"):
        controller.Input(learner.GetInputPort(signal), signal)
    builder.Connect(observer.GetOutputPort("tau_observed"),
                    rhs.GetInputPort("tau_observed"))
    builder.Connect(lhs.GetOutputPort("tau_request"), rhs.GetInputPort("tau_request"))
    builder.Connect(learner.GetOutputPort("weights"), rhs.GetInputPort("weights"))
    builder.Connect(learner.GetOutputPort("beta_hat"), rhs.GetInputPort("beta_hat"))
    for signal in ("q", "qdot"):
        controller.Input(rhs.GetInputPort(signal), signal)
    builder.ExportOutput(rhs.GetOutputPort("u"), "u")
    builder.Connect(rhs.GetOutputPort("chi"), lhs.GetInputPort("chi"))
    for name, port in [("tau_observed", observer.GetOutputPort("tau_observed")),
                       ("rhs_log", rhs.GetOutputPort("rhs_log")),
                       ("learner_log", learner.GetOutputPort("learner_log")),
                       ("estimates", learner.GetOutputPort("estimates"))]:
        builder.ExportOutput(port, name)
    systems = {"port_observer": observer, "learner": learner, "rhs_integrator": rhs}
    if prefilter is not None:
        systems["regression_filter"] = prefilter
    return systems


def build_dac_nominal_diagram(scenario: Scenario) -> ClosedLoop:
    """The learning ablation: build_dac_diagram with the learner switched off (the
    integrator on the nominal RHS B0, D0; the excitation stays, so that learning is
    the only difference)."""
    return build_dac_diagram(scenario, learning=False)


def build_model_based_diagram(scenario: Scenario) -> ClosedLoop:
    """The baseline (docs/equations.md, SPEC settings): the same LHS controller with
    chi from a constant source (lhs.chi_model_based) and the static inversion
    u = B0^-1 (tau_c^r + D0 qdot); no integrator, no learning."""
    return assemble_closed_loop(scenario, "model_based", _AddModelBasedController)


def _AddModelBasedController(scenario: Scenario, loop: ClosedLoop,
                             controller: ControllerBuilder):
    lhs_side = _AddLhsController(scenario, loop, controller, Excitation(amplitude=0.0))
    return {**lhs_side, **AddModelBasedRhs(
        scenario, controller, lhs_side["lhs_controller"], scenario.lhs.chi_model_based)}


def AddModelBasedRhs(scenario, controller: ControllerBuilder, lhs,
                     chi: float) -> Dict[str, object]:
    """The baseline's RHS side, shared by planar and spatial robots: a constant
    ``chi`` into the LHS controller ``lhs`` and the static inversion of its
    ``tau_request`` (ModelBasedInverter, with the controller's input qdot), exported
    as ``u``. Returns the named systems."""
    builder = controller.builder
    fixed_chi = builder.AddNamedSystem("fixed_chi", ConstantVectorSource([chi]))
    builder.Connect(fixed_chi.get_output_port(), lhs.GetInputPort("chi"))
    inverter = builder.AddNamedSystem("model_based_inverter", ModelBasedInverter(scenario))
    builder.Connect(lhs.GetOutputPort("tau_request"), inverter.GetInputPort("tau_request"))
    controller.Input(inverter.GetInputPort("qdot"), "qdot")
    builder.ExportOutput(inverter.GetOutputPort("u"), "u")
    return {"model_based_inverter": inverter}

