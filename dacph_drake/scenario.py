"""Scenario: every setting of a closed-loop run, loaded from YAML with
``pydrake.common.yaml.yaml_load_typed`` (the defaults are the paper's scenario, 1500 s,
with the SPEC settings listed in docs/equations.md)."""
import logging
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import List

import numpy as np
from pydrake.common.yaml import yaml_dump_typed
from pydrake.systems.analysis import SimulatorConfig

from dacph_drake.errors import (ConfigError, require_finite_numbers, require_in_range,
                                require_nonnegative, require_one_of, require_positive)
from dacph_drake.robot import RobotParams, load_yaml_dataclass
from dacph_drake.simulation import FixedStepConfig, validate_simulator_config


@dataclass
class Phases:
    """Durations [s]: warm-up (B0, D0 only), then (1) linear uncertainty, (2) plus
    nonlinear uncertainty, (3) plus the external disturbance d(t)."""
    warmup: float = 60.0
    linear: float = 480.0
    nonlinear: float = 480.0
    disturbance: float = 480.0

    @property
    def linear_start(self) -> float:
        return self.warmup

    @property
    def nonlinear_start(self) -> float:
        return self.warmup + self.linear

    @property
    def disturbance_start(self) -> float:
        return self.warmup + self.linear + self.nonlinear

    @property
    def end(self) -> float:
        return self.disturbance_start + self.disturbance


@dataclass
class LhsGains:
    """Sliding-mode LHS controller (docs/equations.md E23-E25): K_d = Kd I, Lambda, epsilon of
    chi tanh(s / epsilon), eta of xi = -eta grad U. A run must start where the task
    Jacobian's singular value ||D(q0)|| is at least min_task_singular_value (the
    paper's arm has 0.61 to 1.21 over all q)."""
    Kd: float = 0.5
    Lambda: float = 1.0
    epsilon: float = 0.2
    eta: float = 0.1
    chi_model_based: float = 0.05   # fixed chi of the model-based baseline [N m]
    min_task_singular_value: float = 0.05
    boundary_rate: float = 0.0      # [1/s]; chi tanh(s / phi), phi = epsilon + chi /
    #                                 (boundary_rate inf lambda_min(M)); 0: phi = epsilon


@dataclass
class InertiaIdentification:
    """The DAC loops' identification of the bodies' inertial parameters from momentum
    conservation (systems/inertial_identifier.py; README, "Model error"): from
    ``start`` [s] on, the LHS controller, and through it the port observer and the
    learner's samples, use the parameters that the measured base and joint motion
    determine, in place of nominal_robot's. Directions informed less than
    ``prior_weight`` times the average stay at nominal_robot's, and so does the
    common scale of all parameters (which momentum data cannot fix). An estimate that
    changes the reduced mass matrix at the current configuration by more than
    ``change_threshold`` in some entry (relative to sqrt(M_ii M_jj)) since the last
    such one restarts the learner's window (learner.model_change). The estimate
    is kept from ``start`` + ``duration`` on: the bodies' inertias do not change, and
    over the paper scenario's 1500 s the estimate, still refining directions the
    data hardly inform, wandered by 3 % (the learned B then ended phases 1-3 at
    0.13 to 0.30 of the prior's error against the truth, 0.03 to 0.07 before).
    ``identify`` False: the
    controller keeps nominal_robot (earlier releases).

    prior_weight is small because the simulated rates carry no noise: on the 6-DOF
    arm the directions that fix M lie 1e-11 to 1e-8 below the best-informed one
    (at 1e-8 its identified M stayed 10 % off the truth's, up to the scale; at
    1e-12, 4e-4)."""
    identify: bool = True
    prior_weight: float = 1e-12
    start: float = 0.2              # [s]
    duration: float = 10.0          # [s] of identification, then the estimate is kept
    change_threshold: float = 5e-2  # relative change of M(q) that restarts learning


