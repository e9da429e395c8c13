"""Closed loops of spatial robots (description files): ``build_spatial_dac_diagram``,
``build_spatial_dac_nominal_diagram`` (the learning ablation) and
``build_spatial_model_based_diagram`` (the baseline), each returning a SpatialLoop.
The ground truth is a MultibodyPlant from the description (free quaternion base)
driven through the port's true RHS (SpatialTrueRhs) with the disturbance d(t); the
controllers are the planar loops' with the AttitudeController as their LHS: the
same RHS chain (diagrams.AddRhsChain) and the same static inversion."""
from dataclasses import dataclass, field
from typing import Dict

import numpy as np
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import Diagram, DiagramBuilder
from pydrake.systems.primitives import VectorLogSink

from dacph_drake.description import AddRobotFromDescription, MakeRobotPlant
from dacph_drake.diagrams import (AddActuation, AddModelBasedRhs, AddRhsChain,
                                  CloseLoop, ConnectIdentifier, ControllerBuilder)
from dacph_drake.floating_model import FloatingBaseModel
from dacph_drake.inertial_parameters import PER_BODY
from dacph_drake.plant import AddStateSplitter, SetArmAtRest
from dacph_drake.scenario import Excitation
from dacph_drake.simulation import MakeSimulator
from dacph_drake.spatial_potential import BaseClearancePotential
from dacph_drake.spatial_scenario import SpatialScenario
from dacph_drake.systems.attitude_controller import AttitudeController
from dacph_drake.systems.inertial_identifier import InertialIdentifier
from dacph_drake.systems.spatial_true_rhs import SpatialTrueRhs


@dataclass
class SpatialLoop:
    diagram: Diagram
    scenario: SpatialScenario
    plant: object                   # the ground truth
    model: FloatingBaseModel        # the controller's model (of the same description)
    controller: AttitudeController  # the LHS controller
    loggers: Dict[str, VectorLogSink] = field(default_factory=dict)
    systems: Dict[str, object] = field(default_factory=dict)

    def CreateSimulator(self) -> Simulator:
        """A Simulator with the scenario's settings, the arm at rest at q0 and the
        base at the origin (zero momentum)."""
        simulator = MakeSimulator(self.diagram, self.scenario.simulator)
        SetArmAtRest(self.plant, self.plant.GetMyContextFromRoot(
            simulator.get_mutable_context()), self.scenario.q0)
        return simulator


def controller_model(scenario: SpatialScenario) -> FloatingBaseModel:
    """The controller's model of the robot (validating the scenario against it): the
    description's plant with every body's inertia times
    scenario.nominal_inertia_scale (the controller's model error)."""
    model = FloatingBaseModel(MakeRobotPlant(scenario.robot))
    scenario.Validate(model.num_joints, len(model.parameters.bodies))
    if scenario.nominal_inertia_scale:
        model.SetInertialParameters(model.inertial_parameters * np.repeat(
            scenario.nominal_inertia_scale, PER_BODY))
    return model


def assemble_spatial_closed_loop(scenario: SpatialScenario, name: str,
                                 add_controller) -> SpatialLoop:
    """plant -> state splitter -> controller -> true RHS (+ d(t)) -> plant; the
    controller is what ``add_controller(scenario, model, controller_builder)`` builds
    (returning its named systems, the AttitudeController as
    "attitude_controller"); logged as diagrams.CloseLoop logs."""
    model = controller_model(scenario)
    builder = DiagramBuilder()
    plant, _ = AddRobotFromDescription(builder, scenario.robot)
    plant.set_name("plant")
    splitter = AddStateSplitter(builder, plant)
    truth, disturbance = AddActuation(builder, plant, SpatialTrueRhs(
        plant=plant, uncertainty=scenario.uncertainty, phases=scenario.phases),
        scenario)
    controller_builder = ControllerBuilder()
    systems = add_controller(scenario, model, controller_builder)
    loggers = CloseLoop(builder, controller_builder, name, plant, splitter, truth,
                        disturbance, scenario.log_period)
    diagram = builder.Build()
    diagram.set_name(f"{name}_closed_loop")
    return SpatialLoop(diagram=diagram, scenario=scenario, plant=plant, model=model,
                       controller=systems["attitude_controller"], loggers=loggers,
                       systems={"state_splitter": splitter, "true_rhs": truth,
                                "disturbance": disturbance, **systems})


