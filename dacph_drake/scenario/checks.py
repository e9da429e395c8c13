"""The checks of the sections every robot and task share (their own: robots/, tasks/)."""
from typing import List, Sequence, Tuple

import numpy as np

from dacph_drake.scenario.errors import (ConfigError, require_finite_numbers, require_in_range,
                                require_nonnegative, require_one_of, require_positive)
from dacph_drake.scenario.simulator import validate_simulator_config
from dacph_drake.scenario import (ADOPTIONS, GAIN_RULES, INERTIA_ANCHORS, LEARNER_COUPLINGS,
                                  LEARNER_MODES, LEARNER_PRIOR_SCALES, ON_MISMATCH,
                                  RATE_SOURCES, TRUST_ANCHORS, LocalBayes, Periods,
                                  Phases, Scenario, Sensing)


def check_period_order(periods: Periods) -> None:
    """Refuses periods breaking rhs < lhs <= learner_sample <= learner (time scales).

    Args:
        periods: The scenario's periods.

    Raises:
        ConfigError: Naming the two periods out of order."""
    order = [("rhs", periods.rhs), ("lhs", periods.lhs),
             ("learner_sample", periods.learner_sample), ("learner", periods.learner)]
    for (fast, h_fast), (slow, h_slow) in zip(order, order[1:]):
        if not h_fast <= h_slow:
            raise ConfigError(
                f"periods.{fast} = {h_fast:g} s must not exceed periods.{slow} = "
                f"{h_slow:g} s (time-scale separation: RHS faster than LHS faster "
                "than the learner)")
    if periods.lhs == periods.rhs:
        raise ConfigError(f"periods.rhs = {periods.rhs:g} s must be shorter than "
                          f"periods.lhs = {periods.lhs:g} s")


def validate_shared(scenario: Scenario, task: "Task", n: int, joint_names: Sequence[str] = ()
                    ) -> None:
    """Checks the seed and shared sections (robots' constructors call it: Python's too).

    Args:
        scenario: The scenario.
        task: Its tasks.Task, whose Validate checks the task section.
        n: The robot's number of joints.
        joint_names: Their names in q's order, for the messages (none: not named).

    Raises:
        ConfigError: Naming the first invalid setting of those sections."""
    validate_seed(scenario.seed)
    if joint_names and len(scenario.q0) != n:
        raise ConfigError(f"q0 has {len(scenario.q0)} entries; allowed: {n} (one per "
                          f"joint); the joints in q0's order: "
                          f"{', '.join(joint_names)}")
    require_length("q0", scenario.q0, n)
    validate_start(scenario.q0)
    task.Validate(scenario.task, scenario.periods)
    validate_phases(scenario.phases)
    require_positive("phases (total)", scenario.phases.end, "s")
    require_in_range("inertia.prior_weight", scenario.inertia.prior_weight, 1e-14, 1.0)
    require_nonnegative("inertia.start", scenario.inertia.start, "s")
    require_positive("inertia.duration", scenario.inertia.duration, "s")
    require_in_range("inertia.change_threshold", scenario.inertia.change_threshold,
                     0.0, 1.0)
    require_one_of("inertia.anchor", scenario.inertia.anchor, INERTIA_ANCHORS)
    require_nonnegative("inertia.anchor_mass", scenario.inertia.anchor_mass, "kg")
    require_in_range("inertia.anchor_error", scenario.inertia.anchor_error, -0.5, 0.5)
    require_nonnegative("inertia.fit_tolerance", scenario.inertia.fit_tolerance)
    require_one_of("inertia.on_mismatch", scenario.inertia.on_mismatch, ON_MISMATCH)
    require_in_range("inertia.nominal_tolerance", scenario.inertia.nominal_tolerance,
                     0.0, 0.999)
    require_in_range("inertia.anchor_tolerance", scenario.inertia.anchor_tolerance, 0.0,
                     0.5)
    require_in_range("inertia.kinematic_tolerance", scenario.inertia.kinematic_tolerance,
                     0.0, 0.5)
    require_in_range("inertia.error_draws", scenario.inertia.error_draws, 2, 256)
    validate_port_settings(scenario, n)
    validate_sensing(scenario.sensing, scenario.periods)
    validate_simulator_config(scenario.simulator)
    # Last, so that a setting with a range names it: every other number finite.
    require_finite_numbers("", scenario)


# The largest |q0_i| [rad]: beyond it sin and cos of an angle lose every digit.
MAX_ANGLE = 1e3


def validate_start(q0: Sequence[float]) -> None:
    """Requires q0's angles finite and within +-MAX_ANGLE rad.

    Args:
        q0: The initial joint angles [rad]."""
    require_finite_numbers("q0", list(q0))
    if len(q0) and float(np.max(np.abs(np.asarray(q0, float)))) > MAX_ANGLE:
        raise ConfigError(f"q0 = {list(q0)}; allowed: angles within +-{MAX_ANGLE:g} rad")


