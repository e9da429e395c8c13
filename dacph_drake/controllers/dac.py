"""DAC-pH (the paper's controller) and its learning ablation: the LHS controller (chi from
the RHS loop), port observer, regression filter, learner and RHS integrator."""
import logging
from typing import Dict, Optional

import numpy as np
from pydrake.systems.framework import LeafSystem, OutputPort
from pydrake.systems.primitives import LinearSystem

from dacph_drake.controllers.closed_loop import (AddLhsSide, ClosedLoop, ControllerBuilder,
                                                 DelayLine, LhsRequest,
                                                 assemble_closed_loop)
from dacph_drake.dynamics.sensor_noise import measured_rate_noise
from dacph_drake.gain_rule import (best_damped_gain, c_lower_bound, check_rhs_period,
                                   decay_rate, lag_pole)
from dacph_drake.kernels.certificate import lag_weight
from dacph_drake.learning import LearnerTrial, learner_kind
from dacph_drake.scenario import Scenario
from dacph_drake.systems.inertial_identifier import InertialIdentifier
from dacph_drake.systems.learner import RhsLearner
from dacph_drake.systems.port_observer import PortObserver
from dacph_drake.systems.regression_filter import RegressionFilter
from dacph_drake.systems.rhs_integrator import RhsIntegrator, RhsTrial
from dacph_drake.systems.sensors import measures_nothing


def build_dac_diagram(*scenarios: Scenario, learning: bool = True) -> ClosedLoop:
    """Builds "dac": the LHS (chi from the RHS loop) and the RHS side (AddRhsChain).

    Args:
        *scenarios: One scenario, or a batch of trials for one diagram.
        learning: False keeps the learner's initial weights (B0, D0): "dac_nominal"."""
    def add(loop: ClosedLoop, controller: ControllerBuilder):
        lhs, systems = AddLhsSide(loop, controller, loop.scenario.excitation,
                                  identify=loop.scenario.inertia.identify)
        return {**systems, **AddRhsChain(loop, controller, lhs, learning,
                                         systems.get("inertial_identifier"),
                                         LhsRequest(lhs, systems))}
    return assemble_closed_loop(scenarios[0], "dac" if learning else "dac_nominal", add,
                                scenarios[1:])


def build_dac_nominal_diagram(*scenarios: Scenario) -> ClosedLoop:
    """The ablation "dac_nominal": build_dac_diagram with the learner off (excitation on).

    Args:
        *scenarios: One scenario, or a batch of trials for one diagram."""
    return build_dac_diagram(*scenarios, learning=False)


def _WarnOfADelayedLoop(scenario: Scenario, wanted: float, separation: float) -> None:
    """Warns when the command's known delay and lag leave the RHS loop best damped
    below ``wanted``, the gain rule's rate at beta_hat = 1 [1/s]: the integrator then
    runs at the best-damped rate, and whether its loop decays at the time-scale
    separation's ``separation`` = Td lambda_LHS [1/s] (eq. 45, judged on the loop's decay
    rate: gain_rule.separates_by_decay) is said; verify reports both."""
    delay, lag = scenario.sensing.KnownCommandDelay()
    if not (delay or lag):
        return
    h = scenario.periods.rhs
    gain, radius = best_damped_gain(h, delay, lag)
    cap, fastest = gain / h, decay_rate(radius, h)
    if wanted <= cap:
        return
    capped = ("with the command %d samples late and a %g s actuator lag the RHS loop is "
              "best damped at c = %.0f 1/s, below the gain rule's %.0f 1/s (eq. 48)"
              % (delay, lag, cap, wanted))
    log = logging.getLogger(__name__)
    if fastest >= separation:
        log.warning("%s: the integrator runs at %.0f 1/s, where the loop decays at %.0f "
                    "1/s and meets the time-scale separation's %.0f 1/s (eq. 45)",
                    capped, cap, fastest, separation)
    else:
        log.warning("%s, and decays there at %.0f 1/s, the fastest any gain gives it: "
                    "the time-scale separation (eq. 45) asks %.0f 1/s and is not met; a "
                    "shorter delay or lag, or a slower LHS meets it (its damping, which "
                    "the separation's rate is proportional to, times %.2f or less)",
                    capped, fastest, separation, fastest / separation)