@dataclass
class Potential:
    """Null-space artificial potential field U(q) (Khatib's FIRAS form
    U = k / 2 (1 / rho - 1 / rho0)^2 for rho < rho0):
    links against the base square (sample points along each link, clearance rho in
    metres) and each joint k >= 2 against folding (rho = pi - |q_k| in radians)."""
    base_gain: float = 1e-3         # k for link-base clearance [J m^2]
    base_margin: float = 0.06       # rho0 [m]
    fold_gain: float = 1e-3         # k for folding [J rad^2]
    fold_margin: float = 0.6        # rho0 [rad]
    points_per_link: int = 4


@dataclass
class Reference:
    """alpha_d(t) = alpha(0) + sum_i amplitudes[i] sin(2 pi t / periods[i]) [rad]."""
    amplitudes: List[float] = field(default_factory=lambda: [0.3, 0.1])
    periods: List[float] = field(default_factory=lambda: [30.0, 11.0])


@dataclass
class Rhs:
    """RHS integrator (docs/equations.md E48): k_p = c / Re(lambda_hat_p), c filtered towards
    (1 + c_margin) c_min with time constant c_time_constant; chi = peak of ||e_tau||
    with exponential forgetting over chi_window, never below chi_floor. A learned B_hat
is used only if it passes the DIC check and its eigenvalues lie within trust_ratio of
those of the trust band's anchor (the paper's bounded learning error, see
gain_rule.within_trust): ``trust_anchor`` "in_use" (default), the estimate the loop
runs on, so that the band moves with every accepted estimate and refuses only a
sudden jump, while the estimate stays within trust_ratio^2 of B0 overall; "prior",
B0 (the band of earlier releases, which refuses correct estimates wherever B0 is
far from the truth). An estimate outside the band is still
accepted on evidence: when, on the learner's port samples of the last
``evidence_window`` seconds, its port relation leaves at most ``evidence_ratio``
times the residual of the estimate in use (0: never). The gain rule reads
min(beta_hat, beta_max): periods.rhs is checked at build time for the largest c
that this allows, so the discrete loop never runs past the bound it was built for.
``gain_rule`` "paper" (default): c follows (1 + c_margin) c_min(beta_hat) (eq. 48);
"well_damped": c = 1 / (4 periods.rhs), the fastest decay whose discrete loop with
the estimate right is still well damped (at least the paper's rule's c: the period
check at build time guarantees it). With the estimate in use off by a factor r,
lambda~ = r lambda_hat, the loop stays certified (analysis.rhs_loop) for
Td lambda_LHS / c <= r <= 0.9025 / (h c); the faster c moves that band towards
weaker actuators, [0.39, 3.6] against the paper rule's [0.46, 4.2] at beta_hat = 1
on the paper's arm."""
    Td: float = 2.0
    c_margin: float = 0.1
    c_time_constant: float = 1.0    # [s]
    chi_window: float = 2.0         # [s]
    chi_floor: float = 1e-3         # [N m]
    chi_initial: float = 0.05       # [N m]
    observer_noise: float = 0.0     # std of tau_obs measurement noise [N m]
    trust_ratio: float = 2.0        # accept B_hat only if its eigenvalues are within
    #                                 this factor of the anchor's (gain_rule.within_trust)
    trust_anchor: str = "in_use"    # TRUST_ANCHORS: the band around the estimate in
    #                                 use, or around B0 ("prior")
    evidence_ratio: float = 0.5     # accept outside the band if the residual on the
    #                                 port samples is at most this times the in-use one's
    evidence_window: float = 1.0    # [s] forgetting of those samples' statistics
    beta_max: float = 2.0           # the largest beta_hat the gain rule uses: the RHS
    #                                 period is sized for c_min(beta_max), see RhsIntegrator
    gain_rule: str = "paper"        # GAIN_RULES


@dataclass
class Periods:
    """Discrete update periods [s] (docs/equations.md, SPEC settings): rhs < lhs < learner.

    rhs: the integrator and the observer's sampling; lhs: the sliding-mode
    controller and the observer's M, C' refresh; learner_sample: the learner's data
    sampling and the RHS loop's refresh of B_hat(x), D_hat(x) and K at the current
    state (they change on the seconds scale of the arm's motion and when the
    learner publishes); learner: a training step; log: the loggers."""
    rhs: float = 2.5e-4
    lhs: float = 1e-3
    learner: float = 0.1
    learner_sample: float = 0.01
    log: float = 0.01