def validate_seed(seed: object) -> None:
    """Requires a valid seed.

    Args:
        seed: The scenario's seed.

    Raises:
        ConfigError: Unless ``seed`` is an integer in [0, 2^32 - 1]."""
    if isinstance(seed, bool) or not isinstance(seed, int):
        raise ConfigError(f"seed = {seed!r} is not an integer; allowed: an integer in "
                          "[0, 2^32 - 1]")
    require_in_range("seed", seed, 0, 2**32 - 1)


def validate_phases(phases: Phases) -> None:
    """Requires phase durations that can run.

    Args:
        phases: The scenario's phases.

    Raises:
        ConfigError: Unless every phase duration is >= 0."""
    for name in ("warmup", "linear", "nonlinear", "disturbance"):
        require_nonnegative(f"phases.{name}", getattr(phases, name), "s")


def validate_sensing(sensing: Sensing, periods: Periods) -> None:
    """Checks the sensing section (ranges; the star tracker no faster than the samples).

    Args:
        sensing: The section.
        periods: The scenario's periods (the sensors sample at periods.rhs)."""
    require_in_range("sensing.encoder_counts", sensing.encoder_counts, 0, 2**40,
                     "(0: unquantized)")
    for name in ("encoder_noise", "rate_noise", "gyro_noise", "gyro_bias_walk",
                 "star_tracker_noise", "actuator_lag"):
        require_nonnegative(f"sensing.{name}", getattr(sensing, name))
    require_finite_numbers("sensing.gyro_bias", [sensing.gyro_bias])
    require_one_of("sensing.rate_source", sensing.rate_source, RATE_SOURCES)
    require_positive("sensing.rate_cutoff", sensing.rate_cutoff, "Hz")
    require_in_range("sensing.star_tracker_rate", sensing.star_tracker_rate, 0.0,
                     1.0 / periods.rhs, "Hz (0: exact; at most 1 / periods.rhs)")
    for name in ("latency", "lhs_delay", "rhs_delay", "unmodelled_delay"):
        require_in_range(f"sensing.{name}", getattr(sensing, name), 0, 1000, "samples")