def _WarnOfANoisyKinematicCheck(scenario: Scenario,
                                identifier: Optional[InertialIdentifier]) -> None:
    """Warns when the identifier's kinematic check (inertia.fit_tolerance) judges a
    momentum misfit measured through noisy sensors: their noise alone can leave more
    misfit than a link error of a few per cent, so a run reports a mismatch it does
    not have and its claims become the prior's (docs/results/sensing.md)."""
    if (identifier is None or scenario.inertia.fit_tolerance <= 0
            or not scenario.sensing.enabled or measures_nothing(scenario.sensing)):
        return
    logging.getLogger(__name__).warning(
        "inertia.fit_tolerance = %g judges a momentum misfit measured through noisy "
        "sensors, whose noise alone can exceed it: a reported kinematic mismatch may be "
        "the noise's (the claims then become the prior's); allowed: 0 (no check) or a "
        "tolerance above the sensors' misfit", scenario.inertia.fit_tolerance)


def _ObservedCommand(builder, scenario: Scenario, u: OutputPort) -> OutputPort:
    """The command as the port observer's torque saw it: u itself, or with a known delay
    d (sensing.rhs_delay + latency) and lag, u d samples late through the lag averaged
    over the sample, (1 - b) u_d + b s, s(k+1) = a s(k) + (1 - a) u_d
    (kernels.certificate.lag_weight): so the learner pairs each torque with the command
    that produced it (a discrete LinearSystem, compiled)."""
    delay, lag = scenario.sensing.KnownCommandDelay()
    h, size = scenario.periods.rhs, u.size()
    if delay > 0:
        line = builder.AddNamedSystem("observed_command_delay",
                                      DelayLine(h, delay, size))
        builder.Connect(u, line.get_input_port())
        u = line.get_output_port()
    if lag > 0:
        a, identity = lag_pole(h, lag), np.eye(size)
        b = lag_weight(a)
        average = builder.AddNamedSystem("observed_command_lag", LinearSystem(
            a * identity, (1 - a) * identity, b * identity, (1 - b) * identity,
            time_period=h))
        builder.Connect(u, average.get_input_port())
        u = average.get_output_port()
    return u


