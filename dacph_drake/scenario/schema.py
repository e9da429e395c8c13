"""Scenario: every setting of a closed-loop run as typed data (pydrake.common.yaml).
Defaults: the paper's 1500 s scenario; why: the docs' page "Settings explained"."""
from dataclasses import dataclass, field
from typing import Dict, List, Tuple, Union

import numpy as np
from pydrake.common.yaml import yaml_dump_typed
from pydrake.systems.analysis import SimulatorConfig

from dacph_drake.scenario.planar_arm import RobotParams
from dacph_drake.scenario.simulator import FixedStepConfig

TRUST_ANCHORS = ("in_use", "prior")                       # Rhs.trust_anchor
INERTIA_ANCHORS = ("total_mass", "base_mass", "model")    # InertiaIdentification.anchor
ON_MISMATCH = ("identified", "nominal")                   # InertiaIdentification
GAIN_RULES = ("paper", "well_damped")                     # Rhs.gain_rule
ADOPTIONS = ("certified_set", "trust_band")               # Rhs.adoption
LEARNER_MODES = ("regularized", "plain")                  # Learner.mode
LEARNER_COUPLINGS = ("uniform", "inertia")                # Learner.coupling
LEARNER_PRIOR_SCALES = ("pooled", "per_input")            # Learner.prior_scale
JOINT_DAMPING = ("keep", "zero")                          # DescribedArm.joint_damping
JOINT_FRICTION = ("keep", "zero")                         # DescribedArm.joint_friction
JOINT_LIMITS = ("stop", "ignore")                         # DescribedArm.joint_limits
EFFORT_LIMITS = ("saturate", "ignore")                    # DescribedArm.effort_limits
RATE_SOURCES = ("tachometer", "differentiated")           # Sensing.rate_source


@dataclass
class Phases:
    """The run's phases, one after the other.

    Attributes:
        warmup: On (B0, D0) [s], >= 0.
        linear: Phase 1, linear uncertainty [s], >= 0.
        nonlinear: Phase 2, plus nonlinear uncertainty [s], >= 0.
        disturbance: Phase 3, plus d(t) [s], >= 0; the sum > 0 and >= periods.log."""
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
    """The planar sliding-mode LHS gains (E23-E25).

    Attributes:
        Kd: K_d = Kd I [N m s], > 0.
        Lambda: The task error's gain in nu [1/s], > 0.
        epsilon: The boundary layer of chi tanh(s / epsilon) [rad/s], > 0.
        eta: The null-space gain of xi = -eta grad U, > 0.
        chi_model_based: The baseline's fixed chi [N m], >= 0.
        min_task_singular_value: The smallest ||D(q0)|| a run starts at, in [0, 10].
        boundary_rate: phi = epsilon + chi / (boundary_rate inf lambda_min(M)) [1/s]."""
    Kd: float = 0.5
    Lambda: float = 1.0
    epsilon: float = 0.2
    eta: float = 0.1
    chi_model_based: float = 0.05
    min_task_singular_value: float = 0.05
    boundary_rate: float = 0.0


@dataclass
class InertiaIdentification:
    """Inertial parameters identified from momentum conservation (inertial_identifier).

    Attributes:
        identify: Identify them (False: the controller keeps the nominal model).
        prior_weight: Information share below which a direction stays, [1e-14, 1].
        start: When the identified parameters replace the nominal ones [s], >= 0.
        duration: How long they are refined before the estimate is kept [s], > 0.
        change_threshold: Relative change of M(q) restarting the learner, [0, 1].
        anchor: What fixes the common scale, one of INERTIA_ANCHORS.
        anchor_mass: The anchor's measured mass [kg], >= 0 (0: the robot's own).
        anchor_error: The measurement's relative error, in [-0.5, 0.5].
        fit_tolerance: Momentum misfit reporting the kinematics mismatched, >= 0 (0: off).
        on_mismatch: What the LHS uses after a mismatch, one of ON_MISMATCH.
        nominal_tolerance: Relative sd of robot.nominal's inertial parameters, in [0, 1).
        anchor_tolerance: The anchor's mass known to this relative sd, in [0, 0.5].
        kinematic_tolerance: Relative sd of each joint placement's components, [0, 0.5].
        error_draws: The plausible models per trial that measure E, in [2, 256]."""
    identify: bool = True
    prior_weight: float = 1e-12
    start: float = 0.2
    duration: float = 10.0
    change_threshold: float = 5e-2
    anchor: str = "total_mass"
    anchor_mass: float = 0.0
    anchor_error: float = 0.0
    fit_tolerance: float = 1e-6
    on_mismatch: str = "identified"
    nominal_tolerance: float = 0.1
    anchor_tolerance: float = 0.01
    kinematic_tolerance: float = 0.0
    error_draws: int = 16