@dataclass
class ActuatorFault:
    """An actuator fault: from ``time`` [s] on, the actuator of joint ``joint``
    (1-based, the paper's q_joint) delivers ``gain`` times the torque it did
    before (row ``joint`` of B~ is multiplied by ``gain``; faults on one joint
    compound)."""
    time: float = 0.0               # [s]
    joint: int = 1                  # 1 .. n
    gain: float = 0.5               # [-]


@dataclass
class Uncertainty:
    """Ground-truth RHS (docs/equations.md E19, SPEC settings):
    B~ = diag(g(t)) (B0 + Delta B), D~ = D0 + Delta D with
    Delta D(p) = diag(D_offset + D_linear * p)            [linear phase on]
               + diag(D_quadratic * p * p)                [nonlinear phase on]
    Delta B(x) = diag(B_linear @ q)                       [linear phase on]
               + diag(B_quadratic * p * p) + B_q1_squared q1^2   [nonlinear phase on]
    each group multiplied by linear_scale / nonlinear_scale, and the actuators'
    gains g_j(t) = B_scale[j] times the gain of every fault on joint j whose time
    has come (from t = 0, warm-up included: a motor constant off its datasheet,
    an actuator that degrades in orbit). B_scale empty: 1 for every joint."""
    B0: List[float] = field(default_factory=lambda: [1.0, 1.0])     # diagonal
    D0: List[float] = field(default_factory=lambda: [0.1, 0.1])     # diagonal
    D_offset: List[float] = field(default_factory=lambda: [0.02, 0.05])
    D_linear: List[float] = field(default_factory=lambda: [0.4, 0.4])
    D_quadratic: List[float] = field(default_factory=lambda: [-0.05, 0.1])
    B_linear: list[list[float]] = field(
        default_factory=lambda: [[-0.1, 0.0], [0.05, 0.15]])
    B_quadratic: List[float] = field(default_factory=lambda: [0.15, -0.25])
    B_q1_squared: list[list[float]] = field(
        default_factory=lambda: [[0.0, -0.1], [0.4, 0.0]])
    linear_scale: float = 1.0
    nonlinear_scale: float = 1.0
    B_scale: List[float] = field(default_factory=list)     # per joint; []: all 1
    faults: List[ActuatorFault] = field(default_factory=list)


@dataclass
class Disturbance:
    """d(t) = d_LF + d_HF from ``start`` (default: start of phase 3), times ``scale``:
    d_LF = lf_offset + lf_amplitude * [sin(2 pi f_1 t), cos(2 pi f_2 t), ...]
    d_HF = hf_amplitude sin(2 pi hf_frequency t) hf_direction      [N m]"""
    start: float = -1.0             # [s]; negative: start of phase 3
    scale: float = 1.0
    lf_offset: List[float] = field(default_factory=lambda: [0.03, -0.02])
    lf_amplitude: List[float] = field(default_factory=lambda: [0.02, 0.02])
    lf_frequency: List[float] = field(default_factory=lambda: [0.05, 0.07])   # [Hz]
    hf_amplitude: float = 0.005
    hf_frequency: float = 20.0      # [Hz]
    hf_direction: List[float] = field(default_factory=lambda: [1.0, -1.0])


TRUST_ANCHORS = ("in_use", "prior")            # Rhs.trust_anchor
GAIN_RULES = ("paper", "well_damped")           # Rhs.gain_rule
LEARNER_MODES = ("regularized", "plain")
LEARNER_COUPLINGS = ("uniform", "inertia")     # network.coupling_factors
LEARNER_PRIOR_SCALES = ("pooled", "per_input")  # identification.RhsIdentifier


