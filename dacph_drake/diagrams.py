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
from dacph_drake.plant import AddFreeFloatingArm, AddStateSplitter, MakeArmPlant
from dacph_drake.potential import BaseRepulsionPotential
from dacph_drake.reduced_model import ReducedOrderModel, mass_matrix_bounds
from dacph_drake.reference import OrientationReference
from dacph_drake.scenario import Excitation, Scenario
from dacph_drake.simulation import MakeSimulator
from dacph_drake.systems.disturbance import DisturbanceSource
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
        """A Simulator of this loop with the scenario's integrator
        (scenario.integration_scheme, fixed step periods.rhs) and initial state: the
        base at the origin, the joints at q0, everything at rest (zero momentum)."""
        simulator = MakeSimulator(self.diagram, self.scenario.integration_scheme,
                                  self.scenario.periods.rhs)
        plant_context = self.plant.GetMyContextFromRoot(simulator.get_mutable_context())
        self.plant.SetPositions(plant_context,
                                np.concatenate([[0.0, 0.0, 0.0], self.scenario.q0]))
        self.plant.SetVelocities(plant_context, np.zeros(self.plant.num_velocities()))
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


def _BuildCommon(scenario: Scenario, builder: DiagramBuilder, excitation: Excitation):
    """Plant, true RHS, disturbance and LHS controller; loggers shared by all loops."""
    scenario.Validate()
    model = ReducedOrderModel(MakeArmPlant(scenario.nominal_robot))
    _RequireRunnableStart(scenario, model)
    plant, scene_graph = AddFreeFloatingArm(builder, scenario.robot)
    plant.set_name("plant")
    splitter = AddStateSplitter(builder, plant)
    lambda_min, lambda_max = mass_matrix_bounds(model)
    c_min = c_lower_bound(scenario.rhs.Td, scenario.lhs.Kd, lambda_min, 1.0)
    potential = BaseRepulsionPotential(scenario.nominal_robot, scenario.potential)
    alpha0 = float(np.sum(scenario.q0))               # base at theta0 = 0
    reference = OrientationReference(scenario.reference, alpha0)

    truth = builder.AddNamedSystem("true_rhs", TrueRhs(scenario))
    disturbance = builder.AddNamedSystem(
        "disturbance", DisturbanceSource(scenario.disturbance, scenario.disturbance_start))
    lhs = builder.AddNamedSystem("lhs_controller", LhsController(
        model=model, potential=potential, reference=reference, gains=scenario.lhs,
        period=scenario.periods.lhs, excitation=excitation))
    builder.Connect(plant.get_state_output_port(), truth.GetInputPort("state"))
    builder.Connect(disturbance.GetOutputPort("disturbance_model"),
                    truth.GetInputPort("disturbance_model"))
    builder.Connect(truth.GetOutputPort("tau"), plant.get_actuation_input_port())
    for signal in ("base_pose", "q", "qdot"):
        builder.Connect(splitter.GetOutputPort(signal), lhs.GetInputPort(signal))

    loop = ClosedLoop(diagram=None, scenario=scenario, plant=plant, scene_graph=scene_graph, model=model,
                      potential=potential, lambda_min_M=lambda_min,
                      lambda_max_M=lambda_max, c_min_nominal=c_min,
                      systems={"state_splitter": splitter, "true_rhs": truth,
                               "disturbance": disturbance,
                               "lhs_controller": lhs})
    period = scenario.periods.log
    for name, port in [("state", plant.get_state_output_port()),
                       ("tau", truth.GetOutputPort("tau")),
                       ("true_matrices", truth.GetOutputPort("true_matrices")),
                       ("disturbance", disturbance.GetOutputPort("disturbance")),
                       ("tau_request", lhs.GetOutputPort("tau_request")),
                       ("lhs_log", lhs.GetOutputPort("lhs_log"))]:
        loop.loggers[name] = LogVectorOutput(port, builder, period)
        loop.loggers[name].set_name(f"log_{name}")
    return loop