@dataclass
class Potential:
    """The planar arm's null-space potential, U = k / 2 (1 / rho - 1 / rho0)^2 for
    rho < rho0 (Khatib's FIRAS): links against the base and joints against folding.

    Attributes:
        base_gain: k of the link-base clearance [J m^2], > 0.
        base_margin: rho0 of the link-base clearance [m], > 0.
        fold_gain: k of folding [J rad^2], > 0.
        fold_margin: rho0 of folding [rad], in [1e-3, pi].
        points_per_link: Sample points along each link, in [1, 100]."""
    base_gain: float = 1e-3
    base_margin: float = 0.06
    fold_gain: float = 1e-3
    fold_margin: float = 0.6
    points_per_link: int = 4


@dataclass
class Reference:
    """alpha_d(t) = alpha(0) + sum_i a_i sin(2 pi t / T_i) [rad].

    Attributes:
        amplitudes: a_i [rad], as many as periods.
        periods: T_i [s], each > 0."""
    amplitudes: List[float] = field(default_factory=lambda: [0.3, 0.1])
    periods: List[float] = field(default_factory=lambda: [30.0, 11.0])


@dataclass
class AttitudeReference:
    """R_d(t) = R_d(0) Rot(axis, amplitude sin(2 pi t / period)), R_d(0) the attitude
    at q0 turned by initial_error about initial_error_axis (world).

    Attributes:
        axis: The body-fixed axis, a non-zero 3-vector.
        amplitude: [rad], >= 0.
        period: [s], > 0.
        initial_error: [rad], in [0, pi].
        initial_error_axis: A non-zero 3-vector (world)."""
    axis: List[float] = field(default_factory=lambda: [0.0, 0.6, 0.8])
    amplitude: float = 0.4
    period: float = 8.0
    initial_error: float = 0.3
    initial_error_axis: List[float] = field(default_factory=lambda: [0.6, 0.0, 0.8])


@dataclass
class AttitudeGains:
    """The spatial LHS gains: K_d = damping_rate M(q), phi = epsilon + chi / boundary_rate.

    Attributes:
        Lambda: The task error's gain in nu [1/s], > 0.
        damping_rate: [1/s], > 0, damping_rate * periods.lhs <= 0.5.
        task_damping: mu of the damped pseudo-inverse [-], >= 0.
        epsilon: The layer at chi = 0 [N m s], > 0.
        boundary_rate: [1/s], > 0, (damping_rate + boundary_rate) periods.lhs <= 0.5.
        chi_model_based: The baseline's fixed chi [N m], >= 0."""
    Lambda: float = 2.0
    damping_rate: float = 20.0
    task_damping: float = 1e-3
    epsilon: float = 1e-3
    boundary_rate: float = 20.0
    chi_model_based: float = 0.0


@dataclass
class Rhs:
    """The RHS integrator (E48): k_p = c / Re(lambda_hat_p), c -> (1 + c_margin) c_min;
    chi the forgetting peak of ||e_tau||; the adoption of learned estimates.

    Attributes:
        Td: T_d of eq. (48), > 0.
        c_margin: >= 0.
        c_time_constant: c's filter [s], > 0.
        chi_window: chi's forgetting [s], > 0.
        chi_floor: [N m], > 0.
        chi_initial: [N m], > 0.
        observer_noise: tau_obs noise's sd [N m], >= 0.
        trust_ratio: The trust band's factor on eigenvalues, in [1, 10].
        trust_anchor: One of TRUST_ANCHORS.
        evidence_ratio: Residual ratio that adopts outside the band, in [0, 1].
        evidence_window: [s], > 0.
        beta_max: The largest beta_hat the gain rule uses, in [1, 1e6].
        gain_rule: One of GAIN_RULES.
        adoption: One of ADOPTIONS."""
    Td: float = 2.0
    c_margin: float = 0.1
    c_time_constant: float = 1.0
    chi_window: float = 2.0
    chi_floor: float = 1e-3
    chi_initial: float = 0.05
    observer_noise: float = 0.0
    trust_ratio: float = 2.0
    trust_anchor: str = "in_use"
    evidence_ratio: float = 0.5
    evidence_window: float = 1.0
    beta_max: float = 2.0
    gain_rule: str = "paper"
    adoption: str = "certified_set"