@dataclass
class Learner:
    """Physics-informed network (docs/equations.md E34-E35), trained online with Adam.

    ``mode`` "plain" is the paper's learner: the raw port samples (x, u, qdot,
    tau_obs) of the last ``window`` sampling instants, the loss
    mean ||tau_obs - (B_hat u - D_hat qdot)||^2, no prior.

    ``mode`` "regularized" (default) identifies only what the closed-loop data
    inform (README, "Identifiability in closed loop"):
    - band: u, qdot, tau_obs pass the same band-pass filter before the regression
      (band_sections[0] first-order high-pass sections at band[0] Hz, then
      band_sections[1] low-pass sections at band[1] Hz). The relation
      tau = B u - D qdot + d holds for the filtered signals while B, D vary slowly;
      the high-pass removes the slow disturbance d_LF (and the slow reference
      motion, which shares its band), the low-pass d_HF. Excitation (section
      ``excitation``) supplies the content inside the band.
    - forgetting: sample k has the weight exp(-(t - t_k) / forgetting).
    - prior_weight rho: the loss adds
      rho (E_u sum w ||B_hat - B0||_F^2 + E_q sum w ||D_hat - D0||^2), E_u and E_q
      the weighted mean squares of the filtered u and qdot entries: a direction of
      (B, D) whose information is below rho times the average stays at the prior.
      With ``prior_scale`` "per_input" (default "pooled": as written), entry B_ij
      is weighted by max(E_i, E_j), E_j the mean square of input u_j, instead of
      E_u: a light joint's own gain B_jj is weighed against its own small input
      rather than held by the heavy joints' (spatial robots' scenarios).
    - change_ratio, change_floor, change_hold: when the relative residual of the
      newest samples jumps above change_ratio times its recent median and above
      change_floor (an abrupt change of B, D or d), training pauses for change_hold
      seconds and forgets the samples before the pause ends (the band-pass filter's
      memory holds a mix of old and new data until then).
    - start_hold: the start is such a change (the band-pass filter starts from rest
      while the port's signals do not, and the arm sets off from rest): training
      waits start_hold seconds and its window begins then. Fitted through, the
      first 0.75 s let the network settle on a state-dependent B_hat that explains
      them as well as the truth does (with actuators at x0.4 of B0, 0.67 against
      0.4 on the 2 s window, 0.40 from 1 s on). 0: train from the start.
    - min_window: training starts only once the window (after the start or a
      change) holds min_window seconds of samples: two periods of the slower
      excitation frequency determine B and D, while a network fitted to the few
      samples right after a hold swings far off (B_hat's eigenvalues from 1 to
      0.1 and below zero within 0.3 s). 0: fit from the second sample.
    - model_change: the observer forms tau_obs with the LHS's model, which the
      inertial identifier (section ``inertia``) refines while the robot moves; a
      new model (inertia.change_threshold) is a change too: samples observed
      through different models are not one relation (the identifier's first estimate, 1.4 % off the
      satellite_3dof arm's truth at 0.2 s, left 6 % of the heavy joints' in-band
      port torque unexplained 1.7 s later, and D_hat ended phase 1 at twice the
      prior's error). False: off.
    - warm_start: the run's first fit sets B_hat to the window's best constant B
      (RhsIdentifier.ConstantFit: ridge least squares with the same prior, D_hat as
      it is) before its Adam steps. From B0, Adam's first steps move every entry of
      B_hat by about the same amount whatever its gradient (they are normalized per
      parameter): with u1 and u2 correlated, a B0 off by x2.5 went to couplings of
      -0.24 and an eigenvalue near 0 within 0.2 s and took 2.5 s to recover. Only
      the first: after a later change Adam starts from the learned state
      dependence. False: Adam starts from B0.
    - step_guard G: a learner update whose Adam steps leave the window's loss
      above G times its value before them is undone (the network's parameters;
      Adam's moments keep the new gradients). After a long stretch of tiny
      gradients Adam's second moment has decayed, and a gradient that appears
      makes its normalized step about 3 learning rates on every parameter at once:
      on the paper scenario such a step took the window's loss from 6e-16 to 8e-12
      (above the prior's) and B_hat from 0.4 % to 13 % off the truth in the middle
      of phase 2, the change detector then paused training for 1.5 s. 0: off.

    ``coupling`` (either mode): how the network's n x n output enters B_hat
    (network.coupling_factors): "uniform" (the paper) or "inertia", where the
    coupling from a heavy joint j into a light joint i is scaled by
    min(1, m_i / m_j), m = diag M(q0). For arms whose joint inertias lie decades
    apart (the spatial robots' shipped scenarios use it; README, "Spatial robots")."""
    mode: str = "regularized"
    hidden: List[int] = field(default_factory=lambda: [16, 8])
    learning_rate: float = 1e-2
    window: int = 400               # training samples kept (at periods.learner_sample)
    steps_per_update: int = 5       # Adam steps per learner period
    momentum_scale: float = 0.01    # p is divided by this in the features [kg m^2/s]
    beta1: float = 0.9
    beta2: float = 0.999
    eps: float = 1e-8
    band: List[float] = field(default_factory=lambda: [2.0, 6.0])     # [Hz]
    band_sections: List[int] = field(default_factory=lambda: [4, 8])  # high, low
    forgetting: float = 1.0         # [s]
    prior_weight: float = 1e-3
    change_ratio: float = 5.0
    change_floor: float = 0.05
    change_hold: float = 1.5        # [s]
    start_hold: float = 1.0         # [s]; 0: train from t = 0 (earlier releases)
    min_window: float = 0.5         # [s]; 0: fit from the second sample (earlier releases)
    warm_start: bool = True         # False: Adam continues from the old estimate
    model_change: bool = True       # False: the LHS model's changes are not changes
    step_guard: float = 10.0        # 0: every update's steps are kept
    coupling: str = "uniform"
    prior_scale: str = "pooled"