def build_dac_diagram(scenario: Scenario, learning: bool = True) -> ClosedLoop:
    """Plant + true RHS + disturbance, closed by the DAC-pH controller: the LHS
    sliding-mode controller (chi from the RHS loop, plus scenario.excitation), the
    port observer, the RHS integrator and the learner (in regularized mode behind a
    RegressionFilter). With ``learning`` False the learner keeps its initial
    weights, so the integrator runs on the nominal RHS (B0, D0): the dac-nominal
    ablation, otherwise the same diagram."""
    builder = DiagramBuilder()
    loop = _BuildCommon(scenario, builder, excitation=scenario.excitation)
    rhs_settings = scenario.rhs
    check_rhs_period(scenario.periods, (1 + rhs_settings.c_margin) * loop.c_min_nominal,
                     (1 + rhs_settings.c_margin) * c_lower_bound(
                         rhs_settings.Td, scenario.lhs.Kd, loop.lambda_min_M,
                         rhs_settings.beta_max),
                     rhs_settings.beta_max)
    lhs, splitter = loop.systems["lhs_controller"], loop.systems["state_splitter"]
    truth = loop.systems["true_rhs"]
    periods, settings = scenario.periods, scenario.learner
    regularized = settings.mode == "regularized"
    observer = builder.AddNamedSystem("port_observer", PortObserver(
        num_joints=loop.model.num_joints, sample_period=periods.rhs,
        noise_std=scenario.rhs.observer_noise, seed=scenario.seed,
        anti_alias_cutoff=settings.band[1] if regularized else 0.0))
    prefilter = (builder.AddNamedSystem("regression_filter", RegressionFilter(
        settings=settings, num_joints=loop.model.num_joints,
        period=periods.learner_sample)) if regularized else None)
    learner = builder.AddNamedSystem("learner", RhsLearner(
        model=loop.model, settings=settings, period=periods.learner,
        sample_period=periods.learner_sample, B0=scenario.uncertainty.B0,
        D0=scenario.uncertainty.D0, seed=scenario.seed, learning=learning))
    rhs = builder.AddNamedSystem("rhs_integrator", RhsIntegrator(
        model=loop.model, network=learner.exported, settings=scenario.rhs,
        Kd_max=scenario.lhs.Kd, lambda_min_M=loop.lambda_min_M, B0=scenario.uncertainty.B0,
        period=periods.rhs, model_period=periods.learner_sample,
        initial_weights=learner.initial_weights, stress=scenario.stress))
    # The data path, in order: plant -> port observer -> (band-pass) -> learner ->
    # RHS integrator -> true RHS -> plant; the LHS's request and model feed in.
    for signal in ("q", "qdot"):
        builder.Connect(splitter.GetOutputPort(signal), observer.GetInputPort(signal))
    builder.Connect(lhs.GetOutputPort("reduced_model"),
                    observer.GetInputPort("reduced_model"))
    builder.Connect(rhs.GetOutputPort("u"), observer.GetInputPort("u"))
    port_sample = observer.GetOutputPort("port_sample")
    if prefilter is not None:
        builder.Connect(port_sample, prefilter.GetInputPort("port_sample"))
        port_sample = prefilter.GetOutputPort("filtered_sample")
        loop.systems["regression_filter"] = prefilter
    builder.Connect(port_sample, learner.GetInputPort("port_sample"))
    for signal in ("q", "qdot"):
        builder.Connect(splitter.GetOutputPort(signal), learner.GetInputPort(signal))
    builder.Connect(observer.GetOutputPort("tau_observed"),
                    rhs.GetInputPort("tau_observed"))
    builder.Connect(lhs.GetOutputPort("tau_request"), rhs.GetInputPort("tau_request"))
    builder.Connect(learner.GetOutputPort("weights"), rhs.GetInputPort("weights"))
    builder.Connect(learner.GetOutputPort("beta_hat"), rhs.GetInputPort("beta_hat"))
    for signal in ("q", "qdot"):
        builder.Connect(splitter.GetOutputPort(signal), rhs.GetInputPort(signal))
    builder.Connect(rhs.GetOutputPort("u"), truth.GetInputPort("u"))
    builder.Connect(rhs.GetOutputPort("chi"), lhs.GetInputPort("chi"))
    loop.systems.update(port_observer=observer, learner=learner, rhs_integrator=rhs)
    for name, port in [("u", rhs.GetOutputPort("u")),
                       ("tau_observed", observer.GetOutputPort("tau_observed")),
                       ("rhs_log", rhs.GetOutputPort("rhs_log")),
                       ("learner_log", learner.GetOutputPort("learner_log")),
                       ("estimates", learner.GetOutputPort("estimates"))]:
        loop.loggers[name] = LogVectorOutput(port, builder, periods.log)
        loop.loggers[name].set_name(f"log_{name}")
    loop.diagram = builder.Build()
    loop.diagram.set_name("dac_closed_loop" if learning else "dac_nominal_closed_loop")
    return loop


def build_dac_nominal_diagram(scenario: Scenario) -> ClosedLoop:
    """The learning ablation: build_dac_diagram with the learner switched off (the
    integrator on the nominal RHS B0, D0; the excitation stays, so that learning is
    the only difference)."""
    return build_dac_diagram(scenario, learning=False)


def build_model_based_diagram(scenario: Scenario) -> ClosedLoop:
    """The baseline (docs/equations.md, SPEC settings): the same LHS controller with chi from a
    constant source (lhs.chi_model_based) and the static inversion u = B0^-1 (tau_c^r + D0 qdot);
    no integrator, no learning."""
    builder = DiagramBuilder()
    loop = _BuildCommon(scenario, builder, excitation=Excitation(amplitude=0.0))
    lhs = loop.systems["lhs_controller"]
    chi = builder.AddNamedSystem("fixed_chi", ConstantVectorSource(
        [scenario.lhs.chi_model_based]))
    builder.Connect(chi.get_output_port(), lhs.GetInputPort("chi"))
    inverter = builder.AddNamedSystem("model_based_inverter", ModelBasedInverter(scenario))
    builder.Connect(lhs.GetOutputPort("tau_request"), inverter.GetInputPort("tau_request"))
    builder.Connect(loop.systems["state_splitter"].GetOutputPort("qdot"),
                    inverter.GetInputPort("qdot"))
    builder.Connect(inverter.GetOutputPort("u"), loop.systems["true_rhs"].GetInputPort("u"))
    loop.systems["model_based_inverter"] = inverter
    loop.loggers["u"] = LogVectorOutput(inverter.GetOutputPort("u"), builder,
                                        scenario.periods.log)
    loop.loggers["u"].set_name("log_u")
    loop.diagram = builder.Build()
    loop.diagram.set_name("model_based_closed_loop")
    return loop