@dataclass
class Periods:
    """Update periods [s], rhs < lhs <= learner_sample <= learner (time-scale separation).

    Attributes:
        rhs: The integrator and the observer [s].
        lhs: The LHS controller [s].
        learner: A training step [s].
        learner_sample: Data sampling and the RHS model's refresh [s].
        log: The loggers [s], at most the run."""
    rhs: float = 2.5e-4
    lhs: float = 1e-3
    learner: float = 0.1
    learner_sample: float = 0.01
    log: float = 0.01


@dataclass
class ActuatorFault:
    """From ``time`` on, joint ``joint``'s actuator delivers ``gain`` times its torque.

    Attributes:
        time: [s], >= 0.
        joint: 1-based, in [1, n].
        gain: [-], in [1e-2, 1e2]."""
    time: float = 0.0
    joint: int = 1
    gain: float = 0.5


@dataclass
class Uncertainty:
    """The true RHS (E19): B~ = diag(g(t)) (B0 + Delta B), D~ = D0 + Delta D,

        Delta D = diag(D_offset + D_linear p) + diag(D_quadratic p^2)
        Delta B = diag(B_linear q) + diag(B_quadratic p^2) + B_q1_squared q1^2.

    Attributes:
        B0: diag B0 (n), each > 0.
        D0: diag D0 (n), each >= 0.
        D_offset: (n).
        D_linear: (n).
        D_quadratic: (n).
        B_linear: n x n [1/rad].
        B_quadratic: (n).
        B_q1_squared: n x n.
        linear_scale: The linear group's factor from phase 1 on, >= 0.
        nonlinear_scale: The quadratic group's factor from phase 2 on, >= 0.
        B_scale: g_j before faults, one per joint in [1e-2, 1e2], or none (all 1).
        faults: ActuatorFault entries (g_j times those on joint j)."""
    B0: List[float] = field(default_factory=lambda: [1.0, 1.0])
    D0: List[float] = field(default_factory=lambda: [0.1, 0.1])
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
    B_scale: List[float] = field(default_factory=list)
    faults: List[ActuatorFault] = field(default_factory=list)


@dataclass
class Disturbance:
    """d(t) = scale (d_LF + d_HF) from ``start``: d_LF = lf_offset + lf_amplitude
    [sin(2 pi f_1 t), cos(2 pi f_2 t), ...], d_HF = hf_amplitude sin(2 pi hf_frequency
    t) hf_direction [N m].

    Attributes:
        start: [s]; negative: phase 3's start.
        scale: >= 0.
        lf_offset: One per joint [N m].
        lf_amplitude: One per joint [N m].
        lf_frequency: One per joint [Hz].
        hf_amplitude: [N m].
        hf_frequency: [Hz], >= 0.
        hf_direction: One per joint."""
    start: float = -1.0
    scale: float = 1.0
    lf_offset: List[float] = field(default_factory=lambda: [0.03, -0.02])
    lf_amplitude: List[float] = field(default_factory=lambda: [0.02, 0.02])
    lf_frequency: List[float] = field(default_factory=lambda: [0.05, 0.07])
    hf_amplitude: float = 0.005
    hf_frequency: float = 20.0
    hf_direction: List[float] = field(default_factory=lambda: [1.0, -1.0])