def _AddAttitudeController(scenario: SpatialScenario, model: FloatingBaseModel,
                           controller: ControllerBuilder, excitation: Excitation,
                           identify: bool = False) -> Dict[str, object]:
    """The LHS both controllers share, its state inputs exported and its request
    and log as the controller's outputs ``tau_request`` and ``attitude_log``; with
    ``identify``, fed by an InertialIdentifier (scenario.inertia) whose estimate is
    the controller's output ``inertial_parameters``. Returns the named systems."""
    builder = controller.builder
    potential = (BaseClearancePotential(
        description=scenario.robot, model=model, gain=scenario.potential.gain,
        margin=scenario.potential.margin) if scenario.potential.gain > 0 else None)
    lhs = builder.AddNamedSystem("attitude_controller", AttitudeController(
        model=model, reference=scenario.reference, gains=scenario.gains,
        period=scenario.lhs_period, q0=scenario.q0, potential=potential,
        eta=scenario.potential.eta, excitation=excitation, identify=identify))
    for signal in ("base_pose", "base_velocity", "q", "qdot"):
        controller.Input(lhs.GetInputPort(signal), signal)
    for output in ("tau_request", "attitude_log"):
        builder.ExportOutput(lhs.GetOutputPort(output), output)
    if not identify:
        return {"attitude_controller": lhs}
    identifier = builder.AddNamedSystem("inertial_identifier", InertialIdentifier(
        plant=model.plant, prior=model.inertial_parameters, settings=scenario.inertia,
        period=scenario.learner_sample_period))
    ConnectIdentifier(controller, identifier, lhs)
    return {"attitude_controller": lhs, "inertial_identifier": identifier}


def build_spatial_dac_diagram(scenario: SpatialScenario,
                              learning: bool = True) -> SpatialLoop:
    """The DAC-pH loop on a spatial robot: the AttitudeController (chi from the RHS
    loop, plus scenario.excitation) and the RHS chain of the planar loops. With
    K_d = damping_rate M(q) the gain rule's LHS rate lambda_max(K_d) /
    inf lambda_min(M) is damping_rate for every arm
    (gain_rule.inertia_scaled_c_lower_bound). ``learning`` False: the dac-nominal
    ablation (the learner keeps B0, D0)."""
    def add(scenario, model, controller):
        lhs_side = _AddAttitudeController(scenario, model, controller,
                                          scenario.excitation,
                                          identify=scenario.inertia.identify)
        return {**lhs_side, **AddRhsChain(
            scenario, model, controller, lhs_side["attitude_controller"],
            Kd_max=scenario.gains.damping_rate, lambda_min_M=1.0, learning=learning,
            rhs_period_name="rhs_period",
            identifier=lhs_side.get("inertial_identifier"))}
    return assemble_spatial_closed_loop(
        scenario, "spatial_dac" if learning else "spatial_dac_nominal", add)


def build_spatial_dac_nominal_diagram(scenario: SpatialScenario) -> SpatialLoop:
    """The learning ablation: build_spatial_dac_diagram without learning."""
    return build_spatial_dac_diagram(scenario, learning=False)


def build_spatial_model_based_diagram(scenario: SpatialScenario) -> SpatialLoop:
    """The baseline: the AttitudeController with chi = gains.chi_model_based and the
    static inversion u = B0^-1 (tau_c^r + D0 qdot) (ModelBasedInverter); no
    integrator, no learning. On the default scenario's nominal ground truth the
    inversion is exact: the plant receives the LHS's request."""
    def add(scenario, model, controller):
        lhs_side = _AddAttitudeController(scenario, model, controller,
                                          Excitation(amplitude=0.0))
        return {**lhs_side, **AddModelBasedRhs(
            scenario, controller, lhs_side["attitude_controller"],
            scenario.gains.chi_model_based)}
    return assemble_spatial_closed_loop(scenario, "spatial_model_based", add)