@dataclass
class Excitation:
    """A persistently exciting port request for the learner (DAC only): the LHS
    adds tau_pe(t) = amplitude sin(2 pi f_j t) to channel j of tau_c^r, with f_j
    spread geometrically over ``frequencies`` = [f_first, f_last] [Hz]
    (f_j = f_first (f_last / f_first)^(j / (n - 1))). amplitude = 0 switches it off.

    Why: under the slow reference the data inform B only weakly, and from phase 3
    on the low-frequency disturbance shares the reference's band; a small request
    inside the learner's band, away from both, makes B and D identifiable
    (README, "Identifiability in closed loop")."""
    amplitude: float = 2e-4         # [N m]
    frequencies: List[float] = field(default_factory=lambda: [3.1, 4.3])   # [Hz]

    def Frequencies(self, n: int) -> np.ndarray:
        """f_j for joints j = 0 .. n-1 [Hz]."""
        first, last = self.frequencies
        return first * (last / first) ** (np.arange(n) / max(n - 1, 1))


@dataclass
class Stress:
    """A deliberately wrong learner, for verification (``dacph verify``): from time
    ``start`` on, the RHS integrator uses B_hat_scale * B_hat in place of the
    learner's B_hat (1 = the learner's estimate, no stress)."""
    B_hat_scale: float = 1.0
    start: float = 0.0              # [s]