def validate_port_settings(scenario: Scenario, n: int) -> None:
    """Checks rhs, stress, periods, uncertainty, disturbance, learner and excitation.

    Args:
        scenario: The scenario.
        n: Its robot's number of joints.

    Raises:
        ConfigError: Naming the first invalid setting of the port's RHS chain."""
    require_positive("rhs.Td", scenario.rhs.Td)
    require_nonnegative("rhs.c_margin", scenario.rhs.c_margin)
    for name in ("c_time_constant", "chi_window", "chi_floor", "chi_initial"):
        require_positive(f"rhs.{name}", getattr(scenario.rhs, name))
    require_nonnegative("rhs.observer_noise", scenario.rhs.observer_noise, "N m")
    require_in_range("rhs.trust_ratio", scenario.rhs.trust_ratio, 1.0, 10.0)
    require_one_of("rhs.trust_anchor", scenario.rhs.trust_anchor, TRUST_ANCHORS)
    require_one_of("rhs.gain_rule", scenario.rhs.gain_rule, GAIN_RULES)
    require_one_of("rhs.adoption", scenario.rhs.adoption, ADOPTIONS)
    require_in_range("rhs.evidence_ratio", scenario.rhs.evidence_ratio, 0.0, 1.0)
    require_positive("rhs.evidence_window", scenario.rhs.evidence_window, "s")
    require_in_range("rhs.beta_max", scenario.rhs.beta_max, 1.0, 1e6)
    require_positive("stress.B_hat_scale", scenario.stress.B_hat_scale)
    require_nonnegative("stress.start", scenario.stress.start, "s")
    periods = scenario.periods
    for key in ("rhs", "lhs", "learner", "learner_sample", "log"):
        require_positive(f"periods.{key}", getattr(periods, key), "s")
    check_period_order(periods)
    if periods.log > scenario.duration:
        raise ConfigError(f"periods.log = {periods.log:g} s is longer than "
                          f"the run ({scenario.duration:g} s); allowed: at most the "
                          "run's duration")
    u = scenario.uncertainty
    for name in ("B0", "D0", "D_offset", "D_linear", "D_quadratic", "B_quadratic"):
        require_length(f"uncertainty.{name}", getattr(u, name), n)
    for name in ("B_linear", "B_q1_squared"):
        matrix = getattr(u, name)
        if len(matrix) != n or any(len(row) != n for row in matrix):
            raise ConfigError(f"uncertainty.{name} must be a {n} x {n} matrix")
    for i, b in enumerate(u.B0):
        require_positive(f"uncertainty.B0[{i}]", b)
    for i, d in enumerate(u.D0):
        require_nonnegative(f"uncertainty.D0[{i}]", d)
    require_nonnegative("uncertainty.linear_scale", u.linear_scale)
    require_nonnegative("uncertainty.nonlinear_scale", u.nonlinear_scale)
    if len(u.B_scale) not in (0, n):
        raise ConfigError(f"uncertainty.B_scale has {len(u.B_scale)} entries; allowed: "
                          f"{n} (one per joint) or none (all 1)")
    for i, g in enumerate(u.B_scale):
        require_in_range(f"uncertainty.B_scale[{i}]", g, 1e-2, 1e2)
    for i, fault in enumerate(u.faults):
        where = f"uncertainty.faults[{i}]"
        require_nonnegative(f"{where}.time", fault.time, "s")
        if isinstance(fault.joint, bool) or not isinstance(fault.joint, int):
            raise ConfigError(f"{where}.joint = {fault.joint!r} is not an integer; "
                              f"allowed: a joint number in [1, {n}]")
        require_in_range(f"{where}.joint", fault.joint, 1, n, "(1-based joint number)")
        require_in_range(f"{where}.gain", fault.gain, 1e-2, 1e2)
    d = scenario.disturbance
    for name in ("lf_offset", "lf_amplitude", "lf_frequency", "hf_direction"):
        require_length(f"disturbance.{name}", getattr(d, name), n)
    require_nonnegative("disturbance.scale", d.scale)
    require_nonnegative("disturbance.hf_frequency", d.hf_frequency, "Hz")
    for name, time in scheduled_events(scenario):
        require_before_end(name, time, scenario.duration)
    L = scenario.learner
    require_one_of("learner.mode", L.mode, LEARNER_MODES)
    require_one_of("learner.coupling", L.coupling, LEARNER_COUPLINGS)
    require_one_of("learner.prior_scale", L.prior_scale, LEARNER_PRIOR_SCALES)
    if len(L.hidden) == 0:
        raise ConfigError("learner.hidden is empty; allowed: at least one layer")
    for i, width in enumerate(L.hidden):
        require_in_range(f"learner.hidden[{i}]", width, 1, 4096)
    require_positive("learner.learning_rate", L.learning_rate)
    require_in_range("learner.window", L.window, 2, 10**6)
    require_in_range("learner.steps_per_update", L.steps_per_update, 0, 10**4)
    require_in_range("learner.beta1", L.beta1, 0.0, 0.999999)
    require_in_range("learner.beta2", L.beta2, 0.0, 0.999999)
    require_positive("learner.eps", L.eps)
    require_positive("learner.momentum_scale", L.momentum_scale)
    nyquist = 0.5 / periods.learner_sample
    require_length("learner.band", L.band, 2, "[low, high] in Hz")
    require_in_range("learner.band[0]", L.band[0], 0.0, nyquist,
                     "Hz (0: no high-pass; at most the Nyquist frequency of "
                     "periods.learner_sample)")
    require_in_range("learner.band[1]", L.band[1], L.band[0], nyquist,
                     "Hz (above band[0], at most the Nyquist frequency of "
                     "periods.learner_sample)")
    require_length("learner.band_sections", L.band_sections, 2,
                    "[high-pass, low-pass] section counts")
    for i, count in enumerate(L.band_sections):
        require_in_range(f"learner.band_sections[{i}]", count, 0, 16)
    require_positive("learner.forgetting", L.forgetting, "s")
    require_nonnegative("learner.prior_weight", L.prior_weight)
    require_in_range("learner.change_ratio", L.change_ratio, 1.0, 1e6)
    require_nonnegative("learner.change_floor", L.change_floor)
    require_nonnegative("learner.change_hold", L.change_hold, "s")
    require_nonnegative("learner.start_hold", L.start_hold, "s")
    if L.step_guard != 0:
        require_in_range("learner.step_guard", L.step_guard, 1.0, 1e12, "(0: off)")
    require_in_range("learner.min_window", L.min_window, 0.0,
                     L.window * periods.learner_sample,
                     "s (at most learner.window * periods.learner_sample)")
    validate_local_bayes(L.bayes, L.window * periods.learner_sample)
    E = scenario.excitation
    require_nonnegative("excitation.amplitude", E.amplitude, "N m")
    if E.joint_scale:
        require_length("excitation.joint_scale", E.joint_scale, n,
                        "one per joint, or none")
        for i, factor in enumerate(E.joint_scale):
            require_in_range(f"excitation.joint_scale[{i}]", factor, 0.0, 1.0)
    require_length("excitation.frequencies", E.frequencies, 2,
                    "[first, last] in Hz")
    require_in_range("excitation.frequencies[0]", E.frequencies[0], 1e-3,
                     0.5 / periods.lhs, "Hz (at most the Nyquist frequency "
                     "of periods.lhs)")
    require_in_range("excitation.frequencies[1]", E.frequencies[1],
                     E.frequencies[0], 0.5 / periods.lhs,
                     "Hz (at least frequencies[0], at most the Nyquist frequency "
                     "of periods.lhs)")
    if E.amplitude > 0 and L.mode == "regularized" and not (
            L.band[0] < E.frequencies[0] and E.frequencies[1] < L.band[1]):
        raise ConfigError(
            f"excitation.frequencies = {E.frequencies} Hz lie outside learner.band "
            f"= {L.band} Hz; allowed: inside the band (the learner filters "
            "everything else out)")