@dataclass
class LocalBayes:
    """learning.local_bayes: local linear models of B_ij, D_i; Gaussian prior at (B0, D0).

    Attributes:
        gain_range: [low, high] of B~_ii / B0_i, 0 < low < 1 < high <= 100.
        coupling: The prior's bound on a row's cross-coupling, in [0, 1].
        damping_range: [low, high] of D~_i / D0_i, 0 <= low < 1 < high.
        drift: The prior's sd of an entry's rate [1/s], > 0.
        momentum_slope: The prior's sd of a slope in momentum, > 0.
        curvature: A bound on an entry's second time derivative [1/s^2], >= 0.
        floor: The systematic-error floor, >= 0.
        forgetting: [s], > 0.
        min_window: [s], > 0, at most learner.window * periods.learner_sample.
        min_dof: Residual degrees of freedom before a fit is published, >= 1.
        credible_level: The intervals' level, in (0, 1).
        certificate_level: The certified set's level, in [credible_level, 1).
        margin: Half-widths by which a learned entry must leave the prior, >= 0.
        change_floor: The relative residual that is a change, >= 0.
        inconsistency: The relative residual that restarts a window, > change_floor.
        model_error: Relative sd of the LHS inertia error E the claims add to the measured
            one in quadrature, [0, 1)."""
    gain_range: List[float] = field(default_factory=lambda: [0.5, 2.0])
    coupling: float = 0.05
    damping_range: List[float] = field(default_factory=lambda: [0.0, 3.0])
    drift: float = 0.05
    momentum_slope: float = 0.03
    curvature: float = 0.01
    floor: float = 1.0
    forgetting: float = 2.0
    min_window: float = 0.2
    min_dof: float = 3.0
    credible_level: float = 0.9
    certificate_level: float = 0.99
    margin: float = 2.0
    change_floor: float = 5e-3
    inconsistency: float = 0.1
    model_error: float = 0.0


@dataclass
class Learner:
    """The port's RHS learner: "local_bayes" (``bayes``) or the paper's network (E34).

    Attributes:
        mode: One of LEARNER_MODES ("plain": the paper's).
        hidden: The MLPs' widths, each in [1, 4096].
        learning_rate: Adam's, > 0.
        window: Samples kept, in [2, 10^6].
        steps_per_update: Adam steps per period, in [0, 10^4].
        momentum_scale: p's scale in the features [kg m^2/s], > 0.
        beta1: Adam's, in [0, 0.999999].
        beta2: Adam's, in [0, 0.999999].
        eps: Adam's, > 0.
        band: The band-pass [low, high] in Hz, within the sampling's Nyquist.
        band_sections: [high-pass, low-pass] sections, each in [0, 16].
        forgetting: [s], > 0.
        prior_weight: rho, >= 0.
        change_ratio: In [1, 10^6].
        change_floor: >= 0.
        change_hold: [s], >= 0.
        start_hold: [s], >= 0.
        min_window: [s], in [0, window * periods.learner_sample].
        warm_start: The first fit starts from the window's best constant B.
        model_change: A new LHS model counts as a change.
        step_guard: The loss growth that undoes a step: 0 or in [1, 10^12].
        prior_fallback: Publish (B0, D0) while it fits better.
        coupling: One of LEARNER_COUPLINGS.
        prior_scale: One of LEARNER_PRIOR_SCALES.
        model: A registered learner (learning.LEARNERS: local_bayes, network).
        bayes: LocalBayes."""
    mode: str = "regularized"
    hidden: List[int] = field(default_factory=lambda: [16, 8])
    learning_rate: float = 1e-2
    window: int = 400
    steps_per_update: int = 5
    momentum_scale: float = 0.01
    beta1: float = 0.9
    beta2: float = 0.999
    eps: float = 1e-8
    band: List[float] = field(default_factory=lambda: [2.0, 6.0])
    band_sections: List[int] = field(default_factory=lambda: [4, 8])
    forgetting: float = 1.0
    prior_weight: float = 1e-3
    change_ratio: float = 5.0
    change_floor: float = 0.05
    change_hold: float = 1.5
    start_hold: float = 1.0
    min_window: float = 0.5
    warm_start: bool = True
    model_change: bool = True
    step_guard: float = 10.0
    prior_fallback: bool = False
    coupling: str = "uniform"
    prior_scale: str = "pooled"
    model: str = "local_bayes"
    bayes: LocalBayes = field(default_factory=LocalBayes)