def AddRhsChain(loop: ClosedLoop, controller: ControllerBuilder, lhs: LeafSystem,
                learning: bool, identifier: Optional[InertialIdentifier] = None,
                request: Optional[OutputPort] = None) -> Dict[str, object]:
    """Adds the RHS side (port observer, regression filter in regularized mode, learner,
    RHS integrator), wired to the LHS and inputs q, qdot; exports u, tau_observed, the logs,
    estimates and bounds; returns the systems by name. The RHS period is checked for the
    largest c the gain rule (eq. 48) allows (gain_rule.check_rhs_period).

    Args:
        loop: The loop being built.
        controller: The controller's ControllerBuilder.
        lhs: The LHS controller (outputs ``reduced_model``, ``tau_request``; input ``chi``).
        learning: False keeps the learner's initial weights (dac-nominal).
        identifier: The LHS's InertialIdentifier, if any (Learner.model_change watches it).
        request: The request tau_c^r as the RHS receives it (closed_loop.LhsRequest;
            None: the LHS's own output).

    Raises:
        ConfigError: The RHS period cannot realize the gain rule's largest rate."""
    scenario, model = loop.scenario, loop.model
    rhs_settings, periods, settings = scenario.rhs, scenario.periods, scenario.learner
    rates = [robot.task.GainRuleRates(robot) for robot in loop.robots]
    # The gain rule's rate at beta_hat = 1, where every run starts, per trial.
    c_nominal = [(1 + rhs_settings.c_margin) * c_lower_bound(
        rhs_settings.Td, Kd_max, lambda_min_M, 1.0) for Kd_max, lambda_min_M in rates]
    for c, (Kd_max, lambda_min_M) in zip(c_nominal, rates):
        check_rhs_period(periods, c, (1 + rhs_settings.c_margin) * c_lower_bound(
                             rhs_settings.Td, Kd_max, lambda_min_M, rhs_settings.beta_max),
                         rhs_settings.beta_max)
    _WarnOfADelayedLoop(scenario, max(c_nominal), rhs_settings.Td * max(
        2.0 * Kd_max / lambda_min_M for Kd_max, lambda_min_M in rates))
    _WarnOfANoisyKinematicCheck(scenario, identifier)
    builder = controller.builder
    kind = learner_kind(settings)
    regularized = kind.BandPassed(settings)
    observer = builder.AddNamedSystem("port_observer", PortObserver(
        num_joints=model.num_joints, sample_period=periods.rhs,
        noise_std=rhs_settings.observer_noise, seeds=[s.seed for s in loop.scenarios],
        anti_alias_cutoff=settings.band[1] if regularized else 0.0,
        joint_damping=model.joint_damping))
    trials = [LearnerTrial(model=robot.model, B0=s.uncertainty.B0, D0=s.uncertainty.D0,
                           seed=s.seed, q0=s.q0)
              for robot, s in zip(loop.robots, loop.scenarios)]
    learner = RhsLearner(trials=trials, settings=settings, period=periods.learner,
                         sample_period=periods.learner_sample, learning=learning,
                         watch_model=identifier is not None)
    prefilter = (builder.AddNamedSystem("regression_filter", RegressionFilter(
        settings=settings, num_joints=model.num_joints,
        period=periods.learner_sample, trials=loop.trials,
        channels=learner.learner.channels)) if regularized else None)
    builder.AddNamedSystem("learner", learner)
    if identifier is not None:
        builder.Connect(identifier.GetOutputPort("model_epoch"),
                        learner.GetInputPort("model_epoch"))
        builder.Connect(identifier.GetOutputPort("identification_log"),
                        learner.GetInputPort("identification_log"))
    rhs = builder.AddNamedSystem("rhs_integrator", RhsIntegrator(
        trials=[RhsTrial(model=robot.model, network=kind.Published(settings, trial),
                         Kd_max=Kd_max, lambda_min_M=lambda_min_M, B0=s.uncertainty.B0,
                         D0=s.uncertainty.D0,
                         prior_set=kind.PriorSet(s.learner, s.uncertainty.B0,
                                                 s.uncertainty.D0))
                for robot, s, trial, (Kd_max, lambda_min_M)
                in zip(loop.robots, loop.scenarios, trials, rates)],
        settings=rhs_settings, period=periods.rhs,
        model_period=periods.learner_sample, stress=scenario.stress,
        channels=learner.learner.channels if regularized else None,
        command_delay=scenario.sensing.KnownCommandDelay(),
        noisy_torque=any(measured_rate_noise(s.sensing, periods.rhs) > 0
                         or s.rhs.observer_noise > 0 for s in loop.scenarios)))
    # The data path, in order: plant -> port observer -> (band-pass) -> learner ->
    # RHS integrator -> u (to the true RHS); the LHS's request and model feed in.
    for signal in ("q", "qdot"):
        controller.Input(observer.GetInputPort(signal), signal)
    for system in (observer, learner, rhs):      # M for p = M qdot, the observer's
        builder.Connect(lhs.GetOutputPort("reduced_model"),
                        system.GetInputPort("reduced_model"))
    builder.Connect(_ObservedCommand(builder, scenario, rhs.GetOutputPort("u")),
                    observer.GetInputPort("u"))
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
    builder.Connect(request or lhs.GetOutputPort("tau_request"),
                    rhs.GetInputPort("tau_request"))
    builder.Connect(learner.GetOutputPort("weights"), rhs.GetInputPort("weights"))
    builder.Connect(learner.GetOutputPort("beta_hat"), rhs.GetInputPort("beta_hat"))
    for signal in ("q", "qdot"):
        controller.Input(rhs.GetInputPort(signal), signal)
    builder.ExportOutput(rhs.GetOutputPort("u"), "u")
    builder.Connect(rhs.GetOutputPort("chi"), lhs.GetInputPort("chi"))
    for name, port in [("tau_observed", observer.GetOutputPort("tau_observed")),
                       ("rhs_log", rhs.GetOutputPort("rhs_log")),
                       ("learner_log", learner.GetOutputPort("learner_log")),
                       ("estimates", learner.GetOutputPort("estimates")),
                       ("estimate_bounds", learner.GetOutputPort("estimate_bounds"))]:
        builder.ExportOutput(port, name)
    systems = {"port_observer": observer, "learner": learner, "rhs_integrator": rhs}
    if prefilter is not None:
        systems["regression_filter"] = prefilter
    return systems