def validate_local_bayes(bayes: LocalBayes, window: float) -> None:
    """Checks the local Bayesian learner's settings (learner.bayes).

    Args:
        bayes: The settings.
        window: The learner's window, learner.window * periods.learner_sample [s].

    Raises:
        ConfigError: Naming the first invalid setting and its allowed range."""
    for name, values, low_range, high_range in (
            ("gain_range", bayes.gain_range, (1e-3, 1.0), (1.0, 100.0)),
            ("damping_range", bayes.damping_range, (0.0, 1.0), (1.0, 100.0))):
        require_length(f"learner.bayes.{name}", values, 2, "[low, high]")
        require_in_range(f"learner.bayes.{name}[0]", values[0], *low_range,
                         "(below 1)")
        require_in_range(f"learner.bayes.{name}[1]", values[1], *high_range,
                         "(above 1)")
        if not values[0] < 1.0 < values[1]:
            raise ConfigError(f"learner.bayes.{name} = {list(values)}; allowed: "
                              "low < 1 < high (the prior's range holds the prior)")
    require_in_range("learner.bayes.coupling", bayes.coupling, 0.0, 1.0)
    require_positive("learner.bayes.drift", bayes.drift, "1/s")
    require_positive("learner.bayes.momentum_slope", bayes.momentum_slope)
    require_nonnegative("learner.bayes.curvature", bayes.curvature, "1/s^2")
    require_nonnegative("learner.bayes.floor", bayes.floor)
    require_positive("learner.bayes.forgetting", bayes.forgetting, "s")
    require_in_range("learner.bayes.min_window", bayes.min_window, 1e-9, window,
                     "s (above 0, at most learner.window * periods.learner_sample)")
    require_in_range("learner.bayes.min_dof", bayes.min_dof, 1.0, 1e6)
    require_in_range("learner.bayes.credible_level", bayes.credible_level, 0.01, 0.999)
    require_in_range("learner.bayes.certificate_level", bayes.certificate_level,
                     bayes.credible_level, 0.999999,
                     "(at least learner.bayes.credible_level, below 1)")
    require_nonnegative("learner.bayes.margin", bayes.margin)
    require_nonnegative("learner.bayes.change_floor", bayes.change_floor)
    if not bayes.inconsistency > bayes.change_floor:
        raise ConfigError(f"learner.bayes.inconsistency = {bayes.inconsistency!r}; "
                          "allowed: a number above learner.bayes.change_floor = "
                          f"{bayes.change_floor!r}")
    require_in_range("learner.bayes.model_error", bayes.model_error, 0.0, 0.999,
                     "(a relative standard deviation, below 1)")


def require_length(name: str, values: Sequence, n: int, meaning: str = "one per joint"
                   ) -> None:
    """Requires ``n`` entries.

    Args:
        name: The setting.
        values: Its value.
        n: The entries allowed.
        meaning: What they are, for the message."""
    if len(values) != n:
        raise ConfigError(f"{name} has {len(values)} entries; allowed: {n} "
                          f"({meaning})")


def scheduled_events(scenario: Scenario) -> List[Tuple[str, float]]:
    """(setting, time [s]) of each fault, a timed disturbance start and a stress start.

    Args:
        scenario: The scenario."""
    events = [(f"uncertainty.faults[{i}].time", fault.time)
              for i, fault in enumerate(scenario.uncertainty.faults)]
    if scenario.disturbance.start >= 0:
        events.append(("disturbance.start", scenario.disturbance.start))
    if scenario.stress.B_hat_scale != 1.0:
        events.append(("stress.start", scenario.stress.start))
    return events


def require_before_end(name: str, time: float, duration: float) -> None:
    """Requires an event to start before the run ends (a later one never takes effect).

    Args:
        name: The setting's name, for the message.
        time: When the event starts [s].
        duration: The run's duration, the phases' end [s].

    Raises:
        ConfigError: The event starts at or after the run's end."""
    if time >= duration:
        raise ConfigError(f"{name} = {time:g} s is at or after the run's end "
                          f"({duration:g} s, the phases' end), so it never takes effect; "
                          f"allowed: < {duration:g} s, or longer phases")