@dataclass
class Excitation:
    """The learner's excitation tau_pe,j(t) = amplitude joint_scale_j sin(2 pi f_j t)
    added to tau_c^r, f_j geometric over ``frequencies`` (DAC only).

    Attributes:
        amplitude: [N m], >= 0 (0: off).
        joint_scale: Per joint in [0, 1], or none (all 1).
        frequencies: [f_first, f_last] in Hz, inside learner.band."""
    amplitude: float = 2e-4
    frequencies: List[float] = field(default_factory=lambda: [3.1, 4.3])
    joint_scale: List[float] = field(default_factory=list)

    def Amplitudes(self, n: int) -> np.ndarray:
        """a_j [N m].

        Args:
            n: The number of joints."""
        scale = np.asarray(self.joint_scale, float) if self.joint_scale else np.ones(n)
        return self.amplitude * scale

    def Frequencies(self, n: int) -> np.ndarray:
        """f_j = f_first (f_last / f_first)^(j / (n - 1)) [Hz].

        Args:
            n: The number of joints."""
        first, last = self.frequencies
        return first * (last / first) ** (np.arange(n) / max(n - 1, 1))


@dataclass
class Stress:
    """From ``start`` on, the RHS uses B_hat_scale B_hat (``dacph verify``'s test).

    Attributes:
        B_hat_scale: > 0 (1: no stress).
        start: [s], >= 0."""
    B_hat_scale: float = 1.0
    start: float = 0.0


@dataclass
class Sensing:
    """What the controllers measure, and when (off: the ground truth's exact state at
    once; systems.sensors, controllers.closed_loop). Every sensor samples at periods.rhs
    with its noise held for the sample; the star tracker fixes the base attitude at its
    own rate and the gyro propagates it between fixes.

    Attributes:
        enabled: Measure through the sensors and delays below (false: exact, at once).
        encoder_counts: The joint encoders' counts per revolution (0: unquantized).
        encoder_noise: The encoders' noise sd [rad], >= 0.
        rate_source: "tachometer" (qdot + rate_noise) or "differentiated" (the encoder
            readings differenced each sample, low-passed at rate_cutoff).
        rate_noise: The tachometers' noise sd [rad/s], >= 0.
        rate_cutoff: The differentiated rate's first-order low-pass cutoff [Hz], > 0.
        gyro_noise: The base gyro's noise sd per sample and axis [rad/s], >= 0.
        gyro_bias: Its initial bias on every axis [rad/s].
        gyro_bias_walk: Its bias random walk [rad/s/sqrt(s)], >= 0.
        star_tracker_noise: The star tracker's attitude noise sd per axis [rad], >= 0.
        star_tracker_rate: Its fixes per second [Hz] (0: the attitude exact at every
            sample, no gyro propagation).
        latency: Samples (of periods.rhs) by which every measurement is late, >= 0.
        lhs_delay: Samples (of periods.lhs) by which the LHS's request is late, >= 0.
        rhs_delay: Samples (of periods.rhs) by which the command u is late, >= 0.
        actuator_lag: The actuators' first-order time constant [s] (0: none), >= 0.
        unmodelled_delay: Samples (of periods.rhs) by which u acts later still, which
            the controllers do not know of (a test of verify's delay margin), >= 0."""
    enabled: bool = False
    encoder_counts: int = 0
    encoder_noise: float = 0.0
    rate_source: str = "tachometer"
    rate_noise: float = 0.0
    rate_cutoff: float = 200.0
    gyro_noise: float = 0.0
    gyro_bias: float = 0.0
    gyro_bias_walk: float = 0.0
    star_tracker_noise: float = 0.0
    star_tracker_rate: float = 0.0
    latency: int = 0
    lhs_delay: int = 0
    rhs_delay: int = 0
    actuator_lag: float = 0.0
    unmodelled_delay: int = 0

    def KnownCommandDelay(self) -> Tuple[int, float]:
        """(the samples of periods.rhs by which the controllers know the RHS loop's
        command acts late, rhs_delay + latency; actuator_lag [s]); (0, 0.0) when not
        enabled."""
        if not self.enabled:
            return 0, 0.0
        return self.rhs_delay + self.latency, self.actuator_lag

    def TrueCommandDelay(self) -> Tuple[int, float]:
        """KnownCommandDelay with unmodelled_delay added: how late the command acts."""
        delay, lag = self.KnownCommandDelay()
        return delay + (self.unmodelled_delay if self.enabled else 0), lag