@dataclass(eq=False)
class Scenario:
    robot: RobotParams = field(default_factory=RobotParams)
    nominal_robot: RobotParams = field(default_factory=RobotParams)
    q0: List[float] = field(default_factory=lambda: [0.3, 1.0])   # initial joints [rad]
    phases: Phases = field(default_factory=Phases)
    lhs: LhsGains = field(default_factory=LhsGains)
    potential: Potential = field(default_factory=Potential)
    inertia: InertiaIdentification = field(default_factory=InertiaIdentification)
    reference: Reference = field(default_factory=Reference)
    rhs: Rhs = field(default_factory=Rhs)
    periods: Periods = field(default_factory=Periods)
    uncertainty: Uncertainty = field(default_factory=Uncertainty)
    disturbance: Disturbance = field(default_factory=Disturbance)
    learner: Learner = field(default_factory=Learner)
    excitation: Excitation = field(default_factory=Excitation)
    stress: Stress = field(default_factory=Stress)
    # Drake's simulator settings for the ground truth's continuous state. The step
    # taken is min(max_step_size, periods.rhs): the RHS samples end every step.
    simulator: SimulatorConfig = field(default_factory=FixedStepConfig)
    seed: int = 0

    def __eq__(self, other) -> bool:
        """Equal settings: the same YAML form (pydrake's SimulatorConfig compares by
        identity)."""
        return (isinstance(other, Scenario)
                and yaml_dump_typed(self) == yaml_dump_typed(other))

    @property
    def duration(self) -> float:
        return self.phases.end

    @property
    def disturbance_start(self) -> float:
        return (self.disturbance.start if self.disturbance.start >= 0
                else self.phases.disturbance_start)

    def Validate(self) -> None:
        """Raises ConfigError naming the first invalid setting and its allowed range
        (the RHS period is checked against the gain rule when a diagram is built:
        gain_rule.check_rhs_period)."""
        validate_seed(self.seed)
        self.robot.Validate("robot")
        self.nominal_robot.Validate("nominal_robot")
        n = self.robot.num_links
        if self.nominal_robot.num_links != n:
            raise ConfigError(f"nominal_robot has {self.nominal_robot.num_links} links; "
                              f"allowed: the same as robot ({n})")
        _require_length("q0", self.q0, n)
        validate_phases(self.phases)
        require_positive("phases (total)", self.phases.end, "s")
        for name in ("Kd", "Lambda", "epsilon", "eta"):
            require_positive(f"lhs.{name}", getattr(self.lhs, name))
        require_nonnegative("lhs.chi_model_based", self.lhs.chi_model_based, "N m")
        require_in_range("lhs.min_task_singular_value", self.lhs.min_task_singular_value,
                         0.0, 10.0)
        require_nonnegative("lhs.boundary_rate", self.lhs.boundary_rate, "1/s")
        require_in_range("inertia.prior_weight", self.inertia.prior_weight, 1e-14, 1.0)
        require_nonnegative("inertia.start", self.inertia.start, "s")
        require_positive("inertia.duration", self.inertia.duration, "s")
        require_in_range("inertia.change_threshold", self.inertia.change_threshold,
                         0.0, 1.0)
        for name in ("base_gain", "base_margin", "fold_gain"):
            require_positive(f"potential.{name}", getattr(self.potential, name))
        require_in_range("potential.fold_margin", self.potential.fold_margin, 1e-3,
                         np.pi, "rad")
        require_in_range("potential.points_per_link", self.potential.points_per_link,
                         1, 100)
        if len(self.reference.amplitudes) != len(self.reference.periods):
            raise ConfigError("reference.amplitudes and reference.periods must have the "
                              "same length")
        for i, T in enumerate(self.reference.periods):
            require_positive(f"reference.periods[{i}]", T, "s")
        validate_port_settings(self, n)
        validate_simulator_config(self.simulator)
        # Last, so that a setting with a range names it: every other number finite.
        require_finite_numbers("", self)


def validate_seed(seed) -> None:
    """ConfigError unless ``seed`` is an integer in [0, 2^32 - 1]."""
    if isinstance(seed, bool) or not isinstance(seed, int):
        raise ConfigError(f"seed = {seed!r} is not an integer; allowed: an integer in "
                          "[0, 2^32 - 1]")
    require_in_range("seed", seed, 0, 2**32 - 1)


def validate_phases(phases: Phases) -> None:
    """ConfigError unless every phase duration is >= 0."""
    for name in ("warmup", "linear", "nonlinear", "disturbance"):
        require_nonnegative(f"phases.{name}", getattr(phases, name), "s")