@dataclass
class PlanarArm:
    """robot: a planar n-link arm on a free base.

    Attributes:
        truth: The ground truth.
        nominal: The controller's model of it, as many links.
        potential: The null-space potential."""
    truth: RobotParams = field(default_factory=RobotParams)
    nominal: RobotParams = field(default_factory=RobotParams)
    potential: Potential = field(default_factory=Potential)


@dataclass
class ClearancePotential:
    """A described arm's potential U = gain / 2 sum_k max(0, margin - phi_k)^2 over
    the link-base signed distances phi_k, xi = -eta grad U.

    Attributes:
        gain: >= 0 (0: off).
        margin: [m], > 0.
        eta: [1/s], >= 0."""
    gain: float = 1.0
    margin: float = 0.1
    eta: float = 20.0


@dataclass
class ArmBase:
    """robot.base: a uniform box the description is welded to.

    Attributes:
        mass: [kg], >= 0 (0: no box, the description's root body is the free base).
        size: Sides x, y, z [m], each > 0.
        mount: The root in the box's centre frame: x, y, z [m], roll, pitch, yaw [rad]."""
    mass: float = 0.0
    size: List[float] = field(default_factory=lambda: [1.0, 1.0, 1.0])
    mount: List[float] = field(default_factory=lambda: [0.0, 0.0, 0.5, 0.0, 0.0, 0.0])


@dataclass
class EndEffectorFrame:
    """robot.end_effector: the tracked frame.

    Attributes:
        frame: The description's frame ("": the frame named end_effector).
        offset: Its offset x, y, z [m]."""
    frame: str = ""
    offset: List[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])


@dataclass
class DescribedArm:
    """robot: !DescribedArm, an arm from a URDF, SDF or MJCF file.

    Attributes:
        description: A shipped name or a path.
        base: ArmBase.
        end_effector: EndEffectorFrame.
        package_paths: Folders holding ROS packages.
        packages: Package name -> folder, for package:// URIs.
        joint_damping: One of JOINT_DAMPING ("keep": in the truth and the LHS model).
        joint_friction: One of JOINT_FRICTION ("keep": the description's Coulomb friction,
            URDF <dynamics friction> or MJCF frictionloss, in the truth only: an RHS part
            the learner meets; "zero": none, as in Drake's plant).
        locked_joints: Joints welded at a position (name: [rad] or [m]).
        joint_limits: One of JOINT_LIMITS ("stop": refused at q0, stopped in a run).
        effort_limits: One of EFFORT_LIMITS ("saturate": u clipped in the truth).
        nominal_inertia_scale: The model's factor per body with mass, in [0.1, 10].
        potential: ClearancePotential."""
    description: str = "satellite_6dof"
    base: ArmBase = field(default_factory=ArmBase)
    end_effector: EndEffectorFrame = field(default_factory=EndEffectorFrame)
    package_paths: List[str] = field(default_factory=list)
    packages: Dict[str, str] = field(default_factory=dict)
    joint_damping: str = "keep"
    joint_friction: str = "zero"
    locked_joints: Dict[str, float] = field(default_factory=dict)
    joint_limits: str = "stop"
    effort_limits: str = "saturate"
    nominal_inertia_scale: List[float] = field(default_factory=list)
    potential: ClearancePotential = field(default_factory=ClearancePotential)


@dataclass
class EndEffectorAngle:
    """task: the planar end effector's angle alpha = theta0 + sum q.

    Attributes:
        reference: Reference.
        gains: LhsGains."""
    reference: Reference = field(default_factory=Reference)
    gains: LhsGains = field(default_factory=LhsGains)


@dataclass
class EndEffectorAttitude:
    """task: !EndEffectorAttitude, the end effector's 3D attitude.

    Attributes:
        reference: AttitudeReference.
        gains: AttitudeGains."""
    reference: AttitudeReference = field(default_factory=AttitudeReference)
    gains: AttitudeGains = field(default_factory=AttitudeGains)


@dataclass
class PositionReference:
    """p_d(t) = p_E(q0) + initial_offset + axis amplitude sin(2 pi t / period), world.

    Attributes:
        axis: A non-zero 3-vector (world).
        amplitude: [m], >= 0.
        period: [s], > 0.
        initial_offset: p_d(0) - p_E(q0) [m] (3)."""
    axis: List[float] = field(default_factory=lambda: [0.0, 0.0, 1.0])
    amplitude: float = 0.03
    period: float = 8.0
    initial_offset: List[float] = field(default_factory=lambda: [0.02, 0.0, 0.0])


@dataclass
class EndEffectorPose:
    """task: !EndEffectorPose, the end effector's position and attitude.

    Attributes:
        reference: The attitude reference R_d(t).
        position: The position reference p_d(t).
        gains: The LHS gains (Lambda acts on both errors)."""
    reference: AttitudeReference = field(default_factory=AttitudeReference)
    position: PositionReference = field(default_factory=PositionReference)
    gains: AttitudeGains = field(default_factory=AttitudeGains)


@dataclass
class EndEffectorPosition:
    """task: !EndEffectorPosition, the end effector's position.

    Attributes:
        position: The position reference p_d(t).
        gains: The LHS gains (Lambda acts on e_p)."""
    position: PositionReference = field(default_factory=PositionReference)
    gains: AttitudeGains = field(default_factory=AttitudeGains)


@dataclass(eq=False)
class Scenario:
    """Every setting of a closed-loop run; the run lasts as long as the phases.

    Attributes:
        robot: A robot section (PlanarArm, the default, or !DescribedArm).
        task: A task section its robot serves (tasks.TASKS).
        q0: The initial joint angles [rad], one per joint.
        phases: Phases.
        inertia: InertiaIdentification.
        rhs: Rhs.
        periods: Periods.
        uncertainty: Uncertainty.
        disturbance: Disturbance.
        learner: Learner.
        excitation: Excitation.
        stress: Stress.
        sensing: Sensing (off by default).
        simulator: Drake's settings for the truth (step: min(max_step, periods.rhs)).
        seed: The learner's and the observer noise's, in [0, 2^32 - 1]."""
    robot: Union[PlanarArm, DescribedArm] = field(default_factory=PlanarArm)
    task: Union[EndEffectorAngle, EndEffectorAttitude, EndEffectorPose,
                EndEffectorPosition] = field(default_factory=EndEffectorAngle)
    q0: List[float] = field(default_factory=lambda: [0.3, 1.0])
    phases: Phases = field(default_factory=Phases)
    inertia: InertiaIdentification = field(default_factory=InertiaIdentification)
    rhs: Rhs = field(default_factory=Rhs)
    periods: Periods = field(default_factory=Periods)
    uncertainty: Uncertainty = field(default_factory=Uncertainty)
    disturbance: Disturbance = field(default_factory=Disturbance)
    learner: Learner = field(default_factory=Learner)
    excitation: Excitation = field(default_factory=Excitation)
    stress: Stress = field(default_factory=Stress)
    sensing: Sensing = field(default_factory=Sensing)
    simulator: SimulatorConfig = field(default_factory=FixedStepConfig)
    seed: int = 0

    def __eq__(self, other) -> bool:
        """Equal YAML forms (SimulatorConfig compares by identity)."""
        return (isinstance(other, Scenario)
                and yaml_dump_typed(self) == yaml_dump_typed(other))

    @property
    def duration(self) -> float:
        return self.phases.end

    @property
    def disturbance_start(self) -> float:
        return (self.disturbance.start if self.disturbance.start >= 0
                else self.phases.disturbance_start)


def add_section_type(name: str, section: type) -> None:
    """Lets setting ``name:`` take ``!Section``, a kind registered from outside the package.

    Args:
        name: The setting (robot, task or learner).
        section: The section's dataclass."""
    field_ = Scenario.__dataclass_fields__[name]
    kinds = getattr(field_.type, "__args__", (field_.type,))
    if section not in kinds:
        field_.type = Union[kinds + (section,)]