def validate_port_settings(scenario, n: int,
                           period_name=lambda key: f"periods.{key}") -> None:
    """ConfigError naming the first invalid setting of the port's RHS chain (rhs,
    stress, periods, uncertainty, disturbance, learner, excitation) of a scenario
    with ``n`` joints; planar and spatial scenarios share these sections.
    ``period_name(key)`` is how the scenario names its period ``key``."""
    from dacph_drake.gain_rule import check_period_order
    require_positive("rhs.Td", scenario.rhs.Td)
    require_nonnegative("rhs.c_margin", scenario.rhs.c_margin)
    for name in ("c_time_constant", "chi_window", "chi_floor", "chi_initial"):
        require_positive(f"rhs.{name}", getattr(scenario.rhs, name))
    require_nonnegative("rhs.observer_noise", scenario.rhs.observer_noise, "N m")
    require_in_range("rhs.trust_ratio", scenario.rhs.trust_ratio, 1.0, 10.0)
    require_one_of("rhs.trust_anchor", scenario.rhs.trust_anchor, TRUST_ANCHORS)
    require_one_of("rhs.gain_rule", scenario.rhs.gain_rule, GAIN_RULES)
    require_in_range("rhs.evidence_ratio", scenario.rhs.evidence_ratio, 0.0, 1.0)
    require_positive("rhs.evidence_window", scenario.rhs.evidence_window, "s")
    require_in_range("rhs.beta_max", scenario.rhs.beta_max, 1.0, 1e6)
    require_positive("stress.B_hat_scale", scenario.stress.B_hat_scale)
    require_nonnegative("stress.start", scenario.stress.start, "s")
    periods = scenario.periods
    for key in ("rhs", "lhs", "learner", "learner_sample", "log"):
        require_positive(period_name(key), getattr(periods, key), "s")
    check_period_order(periods, period_name)
    if periods.log > scenario.duration:
        raise ConfigError(f"{period_name('log')} = {periods.log:g} s is longer than "
                          f"the run ({scenario.duration:g} s); allowed: at most the "
                          "run's duration")
    u = scenario.uncertainty
    for name in ("B0", "D0", "D_offset", "D_linear", "D_quadratic", "B_quadratic"):
        _require_length(f"uncertainty.{name}", getattr(u, name), n)
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
        _require_length(f"disturbance.{name}", getattr(d, name), n)
    require_nonnegative("disturbance.scale", d.scale)
    require_nonnegative("disturbance.hf_frequency", d.hf_frequency, "Hz")
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
    _require_length("learner.band", L.band, 2, "[low, high] in Hz")
    require_in_range("learner.band[0]", L.band[0], 0.0, nyquist,
                     "Hz (0: no high-pass; at most the Nyquist frequency of "
                     f"{period_name('learner_sample')})")
    require_in_range("learner.band[1]", L.band[1], L.band[0], nyquist,
                     "Hz (above band[0], at most the Nyquist frequency of "
                     f"{period_name('learner_sample')})")
    _require_length("learner.band_sections", L.band_sections, 2,
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
                     f"s (at most learner.window * {period_name('learner_sample')})")
    E = scenario.excitation
    require_nonnegative("excitation.amplitude", E.amplitude, "N m")
    _require_length("excitation.frequencies", E.frequencies, 2,
                    "[first, last] in Hz")
    require_in_range("excitation.frequencies[0]", E.frequencies[0], 1e-3,
                     0.5 / periods.lhs, "Hz (at most the Nyquist frequency "
                     f"of {period_name('lhs')})")
    require_in_range("excitation.frequencies[1]", E.frequencies[1],
                     E.frequencies[0], 0.5 / periods.lhs,
                     "Hz (at least frequencies[0], at most the Nyquist frequency "
                     f"of {period_name('lhs')})")
    if E.amplitude > 0 and L.mode == "regularized" and not (
            L.band[0] < E.frequencies[0] and E.frequencies[1] < L.band[1]):
        raise ConfigError(
            f"excitation.frequencies = {E.frequencies} Hz lie outside learner.band "
            f"= {L.band} Hz; allowed: inside the band (the learner filters "
            "everything else out)")


def _require_length(name: str, values, n: int, meaning: str = "one per joint"
                    ) -> None:
    if len(values) != n:
        raise ConfigError(f"{name} has {len(values)} entries; allowed: {n} "
                          f"({meaning})")


def load_scenario(path) -> Scenario:
    """Loads and validates a scenario: a YAML file (unknown keys and wrong types are
    errors that name the file and the key; a file without a robot: or nominal_robot:
    section gets the paper's arm and a logged warning saying so) or a built-in name (BUILT_IN_SCENARIOS:
    "paper", "short") where no file of that name exists."""
    if str(path) in BUILT_IN_SCENARIOS and not Path(path).is_file():
        return BUILT_IN_SCENARIOS[str(path)]()
    if not Path(path).is_file():
        raise ConfigError(f"scenario {str(path)!r}: no such file; allowed: a scenario "
                          f"YAML file or a built-in name ({', '.join(BUILT_IN_SCENARIOS)})")
    scenario = load_yaml_dataclass(path, Scenario,
                                   noted_defaults=("robot", "nominal_robot"),
                                   migrate=_move_integration_scheme)
    scenario.Validate()
    return scenario


def _move_integration_scheme(raw, path):
    """Files saved before the scenario embedded Drake's SimulatorConfig have a
    top-level ``integration_scheme: X``: it is read as ``simulator:
    {integration_scheme: X, max_step_size: periods.rhs}`` (with a logged note), the
    settings it implied; the rest are the simulator's defaults (FixedStepConfig)."""
    if not (isinstance(raw, dict) and "integration_scheme" in raw):
        return None
    if "simulator" in raw:
        raise ConfigError(f"{path}: both integration_scheme: and simulator: are set; "
                          "allowed: simulator: {integration_scheme: ...} only")
    migrated = dict(raw)
    migrated["simulator"] = {"integration_scheme": migrated.pop("integration_scheme")}
    periods = raw.get("periods")
    if isinstance(periods, dict) and "rhs" in periods:     # the step it implied
        migrated["simulator"]["max_step_size"] = periods["rhs"]
    logging.getLogger(__name__).warning(
        "%s: integration_scheme: is read as simulator: {integration_scheme: %s} (the "
        "scenario now embeds Drake's SimulatorConfig; save it again to update the file)", path,
        migrated["simulator"]["integration_scheme"])
    return migrated


def paper_scenario() -> Scenario:
    """The paper's scenario (1500 s): the defaults;
    diagrams/paper.yaml is its file."""
    return Scenario()


def short_scenario() -> Scenario:
    """The paper's phases compressed to 2 + 8 + 8 + 8 s (tests and a quick look);
    diagrams/short.yaml is its file."""
    return Scenario(phases=Phases(warmup=2.0, linear=8.0, nonlinear=8.0, disturbance=8.0))


BUILT_IN_SCENARIOS = {"paper": paper_scenario, "short": short_scenario}


# The YAML lines of settings added after runs were first saved, at their defaults.
ADDED_SETTING_DEFAULTS = ("  coupling: uniform", "  prior_scale: pooled",
                          "  B_scale: []", "  faults: []", "  trust_anchor: in_use",
                          "  start_hold: 1.0", "  gain_rule: paper",
                          "  evidence_ratio: 0.5", "  evidence_window: 1.0",
                          "  min_window: 0.5", "  warm_start: true",
                          "  model_change: true", "  step_guard: 10.0",
                          "  boundary_rate: 0.0")
# The sections added since, at their defaults.
ADDED_SECTION_DEFAULTS = (
    "inertia:\n  identify: true\n  prior_weight: 1.0e-12\n  start: 0.2\n"
    "  duration: 10.0\n  change_threshold: 0.05\n",)


def saved_forms(scenario: Scenario) -> List[str]:
    """The YAML texts a saved run of ``scenario`` may have been fingerprinted from:
    its current form and, where its simulator settings are those an older file's
    top-level ``integration_scheme: X`` implied (_move_integration_scheme), that
    older form. The lines of settings added since (ADDED_SETTING_DEFAULTS) and the
    sections added since (ADDED_SECTION_DEFAULTS) are left out of these texts where
    they hold their defaults, so that runs saved before they existed still match."""
    text = yaml_dump_typed(scenario)
    for line in ADDED_SETTING_DEFAULTS:
        text = re.sub(f"^{re.escape(line)}\n", "", text, flags=re.MULTILINE)
    for section in ADDED_SECTION_DEFAULTS:
        text = re.sub(f"^{re.escape(section)}", "", text, flags=re.MULTILINE)
    config = scenario.simulator
    if yaml_dump_typed(config) != yaml_dump_typed(FixedStepConfig(
            config.integration_scheme, scenario.periods.rhs)):
        return [text]
    older = re.sub(r"^simulator:\n(?:  .*\n)*",
                   f"integration_scheme: {config.integration_scheme}\n", text,
                   flags=re.MULTILINE)
    return [text, older]


def save_scenario(scenario: Scenario, path) -> None:
    with open(path, "w") as f:
        f.write(yaml_dump_typed(scenario))
