"""Scenario: every setting of a closed-loop run (the defaults are the paper's
scenario, 1500 s, with the SPEC settings listed in docs/equations.md), its sections,
their validation and the built-in scenarios; scenario_files reads and writes them
(YAML with ``pydrake.common.yaml.yaml_load_typed``)."""
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
from pydrake.common.eigen_geometry import AngleAxis
from pydrake.common.yaml import yaml_dump_typed
from pydrake.math import RotationMatrix
from pydrake.systems.analysis import SimulatorConfig

from dacph_drake.errors import (ConfigError, require_finite_numbers, require_in_range,
                                require_nonnegative, require_one_of, require_positive)
from dacph_drake.arm_parameters import RobotParams
from dacph_drake.loop.simulator import FixedStepConfig, validate_simulator_config


@dataclass
class Phases:
    """The run's phases, whose durations add up to its length.

    Durations [s]: warm-up (B0, D0 only), then (1) linear uncertainty, (2) plus
    nonlinear uncertainty, (3) plus the external disturbance d(t).

    Attributes:
        warmup: The warm-up on the nominal RHS (B0, D0 only) [s], >= 0.
        linear: Phase 1, the linear uncertainty [s], >= 0.
        nonlinear: Phase 2, plus the nonlinear uncertainty [s], >= 0.
        disturbance: Phase 3, plus the external disturbance d(t) [s], >= 0. The
            four together must be > 0 and at least periods.log."""
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
    """The planar arm's sliding-mode LHS controller gains (task.gains).

    Sliding-mode LHS controller (docs/equations.md E23-E25): K_d = Kd I, Lambda,
    epsilon of chi tanh(s / epsilon), eta of xi = -eta grad U. A run must start
    where the task Jacobian's singular value ||D(q0)|| is at least
    min_task_singular_value (the paper's arm has 0.61 to 1.21 over all q).

    Attributes:
        Kd: The damping K_d = Kd I of the sliding variable s [N m s], > 0.
        Lambda: The task error's gain in nu = D^+ (alpha_d_dot - Lambda alpha~) + ...
            [1/s], > 0.
        epsilon: The boundary layer of chi tanh(s / epsilon) [rad/s], > 0.
        eta: The null-space gain of xi = -eta grad U, > 0.
        chi_model_based: The fixed chi of the model-based baseline [N m], >= 0
            (the DAC loops take chi from the RHS loop).
        min_task_singular_value: The smallest ||D(q0)|| a run may start at, in
            [0, 10].
        boundary_rate: The rate that sizes the boundary layer with chi [1/s],
            >= 0: chi tanh(s / phi), phi = epsilon + chi / (boundary_rate
            inf lambda_min(M)); 0: phi = epsilon (the paper's)."""
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
    """The DAC loops' identification of the inertial parameters (section inertia).

    The DAC loops' identification of the bodies' inertial parameters from momentum
    conservation (systems/inertial_identifier.py; docs/results/model-error.md): from
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

    ``anchor`` fixes that common scale: "total_mass" (default) or "base_mass" at a
    measured mass of the whole spacecraft or of its base (``anchor_mass`` [kg]; 0:
    the simulated robot's own, measured with the relative error ``anchor_error``),
    which momentum data cannot give and a spacecraft's mass properties do; "model"
    at the controller's model's, as above (earlier releases: a model 15 % off in
    its masses and 5 % in a link's length identified half the robot). With the controller's
    kinematics off (a link a few percent longer than modelled), no parameters
    explain the momentum: the identifier measures the unexplained part
    (inertial_parameters.momentum_misfit) and past ``fit_tolerance`` reports a
    kinematic mismatch, after which the LHS keeps the identified parameters
    (``on_mismatch`` "identified") or returns to nominal_robot's ("nominal").

    prior_weight is small because the simulated rates carry no noise: on the 6-DOF
    arm the directions that fix M lie 1e-11 to 1e-8 below the best-informed one
    (at 1e-8 its identified M stayed 10 % off the truth's, up to the scale; at
    1e-12, 4e-4).

    Attributes:
        identify: Whether the DAC loops identify the parameters (False: the
            controller keeps nominal_robot).
        prior_weight: The share of the average information below which a direction
            stays at nominal_robot's, in [1e-14, 1].
        start: When the identified parameters replace the nominal ones [s], >= 0.
        duration: How long the identification refines them before the estimate is
            kept [s], > 0.
        change_threshold: The relative change of M(q) (an entry against
            sqrt(M_ii M_jj)) that restarts the learner's window, in [0, 1].
        anchor: What fixes the parameters' common scale, one of
            INERTIA_ANCHORS: "total_mass", "base_mass" or "model".
        anchor_mass: The measured mass of the anchor [kg], >= 0 (0: the
            simulated robot's own, times 1 + anchor_error).
        anchor_error: The relative error of the simulated measurement, in
            [-0.5, 0.5] (with anchor_mass 0).
        fit_tolerance: The momentum misfit past which the kinematics are reported
            mismatched, >= 0 (0: no test). In a noise-free simulation the
            paper's arm with its kinematics right leaves below 1e-7, a link 5 %
            longer than modelled 5e-6 to 4e-5, 1 % longer 1e-6 to 8e-6; a real
            robot's sensor noise sets its own floor.
        on_mismatch: What the LHS uses after a mismatch, one of ON_MISMATCH:
            "identified" or "nominal"."""
    identify: bool = True
    prior_weight: float = 1e-12
    start: float = 0.2              # [s]
    duration: float = 10.0          # [s] of identification, then the estimate is kept
    change_threshold: float = 5e-2  # relative change of M(q) that restarts learning
    anchor: str = "total_mass"
    anchor_mass: float = 0.0        # [kg]; 0: the simulated robot's own
    anchor_error: float = 0.0
    fit_tolerance: float = 1e-5
    on_mismatch: str = "identified"


@dataclass
class Potential:
    """The planar arm's null-space potential field (robot.potential).

    Null-space artificial potential field U(q) (Khatib's FIRAS form
    U = k / 2 (1 / rho - 1 / rho0)^2 for rho < rho0):
    links against the base square (sample points along each link, clearance rho in
    metres) and each joint k >= 2 against folding (rho = pi - |q_k| in radians).

    Attributes:
        base_gain: k for the link-base clearance [J m^2], > 0.
        base_margin: rho0 of the link-base clearance [m], > 0.
        fold_gain: k for folding [J rad^2], > 0.
        fold_margin: rho0 of folding [rad], in [1e-3, pi].
        points_per_link: The sample points along each link, an integer in
            [1, 100]."""
    base_gain: float = 1e-3         # k for link-base clearance [J m^2]
    base_margin: float = 0.06       # rho0 [m]
    fold_gain: float = 1e-3         # k for folding [J rad^2]
    fold_margin: float = 0.6        # rho0 [rad]
    points_per_link: int = 4


@dataclass
class Reference:
    """The planar end effector's reference angle (task.reference).

    alpha_d(t) = alpha(0) + sum_i amplitudes[i] sin(2 pi t / periods[i]) [rad].

    Attributes:
        amplitudes: The sines' amplitudes [rad], as many as periods.
        periods: The sines' periods [s], each > 0."""
    amplitudes: List[float] = field(default_factory=lambda: [0.3, 0.1])
    periods: List[float] = field(default_factory=lambda: [30.0, 11.0])


@dataclass
class AttitudeReference:
    """The end effector's reference attitude (task.reference of EndEffectorAttitude).

    R_d(t) = R_d(0) Rot(axis, amplitude sin(2 pi t / period)) (a body-fixed
    axis), with R_d(0) the end effector's attitude at q0 turned by
    ``initial_error`` [rad] about ``initial_error_axis`` (world frame).

    Attributes:
        axis: The body-fixed axis of the oscillation, a non-zero 3-vector (its
            length does not matter).
        amplitude: The oscillation's amplitude [rad], >= 0.
        period: The oscillation's period [s], > 0.
        initial_error: The angle R_d(0) is turned from the attitude at q0 [rad],
            in [0, pi].
        initial_error_axis: The world-frame axis of that turn, a non-zero
            3-vector."""
    axis: List[float] = field(default_factory=lambda: [0.0, 0.6, 0.8])
    amplitude: float = 0.4          # [rad]
    period: float = 8.0             # [s]
    initial_error: float = 0.3      # [rad]
    initial_error_axis: List[float] = field(default_factory=lambda: [0.6, 0.0, 0.8])

    def Start(self, R_WE0: RotationMatrix) -> RotationMatrix:
        """The reference's start R_d(0).

        Args:
            R_WE0: The end effector's attitude at the start (q0).

        Returns:
            R_d(0), R_WE0 turned by initial_error about initial_error_axis."""
        axis = np.asarray(self.initial_error_axis, float)
        return RotationMatrix(AngleAxis(self.initial_error,
                                        axis / np.linalg.norm(axis))) @ R_WE0

    def At(self, R_d0: RotationMatrix, t: float
           ) -> Tuple[RotationMatrix, np.ndarray]:
        """The reference attitude and its angular velocity at a time.

        Args:
            R_d0: The reference's start R_d(0) (Start).
            t: The time [s].

        Returns:
            The pair of R_d(t) and omega_d(t) in the world frame (3,) [rad/s]."""
        axis = np.asarray(self.axis, float) / np.linalg.norm(self.axis)
        w = 2 * np.pi / self.period
        phi, phi_dot = self.amplitude * np.sin(w * t), self.amplitude * w * np.cos(w * t)
        return (R_d0 @ RotationMatrix(AngleAxis(phi, axis)),
                R_d0.matrix() @ axis * phi_dot)


@dataclass
class AttitudeGains:
    """The attitude controller's gains (task.gains of EndEffectorAttitude).

    nu = D^+ (omega_d - Lambda e) + (I - D^+ D) xi with a damped pseudo-inverse
    (``task_damping`` mu), and the sliding-mode law

        tau = M nu_dot + C' nu - damping_rate M s - chi tanh(diag(M) s / phi),
        phi = epsilon + chi / boundary_rate:

    the damping is scaled to the inertia (K_d = damping_rate M(q)), so every joint's
    s decays at the same rate whatever its inertia (a light wrist with a constant
    K_d would need a far faster controller than a heavy shoulder), and so is the
    robust term's boundary layer, whose thickness phi follows chi (Slotine and Li's
    balance condition, Applied Nonlinear Control, sec. 7.2): its slope adds at most
    boundary_rate [1/s] to any joint's rate, whatever chi and the inertia (the
    paper's fixed tanh(s / epsilon) would add chi / (epsilon M_ii), a stiff sampled
    loop for a 5e-4 kg m^2 wrist or a large chi). chi comes from the RHS loop in DAC
    (its bound on ||e_tau||) and is ``chi_model_based`` in the baseline.

    Attributes:
        Lambda: The attitude error's gain in nu [1/s], > 0.
        damping_rate: The damping K_d = damping_rate M(q) [1/s], > 0, with
            damping_rate * periods.lhs <= 0.5 (the sampled loop stays well
            damped).
        task_damping: mu of the damped pseudo-inverse D^+ [-], >= 0.
        epsilon: The boundary layer's thickness at chi = 0 [N m s], > 0.
        boundary_rate: The most the boundary layer's slope adds to a joint's rate
            [1/s], > 0, with (damping_rate + boundary_rate) * periods.lhs <= 0.5
            (on an arm whose coupled motion is much lighter than its joints'
            inertias, the layer thickens to keep that: AttitudeController).
        chi_model_based: The fixed chi of the model-based baseline [N m], >= 0."""
    Lambda: float = 2.0             # [1/s]
    damping_rate: float = 20.0      # [1/s]
    task_damping: float = 1e-3      # mu [-]
    epsilon: float = 1e-3           # [N m s]
    boundary_rate: float = 20.0     # [1/s]
    chi_model_based: float = 0.0    # [N m]


@dataclass
class Rhs:
    """The RHS integrator's settings: its gain rule, chi and the trust band (rhs).

    RHS integrator (docs/equations.md E48): k_p = c / Re(lambda_hat_p), c filtered
    towards (1 + c_margin) c_min with time constant c_time_constant; chi = peak of
    ||e_tau|| with exponential forgetting over chi_window, never below chi_floor. A
    learned B_hat is used only if it passes the DIC check and its eigenvalues lie
    within trust_ratio of those of the trust band's anchor (the paper's bounded
    learning error, see gain_rule.within_trust): ``trust_anchor`` "in_use"
    (default), the estimate the loop runs on, so that the band moves with every
    accepted estimate and refuses only a sudden jump, while the estimate stays
    within trust_ratio^2 of B0 overall; "prior", B0 (the band of earlier releases,
    which refuses correct estimates wherever B0 is far from the truth). An estimate
    outside the band is still accepted on evidence: when, on the learner's port
    samples of the last ``evidence_window`` seconds, its port relation leaves at
    most ``evidence_ratio`` times the residual of the estimate in use (0: never).
    The gain rule reads min(beta_hat, beta_max): periods.rhs is checked at build
    time for the largest c that this allows, so the discrete loop never runs past
    the bound it was built for.

    ``adoption`` "certified_set" (default): a learner that publishes a credible set
    of B (learner.model local_bayes) has an estimate adopted only if the discrete
    loop's certificate (spectral radius, time-scale separation, DIC) holds for every
    B of the set, with c raised from the paper's rule where the set asks for it
    (gain_rule.CertifiedGains); the trust band and the evidence are then not used.
    A learner without a set (the network) is adopted by the trust band, as with
    "trust_band", which adopts every learner's point estimate by it. ``gain_rule`` "paper" (default): c follows
    (1 + c_margin) c_min(beta_hat) (eq. 48); "well_damped": c = 1 / (4 periods.rhs),
    the fastest decay whose discrete loop with the estimate right is still well
    damped (at least the paper's rule's c: the period check at build time
    guarantees it). With the estimate in use off by a factor r,
    lambda~ = r lambda_hat, the loop stays certified (analysis.rhs_loop) for
    Td lambda_LHS / c <= r <= 0.9025 / (h c); the faster c moves that band towards
    weaker actuators, [0.39, 3.6] against the paper rule's [0.46, 4.2] at
    beta_hat = 1 on the paper's arm.

    Attributes:
        Td: The time-scale separation factor T_d of eq. (48), > 0.
        c_margin: c's target is (1 + c_margin) c_min, >= 0.
        c_time_constant: The time constant of c's filter [s], > 0.
        chi_window: The forgetting time of chi's peak of ||e_tau|| [s], > 0.
        chi_floor: chi's lower bound [N m], > 0.
        chi_initial: chi at the start [N m], > 0.
        observer_noise: The standard deviation of the tau_obs measurement noise
            [N m], >= 0 (0: none).
        trust_ratio: B_hat is accepted only if its eigenvalues lie within this
            factor of the anchor's (gain_rule.within_trust), in [1, 10].
        trust_anchor: The trust band's anchor, one of TRUST_ANCHORS: "in_use" (the
            estimate in use) or "prior" (B0).
        evidence_ratio: An estimate outside the band is accepted if its residual on
            the port samples is at most this times the in-use one's, in [0, 1]
            (0: never).
        evidence_window: The forgetting time of those samples' statistics [s],
            > 0.
        beta_max: The largest beta_hat the gain rule uses, in [1, 1e6]: the RHS
            period is sized for c_min(beta_max), see RhsIntegrator.
        gain_rule: How c is chosen, one of GAIN_RULES: "paper" or
            "well_damped".
        adoption: How an estimate is adopted, one of ADOPTIONS: "certified_set"
            or "trust_band"."""
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
    adoption: str = "certified_set"


@dataclass
class Periods:
    """Discrete update periods [s] (docs/equations.md, SPEC settings): rhs < lhs < learner.

    Each > 0, with rhs < lhs <= learner_sample <= learner (the time-scale
    separation, gain_rule.check_period_order); rhs is also checked against the
    gain rule when a diagram is built (gain_rule.check_rhs_period).

    Attributes:
        rhs: The integrator and the observer's sampling [s].
        lhs: The sliding-mode controller and the observer's M, C' refresh [s].
        learner: A training step [s].
        learner_sample: The learner's data sampling and the RHS loop's refresh of
            B_hat(x), D_hat(x) and K at the current state (they change on the
            seconds scale of the arm's motion and when the learner publishes) [s].
        log: The loggers [s], at most the run's duration."""
    rhs: float = 2.5e-4
    lhs: float = 1e-3
    learner: float = 0.1
    learner_sample: float = 0.01
    log: float = 0.01


@dataclass
class ActuatorFault:
    """An actuator fault of the ground truth (an entry of uncertainty.faults).

    From ``time`` [s] on, the actuator of joint ``joint`` (1-based, the paper's
    q_joint) delivers ``gain`` times the torque it did before (row ``joint`` of B~
    is multiplied by ``gain``; faults on one joint compound).

    Attributes:
        time: When the fault starts [s], >= 0.
        joint: The joint, an integer in [1, n] (1-based).
        gain: The factor on the actuator's torque [-], in [1e-2, 1e2]."""
    time: float = 0.0               # [s]
    joint: int = 1                  # 1 .. n
    gain: float = 0.5               # [-]


@dataclass
class Uncertainty:
    """The ground truth's RHS: the nominal B0, D0 and their uncertainty by phase.

    Ground-truth RHS (docs/equations.md E19, SPEC settings):
    B~ = diag(g(t)) (B0 + Delta B), D~ = D0 + Delta D with
    Delta D(p) = diag(D_offset + D_linear * p)            [linear phase on]
               + diag(D_quadratic * p * p)                [nonlinear phase on]
    Delta B(x) = diag(B_linear @ q)                       [linear phase on]
               + diag(B_quadratic * p * p) + B_q1_squared q1^2   [nonlinear phase on]
    each group multiplied by linear_scale / nonlinear_scale, and the actuators'
    gains g_j(t) = B_scale[j] times the gain of every fault on joint j whose time
    has come (from t = 0, warm-up included: a motor constant off its datasheet,
    an actuator that degrades in orbit). B_scale empty: 1 for every joint.

    Every vector has one entry per joint (n), every matrix is n x n.

    Attributes:
        B0: The diagonal of the nominal B0 (n), each > 0.
        D0: The diagonal of the nominal D0 (n), each >= 0.
        D_offset: Delta D's constant diagonal (n).
        D_linear: Delta D's diagonal per unit of momentum p (n).
        D_quadratic: Delta D's diagonal per unit of p^2 (n).
        B_linear: Delta B's diagonal diag(B_linear @ q), n x n [1/rad].
        B_quadratic: Delta B's diagonal per unit of p^2 (n).
        B_q1_squared: Delta B's term B_q1_squared q1^2, n x n.
        linear_scale: The factor on the linear group, >= 0.
        nonlinear_scale: The factor on the nonlinear group, >= 0.
        B_scale: The actuators' gains, one per joint, each in [1e-2, 1e2], or none
            (all 1).
        faults: The actuator faults (ActuatorFault), none by default."""
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
    """The external disturbance d(t) acting on the port.

    d(t) = d_LF + d_HF from ``start`` (default: start of phase 3), times ``scale``:
    d_LF = lf_offset + lf_amplitude * [sin(2 pi f_1 t), cos(2 pi f_2 t), ...]
    d_HF = hf_amplitude sin(2 pi hf_frequency t) hf_direction      [N m]

    Attributes:
        start: When d starts [s]; negative: at the start of phase 3.
        scale: The factor on d, >= 0.
        lf_offset: d_LF's constant part, one per joint [N m].
        lf_amplitude: d_LF's amplitudes, one per joint [N m].
        lf_frequency: d_LF's frequencies f_j, one per joint [Hz].
        hf_amplitude: d_HF's amplitude [N m].
        hf_frequency: d_HF's frequency [Hz], >= 0.
        hf_direction: d_HF's direction, one entry per joint."""
    start: float = -1.0             # [s]; negative: start of phase 3
    scale: float = 1.0
    lf_offset: List[float] = field(default_factory=lambda: [0.03, -0.02])
    lf_amplitude: List[float] = field(default_factory=lambda: [0.02, 0.02])
    lf_frequency: List[float] = field(default_factory=lambda: [0.05, 0.07])   # [Hz]
    hf_amplitude: float = 0.005
    hf_frequency: float = 20.0      # [Hz]
    hf_direction: List[float] = field(default_factory=lambda: [1.0, -1.0])


TRUST_ANCHORS = ("in_use", "prior")            # Rhs.trust_anchor
INERTIA_ANCHORS = ("total_mass", "base_mass", "model")   # InertiaIdentification.anchor
ON_MISMATCH = ("identified", "nominal")         # InertiaIdentification.on_mismatch
GAIN_RULES = ("paper", "well_damped")           # Rhs.gain_rule
ADOPTIONS = ("certified_set", "trust_band")     # Rhs.adoption
LEARNER_MODELS = ("local_bayes", "network")     # Learner.model (learning package)
LEARNER_MODES = ("regularized", "plain")
LEARNER_COUPLINGS = ("uniform", "inertia")     # network.coupling_factors
LEARNER_PRIOR_SCALES = ("pooled", "per_input")  # identification.RhsIdentifier


@dataclass
class LocalBayes:
    """The local Bayesian learner's settings (learner.bayes; learning.local_bayes).

    Per joint, B_ij(x) and D_i(x) are local linear models (a value, a drift in time
    and a slope in the joint's momentum) fitted with a Gaussian prior: B_ii around
    B0_i, B_ij (i != j) around 0, D_i around D0_i, drifts and slopes around 0, each
    with the sd below times the entry's scale (B0_i, sqrt(B0_i B0_j), D0_i). The
    prior's ranges are also what is published (and certified by the RHS
    integrator) while a joint's window does not determine its row.

    Attributes:
        gain_range: [low, high], the actuators' gains B~_ii / B0_i the prior
            allows; 0 < low < 1 < high <= 100. Its half-width is the regression
            prior's sd of B_ii / B0_i.
        coupling: The prior's bound on a row's total cross-coupling
            sum_{j != i} |B_ij| / sqrt(B0_i B0_j), in [0, 1]; each entry's range
            and sd is its share, coupling / (n - 1) (local_bayes.entry_coupling).
        damping_range: [low, high], D~_i / D0_i the prior allows, 0 <= low < 1 <
            high; its half-width is the prior's sd of D_i / D0_i.
        drift: The prior's sd of an entry's rate of change along the trajectory,
            per unit of its scale [1/s], > 0.
        momentum_slope: The prior's sd of an entry's slope in its joint's
            momentum, per unit of its scale and of learner.momentum_scale, > 0.
        curvature: A bound on the second time derivative of an entry along the
            trajectory, per unit of its scale [1/s^2], >= 0: the local linear
            model's error over the window widens every interval by half of it
            times the window's mean squared age.
        floor: The systematic-error floor (kernels.bayes.fit_row), >= 0.
        forgetting: The samples' forgetting time [s], > 0: sample k weighs
            exp(-(t - t_k) / forgetting) (the window's length against the local
            model's curvature error).
        min_window: The samples a row's window must hold before it is fitted [s],
            > 0 and at most learner.window * periods.learner_sample.
        min_dof: The residual degrees of freedom, in independent samples, a
            row's window must leave before its fit is published, >= 1: the
            band-pass makes neighbouring samples one (kernels.bayes.fit_row).
        credible_level: The level of the reported intervals, in (0, 1).
        certificate_level: The level of the credible set the RHS integrator
            certifies, in [credible_level, 1).
        margin: An entry is published as learned only where it differs from the
            prior by more than margin times its credible half-width, >= 0 (2:
            with the interval right, the learned entry is no worse than the
            prior).
        change_floor: The relative residual of a row's newest samples that is a
            change (with learner.change_ratio over its recent median), >= 0: the
            local model explains its window to about 1e-3 of tau_obs.
        inconsistency: The relative residual of a row's newest samples that
            restarts its window whatever its history, > change_floor: the
            window's relation does not hold.
        model_error: The relative standard deviation of the LHS model's inertia
            that the physical claims allow, in [0, 1): the learner fits the port
            as the model sees it, (I + E) B~ and (I + E) D~ with E the model's
            relative inertia error, which port data cannot tell from B~ and
            momentum data do not reveal when a link's length is off
            (learning.local_bayes.physical_claims). It widens only what the
            metrics and reports claim about B~ and D~; the loop runs on the
            port as the model sees it."""
    gain_range: List[float] = field(default_factory=lambda: [0.5, 2.0])
    coupling: float = 0.05
    damping_range: List[float] = field(default_factory=lambda: [0.0, 3.0])
    drift: float = 0.05             # [1/s]
    momentum_slope: float = 0.03
    curvature: float = 0.01         # [1/s^2]
    floor: float = 1.0
    forgetting: float = 2.0         # [s]
    min_window: float = 0.2         # [s]
    min_dof: float = 6.0
    credible_level: float = 0.9
    certificate_level: float = 0.99
    margin: float = 2.0
    change_floor: float = 5e-3
    inconsistency: float = 0.1
    model_error: float = 0.1


@dataclass
class Learner:
    """The learner of the port's RHS (learning package), trained online.

    ``model`` "local_bayes" (default) is the local Bayesian learner: per joint a
    local linear model of B and D with calibrated intervals, its settings in
    ``bayes`` (LocalBayes), and band, band_sections, window, forgetting,
    momentum_scale, change_ratio and model_change below (learning.local_bayes).
    ``model`` "network" is the paper's physics-informed network (docs/equations.md
    E34-E35), trained online with Adam, with every setting below but ``bayes``;
    ``mode`` "plain" is always the network (the paper's learner):

    ``mode`` "plain" is the paper's learner: the raw port samples (x, u, qdot,
    tau_obs) of the last ``window`` sampling instants, the loss
    mean ||tau_obs - (B_hat u - D_hat qdot)||^2, no prior.

    ``mode`` "regularized" (default) identifies only what the closed-loop data
    inform (docs/concepts/identifiability.md):
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
    - prior_fallback: the learner publishes the prior (B0, D0) instead of the
      network while training holds after a change, before min_window seconds of
      samples follow it, and whenever the network explains the samples since the
      change worse than the prior (RhsLearner._NetworkPublished). After a change
      the frozen network describes the old relation and drifts with the state:
      on satellite_3dof without it, q0 moved by 0 to 3e-7 rad gave the learned
      B's error in phase 2 0.54-0.98 of the prior's and in phase 3 0.53-1.73
      (seed 1: 2.36); with it 0.61-0.75 and 0.82-0.84 (eight such q0, three
      seeds). Its price is the holds' share of each phase: on satellite_6dof
      (two seeds) phase 2 went from 0.67-0.73 to 0.80-0.81 and phase 3 from
      0.56-0.64 to 0.85-0.87, and on the Panda and the UR5 (arm_defaults) B
      went from 0.33-0.44 to 0.75-0.77 in phases 2-3 (the prior published for
      half of each 4 s phase), tracking within 2 % but the UR5's phase 2
      (1.44e-5 against 1.07e-5 rad, the learner-off loop's). False: the
      network is always published (the planar scenarios: their networks stay
      good across the changes, and the fallback would take the short
      scenario's B from 0.52 / 0.17 / 0.05 of the prior's error to 0.53 / 0.57
      / 0.45, and with actuators at x0.4 of B0 from 0.10 / 0.02 / 0.01 to
      0.50 / 0.49 / 0.50).

    ``coupling`` (either mode): how the network's n x n output enters B_hat
    (network.coupling_factors): "uniform" (the paper) or "inertia", where the
    coupling from a heavy joint j into a light joint i is scaled by
    min(1, m_i / m_j), m = diag M(q0). For arms whose joint inertias lie decades
    apart (the spatial robots' shipped scenarios use it; docs/results/spatial.md).

    Attributes:
        mode: One of LEARNER_MODES: "regularized" or "plain" (the paper's).
        hidden: The MLPs' hidden layer widths, at least one, each in [1, 4096].
        learning_rate: Adam's learning rate, > 0.
        window: The training samples kept (at periods.learner_sample), an integer
            in [2, 10^6].
        steps_per_update: Adam steps per learner period, an integer in
            [0, 10^4].
        momentum_scale: p is divided by this in the features [kg m^2/s], > 0.
        beta1: Adam's beta_1, in [0, 0.999999].
        beta2: Adam's beta_2, in [0, 0.999999].
        eps: Adam's epsilon, > 0.
        band: The band-pass filter's [low, high] corner frequencies [Hz]: low in
            [0, the Nyquist frequency of periods.learner_sample] (0: no
            high-pass), high in [low, that Nyquist frequency].
        band_sections: The band-pass filter's [high-pass, low-pass] section
            counts, each in [0, 16].
        forgetting: The samples' forgetting time [s], > 0.
        prior_weight: rho, the prior's weight in the loss, >= 0.
        change_ratio: The jump of the relative residual over its recent median
            that counts as a change, in [1, 10^6].
        change_floor: The relative residual a change must also exceed, >= 0.
        change_hold: How long training pauses after a change [s], >= 0.
        start_hold: How long training waits at the start [s], >= 0 (0: train from
            t = 0, earlier releases).
        min_window: The samples a fit needs after the start or a change [s], in
            [0, window * periods.learner_sample] (0: fit from the second sample,
            earlier releases).
        warm_start: Whether the first fit starts from the window's best constant
            B (False: Adam continues from the old estimate).
        model_change: Whether a new LHS model counts as a change (False: the LHS
            model's changes are not changes).
        step_guard: G, the loss growth that undoes an update's steps: 0 (off) or
            in [1, 10^12].
        prior_fallback: Whether the prior (B0, D0) is published while it fits
            better than the network.
        coupling: One of LEARNER_COUPLINGS: "uniform" or "inertia"
            (network.coupling_factors).
        prior_scale: One of LEARNER_PRIOR_SCALES: "pooled" or "per_input"
            (identification.RhsIdentifier).
        model: One of LEARNER_MODELS: "local_bayes" or "network".
        bayes: The local Bayesian learner's settings (LocalBayes)."""
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
    prior_fallback: bool = False    # True: (B0, D0) published while they fit better
    coupling: str = "uniform"
    prior_scale: str = "pooled"
    model: str = "local_bayes"
    bayes: LocalBayes = field(default_factory=LocalBayes)


@dataclass
class Excitation:
    """A persistently exciting port request for the learner (DAC only).

    The LHS adds tau_pe(t) = a_j sin(2 pi f_j t) to channel j of tau_c^r, with
    a_j = amplitude joint_scale_j and f_j spread geometrically over ``frequencies``
    = [f_first, f_last] in Hz (f_j = f_first (f_last / f_first)^(j / (n - 1))).
    amplitude = 0 switches it off. Joint i moves by about |(M^-1)_ij| a_j / (2 pi
    f_j)^2 under channel j: one amplitude for a 0.01 kg m^2 wrist and a 4e-5 kg m^2
    one (SO-101's) moves the light joint 250 times as far, which then bounds the
    tracking error; arm_defaults.excitation_scale sizes joint_scale for described
    arms.

    Why: under the slow reference the data inform B only weakly, and from phase 3
    on the low-frequency disturbance shares the reference's band; a small request
    inside the learner's band, away from both, makes B and D identifiable
    (docs/concepts/identifiability.md).

    Attributes:
        amplitude: The request's amplitude [N m], >= 0 (0: off).
        joint_scale: Each joint's factor on it, in [0, 1], or none (all 1).
        frequencies: The first and last frequency, [f_first, f_last], in Hz:
            f_first in [1e-3, the Nyquist frequency of periods.lhs], f_last in
            [f_first, that Nyquist frequency]; with learner.mode "regularized" and
            an amplitude > 0, both inside learner.band."""
    amplitude: float = 2e-4         # [N m]
    frequencies: List[float] = field(default_factory=lambda: [3.1, 4.3])   # [Hz]
    joint_scale: List[float] = field(default_factory=list)     # per joint; []: all 1

    def Amplitudes(self, n: int) -> np.ndarray:
        """The excitation's amplitude on each joint.

        Args:
            n: The number of joints.

        Returns:
            a_j = amplitude joint_scale_j for joints j = 0 .. n-1 [N m]."""
        scale = np.asarray(self.joint_scale, float) if self.joint_scale else np.ones(n)
        return self.amplitude * scale

    def Frequencies(self, n: int) -> np.ndarray:
        """The excitation's frequency on each joint.

        Args:
            n: The number of joints.

        Returns:
            f_j for joints j = 0 .. n-1 [Hz]."""
        first, last = self.frequencies
        return first * (last / first) ** (np.arange(n) / max(n - 1, 1))


@dataclass
class Stress:
    """A deliberately wrong learner, for verification (``dacph verify``).

    From time ``start`` on, the RHS integrator uses B_hat_scale * B_hat in place of
    the learner's B_hat (1 = the learner's estimate, no stress).

    Attributes:
        B_hat_scale: The factor on the learner's B_hat, > 0 (1: no stress).
        start: When the stress starts [s], >= 0."""
    B_hat_scale: float = 1.0
    start: float = 0.0              # [s]


# The robot: one of two typed sections (YAML tags !PlanarArm, the default, and
# !DescribedArm), and the task its LHS controller tracks (!EndEffectorAngle, the
# default, and !EndEffectorAttitude). robots.robot_of is the one place that
# dispatches on them.


@dataclass
class PlanarArm:
    """robot: a planar n-link arm on a free base (arm_parameters.RobotParams).

    Its task: EndEffectorAngle.

    Attributes:
        truth: The ground truth (RobotParams).
        nominal: The controller's model of it (their difference is the
            controller's model error), with as many links as ``truth``.
        potential: The null-space potential keeping the links off the base and
            unfolded (Potential)."""
    truth: RobotParams = field(default_factory=RobotParams)
    nominal: RobotParams = field(default_factory=RobotParams)
    potential: Potential = field(default_factory=Potential)

    def Validate(self) -> int:
        """Checks the robot section's settings.

        Returns:
            The joint count.

        Raises:
            ConfigError: Naming the first invalid setting."""
        self.truth.Validate("robot.truth")
        self.nominal.Validate("robot.nominal")
        n = self.truth.num_links
        if self.nominal.num_links != n:
            raise ConfigError(f"robot.nominal has {self.nominal.num_links} links; "
                              f"allowed: the same as robot.truth ({n})")
        for name in ("base_gain", "base_margin", "fold_gain"):
            require_positive(f"robot.potential.{name}", getattr(self.potential, name))
        require_in_range("robot.potential.fold_margin", self.potential.fold_margin, 1e-3,
                         np.pi, "rad")
        require_in_range("robot.potential.points_per_link",
                         self.potential.points_per_link, 1, 100)
        return n

    # The sweep's ground-truth distributions this robot takes
    # (montecarlo.definition.ROBOT_DISTRIBUTIONS).
    SAMPLED_SETTINGS = ("link_mass_scale", "link_length_scale", "link_inertia_scale",
                        "base_mass_scale", "base_inertia_scale")

    def ApplyRobotSample(self, sampled: Dict[str, object]) -> None:
        """Applies a sweep trial's sampled ground truth (montecarlo.definition).

        Args:
            sampled: The trial's sampled settings by name (SAMPLED_SETTINGS taken):
                per link mass (and inertia), length (com, width; inertia by its
                square) and inertia factors, the base's mass (and inertia) and
                inertia factors."""
        links = self.truth.links
        for link, f in zip(links, sampled.get("link_mass_scale", [1.0] * len(links))):
            link.mass *= f
            link.inertia *= f
        for link, f in zip(links, sampled.get("link_length_scale", [1.0] * len(links))):
            link.length *= f
            link.com *= f
            link.width *= f
            link.inertia *= f * f
        for link, f in zip(links, sampled.get("link_inertia_scale", [1.0] * len(links))):
            link.inertia *= f
        f = sampled.get("base_mass_scale", 1.0)
        self.truth.base.mass *= f
        self.truth.base.inertia *= f * sampled.get("base_inertia_scale", 1.0)

    def ApplyModelErrorSample(self, links: Optional[Sequence[float]],
                              base: Optional[float], num_joints: int) -> None:
        """Applies the controller's model error of a sweep trial.

        Args:
            links: One factor per link on the nominal robot's link masses and
                inertias, or None.
            base: The factor on the nominal base's mass and inertia, or None.
            num_joints: The number of joints (not needed by a planar arm)."""
        for link, f in zip(self.nominal.links, links or []):
            link.mass *= f
            link.inertia *= f
        if base is not None:
            self.nominal.base.mass *= base
            self.nominal.base.inertia *= base

    def ResolvePaths(self, folder: Path) -> None:
        """Nothing: a planar arm's section names no file.

        Args:
            folder: The folder of the scenario file."""

    def SizedDefaults(self, q0: Optional[Sequence[float]],
                      task: Optional["EndEffectorAngle"]) -> Optional["Scenario"]:
        """The scenario a file naming this robot starts from.

        Args:
            q0: The file's q0 (None where it leaves it out).
            task: The file's task (None where it leaves it out).

        Returns:
            None for the paper's arm (Scenario's own defaults, the paper's); for
                any other, arm_defaults.planar_arm_scenario: every per-joint setting
                sized to the arm, so that a file naming only robot.truth runs."""
        if self.truth == RobotParams():
            return None
        from dacph_drake.arm_defaults import planar_arm_scenario
        return planar_arm_scenario(self, q0, task)

    # The older file layouts that can express a scenario of this robot
    # (scenario_files: a saved run's fingerprint may come from them).
    OLDER_LAYOUTS = ("PlanarLayoutV1",)


@dataclass
class ClearancePotential:
    """The null-space potential of a described arm (robot.potential).

    robots.clearance_potential.BaseClearancePotential:
    U = gain / 2 sum_k max(0, margin - phi_k)^2 over the link-base signed distances,
    xi = -eta grad U; gain = 0 switches it off.

    Attributes:
        gain: The potential's gain, >= 0 (0: off).
        margin: The clearance below which the potential acts [m], > 0 (a file
            that leaves it out gets at most half its start's clearance:
            arm_defaults.potential_margin).
        eta: The null-space gain of xi = -eta grad U [1/s], >= 0."""
    gain: float = 1.0
    margin: float = 0.1             # [m]
    eta: float = 20.0               # [1/s]


JOINT_DAMPING = ("keep", "zero")               # DescribedArm.joint_damping
JOINT_LIMITS = ("stop", "ignore")              # DescribedArm.joint_limits
EFFORT_LIMITS = ("saturate", "ignore")         # DescribedArm.effort_limits


@dataclass
class ArmBase:
    """robot.base: the free-floating body an arm's own description is mounted on.

    A uniform box of ``mass`` [kg] and ``size`` [m] (its inertia and its collision
    shape, which the clearance potential keeps the links from), the arm's root
    frame welded to it at ``mount`` = [x, y, z] in m, [roll, pitch, yaw] in rad, in
    the box's centre frame. ``mass`` 0: no base is added, the description is the
    whole robot (its root body is the free base).

    Attributes:
        mass: The box's mass [kg], >= 0 (0: no base).
        size: The box's sides along x, y, z [m], each > 0.
        mount: The root frame's pose in the box's centre frame, [x, y, z] in m
            and [roll, pitch, yaw] in rad (6 finite numbers)."""
    mass: float = 0.0               # [kg]
    size: List[float] = field(default_factory=lambda: [1.0, 1.0, 1.0])      # [m]
    mount: List[float] = field(default_factory=lambda: [0.0, 0.0, 0.5, 0.0, 0.0, 0.0])


@dataclass
class EndEffectorFrame:
    """robot.end_effector: the frame whose attitude the task tracks.

    ``offset`` [m] from the description's frame ``frame``; ``frame`` empty: the
    description's own frame named end_effector.

    Attributes:
        frame: The description's frame it is fixed to ("": the frame named
            end_effector).
        offset: Its offset from that frame, x, y, z [m] (3 finite numbers)."""
    frame: str = ""
    offset: List[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])     # [m]


@dataclass
class DescribedArm:
    """robot: !DescribedArm, an arm from a description file.

    On the free base ``base`` (by default the description's root body is the
    base), tracking the attitude of ``end_effector``. Its task:
    EndEffectorAttitude.

    Attributes:
        description: A shipped name (description.SPATIAL_ROBOTS) or a path to a
            .urdf, .sdf or MJCF .xml file.
        base: The free base (ArmBase; by default the description's root body is
            the base).
        end_effector: The frame whose attitude the task tracks
            (EndEffectorFrame).
        package_paths: Folders holding ROS packages (a package.xml) whose
            package:// URIs the description uses, besides those on
            ROS_PACKAGE_PATH; each must be a folder.
        packages: Package name -> folder, for the URIs whose package name is not
            the one its package.xml declares (example-robot-data's files use
            package://example-robot-data/ while its package.xml is
            example_robot_descriptions); each must be a folder.
        joint_damping: What becomes of the description's joint damping b (URDF
            ``<dynamics damping>``), one of JOINT_DAMPING: "keep" lets it act in the
            ground truth and counts it in the LHS model, as the inertias are (the
            attitude controller requests b nu, the port observer adds b qdot: the
            port's D~ is what acts beyond it); "zero" removes it (a logged note),
            as the planar arms have none.
        locked_joints: Joints welded at a position (name: [rad] or [m], finite):
            a gripper's and any other joint that is not the arm's. Every prismatic
            joint is locked, at its position here or 0 (a logged note names them).
        joint_limits: The description's joint position limits, which the ground
            truth does not enforce, one of JOINT_LIMITS: "stop" refuses a q0
            outside them and stops a run that leaves them with a named reason;
            "ignore" leaves them unchecked.
        effort_limits: The URDF's joint effort limits (``<limit effort>``), one of
            EFFORT_LIMITS: "saturate" clips each actuator's command u_j to them in
            the ground truth and logs where it did (the log ``saturated``, the
            metric ``effort_saturated_share``); "ignore" leaves u as the
            controller sent it.
        nominal_inertia_scale: The controller's model error: one factor per body
            with mass in the plant's order (the description's bodies in its order,
            then robot.base's box when mass > 0; a wrong length lists them), each in [0.1, 10], by which
            the controller's model multiplies that body's mass and rotational
            inertia (its centre of mass stays); empty: the description's own
            inertias.
        potential: The null-space potential (ClearancePotential)."""
    description: str = "satellite_6dof"
    base: ArmBase = field(default_factory=ArmBase)
    end_effector: EndEffectorFrame = field(default_factory=EndEffectorFrame)
    package_paths: List[str] = field(default_factory=list)
    packages: Dict[str, str] = field(default_factory=dict)
    joint_damping: str = "keep"     # JOINT_DAMPING
    locked_joints: Dict[str, float] = field(default_factory=dict)
    joint_limits: str = "stop"      # JOINT_LIMITS
    effort_limits: str = "saturate"  # EFFORT_LIMITS
    nominal_inertia_scale: List[float] = field(default_factory=list)
    potential: ClearancePotential = field(default_factory=ClearancePotential)

    def ResolvePaths(self, folder: Path) -> None:
        """Makes the relative file paths of a scenario file's robot section relative
        to the file's folder: description (a .urdf, .sdf or MJCF .xml file),
        package_paths and packages' folders. Names of shipped robots and package:// URIs stay. A path
        that exists only relative to the working directory, as the previous release
        read it (a run directory's scenario.yaml saved by it), stays as it is.

        Args:
            folder: The folder of the scenario file."""
        def resolved(path: str) -> str:
            beside = folder / path
            if Path(path).is_absolute() or (Path(path).exists() and not beside.exists()):
                return path
            return str(beside)
        if (not self.description.startswith("package://")
                and Path(self.description).suffix.lower() in (".urdf", ".sdf", ".xml")):
            self.description = resolved(self.description)
        self.package_paths = [resolved(path) for path in self.package_paths]
        self.packages = {name: resolved(path) for name, path in self.packages.items()}

    def ValidateAssembly(self) -> None:
        """Checks how the robot is put together, before it is parsed.

        Raises:
            ConfigError: Naming the first invalid setting of how the robot is put
                together (base, mount, end effector, package paths)."""
        require_one_of("robot.joint_damping", self.joint_damping, JOINT_DAMPING)
        require_one_of("robot.joint_limits", self.joint_limits, JOINT_LIMITS)
        require_one_of("robot.effort_limits", self.effort_limits, EFFORT_LIMITS)
        for name, position in self.locked_joints.items():
            require_finite_numbers(f"robot.locked_joints.{name}", position)
        require_nonnegative("robot.base.mass", self.base.mass, "kg")
        for name, values, count in (("base.size", self.base.size, 3),
                                    ("base.mount", self.base.mount, 6),
                                    ("end_effector.offset", self.end_effector.offset, 3)):
            _require_length(f"robot.{name}", values, count,
                            {3: "x, y, z", 6: "x, y, z, roll, pitch, yaw"}[count])
            require_finite_numbers(f"robot.{name}", list(values))
        for i, side in enumerate(self.base.size):
            require_positive(f"robot.base.size[{i}]", side, "m")
        for i, folder in enumerate(self.package_paths):
            if not Path(folder).is_dir():
                raise ConfigError(f"robot.package_paths[{i}] = {folder!r} is not a "
                                  "folder; allowed: folders holding ROS packages "
                                  "(package.xml)")
        for name, folder in self.packages.items():
            if not Path(folder).is_dir():
                raise ConfigError(f"robot.packages.{name} = {folder!r} is not a folder; "
                                  "allowed: the folder package://NAME/ stands for")

    def Validate(self, bodies: Sequence[str]) -> None:
        """Checks the settings that depend on the parsed description.

        Args:
            bodies: The names of the bodies with mass, in the plant's order.

        Raises:
            ConfigError: Naming the first invalid setting."""
        if len(self.nominal_inertia_scale) not in (0, len(bodies)):
            raise ConfigError(f"robot.nominal_inertia_scale has "
                              f"{len(self.nominal_inertia_scale)} entries; allowed: "
                              f"{len(bodies)}, one per body with mass in this order: "
                              f"{', '.join(bodies)}; or none")
        for i, f in enumerate(self.nominal_inertia_scale):
            require_in_range(f"robot.nominal_inertia_scale[{i}]", f, 0.1, 10.0)
        require_nonnegative("robot.potential.gain", self.potential.gain)
        require_positive("robot.potential.margin", self.potential.margin, "m")
        require_nonnegative("robot.potential.eta", self.potential.eta, "1/s")

    def SizedDefaults(self, q0: Optional[Sequence[float]],
                      task: Optional["EndEffectorAttitude"]) -> "Scenario":
        """The scenario whose settings a file naming this robot starts from.

        Every per-joint setting sized to the arm (arm_defaults.arm_scenario).

        Args:
            q0: The file's q0 [rad] (None where the file leaves it out).
            task: The file's task (None where the file leaves it out).

        Returns:
            The sized scenario."""
        from dacph_drake.arm_defaults import arm_scenario
        return arm_scenario(self, q0, task)

    SAMPLED_SETTINGS = ()           # a description has no link parameters to sample

    def ApplyRobotSample(self, sampled: Dict[str, object]) -> None:
        """Nothing: the ground truth is the description's.

        Args:
            sampled: The trial's sampled settings by name (none taken)."""

    def ApplyModelErrorSample(self, links: Optional[Sequence[float]],
                              base: Optional[float], num_joints: int) -> None:
        """Applies the controller's model error of a sweep trial.

        nominal_inertia_scale in the plant's body order: ``base`` on the free
        base's body, links[j] on the body joint j moves, 1 elsewhere
        (robots.described.model_error_scale).

        Args:
            links: One factor per joint, or None.
            base: The base's factor, or None.
            num_joints: The number of joints (not needed: the description has
                them)."""
        if links is not None or base is not None:
            from dacph_drake.robots.described import model_error_scale
            self.nominal_inertia_scale = model_error_scale(self, links, base)

    OLDER_LAYOUTS = ()              # runs of described arms were first fingerprinted
    #                                 in the current layout


@dataclass
class EndEffectorAngle:
    """task: the planar end effector's absolute angle alpha = theta0 + sum q.

    It tracks ``reference`` under the sliding-mode LHS controller with ``gains``.

    Attributes:
        reference: The reference angle alpha_d(t) (Reference).
        gains: The LHS controller's gains (LhsGains)."""
    reference: Reference = field(default_factory=Reference)
    gains: LhsGains = field(default_factory=LhsGains)

    def Validate(self, periods: Periods) -> None:
        """Checks the gains and the reference.

        Args:
            periods: The scenario's periods (not needed by this task).

        Raises:
            ConfigError: Naming the first gain or reference setting out of range."""
        for name in ("Kd", "Lambda", "epsilon", "eta"):
            require_positive(f"task.gains.{name}", getattr(self.gains, name))
        require_nonnegative("task.gains.chi_model_based", self.gains.chi_model_based,
                            "N m")
        require_in_range("task.gains.min_task_singular_value",
                         self.gains.min_task_singular_value, 0.0, 10.0)
        require_nonnegative("task.gains.boundary_rate", self.gains.boundary_rate, "1/s")
        if len(self.reference.amplitudes) != len(self.reference.periods):
            raise ConfigError("task.reference.amplitudes and task.reference.periods "
                              "must have the same length")
        for i, T in enumerate(self.reference.periods):
            require_positive(f"task.reference.periods[{i}]", T, "s")


@dataclass
class EndEffectorAttitude:
    """task: !EndEffectorAttitude, the end effector's 3D attitude.

    It tracks ``reference`` under the AttitudeController with ``gains``.

    Attributes:
        reference: The reference attitude R_d(t) (AttitudeReference).
        gains: The attitude controller's gains (AttitudeGains)."""
    reference: AttitudeReference = field(default_factory=AttitudeReference)
    gains: AttitudeGains = field(default_factory=AttitudeGains)

    def Validate(self, periods: Periods) -> None:
        """Checks the gains and the reference.

        Args:
            periods: The scenario's periods (the gains' rates against
                periods.lhs).

        Raises:
            ConfigError: Naming the first gain or reference setting out of range."""
        r, g = self.reference, self.gains
        require_positive("task.reference.period", r.period, "s")
        require_nonnegative("task.reference.amplitude", r.amplitude, "rad")
        require_in_range("task.reference.initial_error", r.initial_error, 0.0, np.pi,
                         "rad")
        for name in ("axis", "initial_error_axis"):
            axis = getattr(r, name)
            require_finite_numbers(f"task.reference.{name}", list(axis))
            if len(axis) != 3 or np.linalg.norm(axis) == 0:
                raise ConfigError(f"task.reference.{name} = {list(axis)}; allowed: a "
                                  "non-zero 3-vector")
        require_positive("task.gains.Lambda", g.Lambda, "1/s")
        require_positive("task.gains.damping_rate", g.damping_rate, "1/s")
        require_nonnegative("task.gains.task_damping", g.task_damping)
        require_positive("task.gains.epsilon", g.epsilon, "N m s")
        require_positive("task.gains.boundary_rate", g.boundary_rate, "1/s")
        require_nonnegative("task.gains.chi_model_based", g.chi_model_based, "N m")
        for name, rate in (("damping_rate", g.damping_rate),
                           ("damping_rate + task.gains.boundary_rate",
                            g.damping_rate + g.boundary_rate)):
            if rate * periods.lhs > 0.5:
                raise ConfigError(
                    f"task.gains.{name} = {rate:g} 1/s with periods.lhs = "
                    f"{periods.lhs:g} s; allowed: rate * periods.lhs <= 0.5 (the "
                    "sampled sliding-mode loop stays well damped)")


@dataclass(eq=False)
class Scenario:
    """Every setting of a closed-loop run.

    The robot and its task (typed sections, see PlanarArm, DescribedArm,
    EndEffectorAngle, EndEffectorAttitude), the initial joint angles, and the
    sections every robot shares. The run lasts as long as the phases.

    Attributes:
        robot: The robot: PlanarArm (the default) or DescribedArm (YAML tag
            !DescribedArm).
        task: The task its LHS controller tracks: EndEffectorAngle with a
            PlanarArm, EndEffectorAttitude (!EndEffectorAttitude) with a
            DescribedArm.
        q0: The initial joint angles [rad], one per joint, finite (the robot
            checks it further: a planar arm's clear of the base and of the task's
            singularities, a described arm's within its joint limits where
            robot.joint_limits is "stop").
        phases: The phases' durations (Phases).
        inertia: The identification of the inertial parameters
            (InertiaIdentification).
        rhs: The RHS integrator (Rhs).
        periods: The discrete update periods (Periods).
        uncertainty: The ground truth's RHS (Uncertainty).
        disturbance: The external disturbance d(t) (Disturbance).
        learner: The learner (Learner).
        excitation: The learner's excitation (Excitation).
        stress: A deliberately wrong learner, for verification (Stress).
        simulator: Drake's simulator settings for the ground truth's continuous
            state (SimulatorConfig; loop.simulator.validate_simulator_config
            says what a closed loop can run). The step taken is
            min(max_step_size, periods.rhs): the RHS samples end every step.
        seed: The learner's initialization and the observer's noise, an integer
            in [0, 2^32 - 1]."""
    robot: Union[PlanarArm, DescribedArm] = field(default_factory=PlanarArm)
    task: Union[EndEffectorAngle, EndEffectorAttitude] = field(
        default_factory=EndEffectorAngle)
    q0: List[float] = field(default_factory=lambda: [0.3, 1.0])   # initial joints [rad]
    phases: Phases = field(default_factory=Phases)
    inertia: InertiaIdentification = field(default_factory=InertiaIdentification)
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
        """Checks every setting.

        The robot and its task through robots.robot_of, which builds the robot;
        the RHS period is checked against the gain rule when a diagram is built
        (gain_rule.check_rhs_period).

        Raises:
            ConfigError: Naming the first invalid setting and its allowed range."""
        from dacph_drake.robots import robot_of
        validate_seed(self.seed)
        robot_of(self)

    def ValidateShared(self, n: int, joint_names: Sequence[str] = ()) -> None:
        """Checks the sections every robot shares (robots.robot_of calls it).

        Args:
            n: The robot's number of joints.
            joint_names: Their names in q's order, for the messages (none: not
                named).

        Raises:
            ConfigError: Naming the first invalid setting of those sections."""
        if joint_names and len(self.q0) != n:
            raise ConfigError(f"q0 has {len(self.q0)} entries; allowed: {n} (one per "
                              f"joint); the joints in q0's order: "
                              f"{', '.join(joint_names)}")
        _require_length("q0", self.q0, n)
        require_finite_numbers("q0", list(self.q0))
        self.task.Validate(self.periods)
        validate_phases(self.phases)
        require_positive("phases (total)", self.phases.end, "s")
        require_in_range("inertia.prior_weight", self.inertia.prior_weight, 1e-14, 1.0)
        require_nonnegative("inertia.start", self.inertia.start, "s")
        require_positive("inertia.duration", self.inertia.duration, "s")
        require_in_range("inertia.change_threshold", self.inertia.change_threshold,
                         0.0, 1.0)
        require_one_of("inertia.anchor", self.inertia.anchor, INERTIA_ANCHORS)
        require_nonnegative("inertia.anchor_mass", self.inertia.anchor_mass, "kg")
        require_in_range("inertia.anchor_error", self.inertia.anchor_error, -0.5, 0.5)
        require_nonnegative("inertia.fit_tolerance", self.inertia.fit_tolerance)
        require_one_of("inertia.on_mismatch", self.inertia.on_mismatch, ON_MISMATCH)
        validate_port_settings(self, n)
        validate_simulator_config(self.simulator)
        # Last, so that a setting with a range names it: every other number finite.
        require_finite_numbers("", self)


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


def validate_port_settings(scenario: Scenario, n: int) -> None:
    """Checks the settings of the port's RHS chain.

    The sections rhs, stress, periods, uncertainty, disturbance, learner and
    excitation.

    Args:
        scenario: The scenario.
        n: Its robot's number of joints.

    Raises:
        ConfigError: Naming the first invalid setting of the port's RHS chain."""
    from dacph_drake.gain_rule import check_period_order
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
                     "periods.learner_sample)")
    require_in_range("learner.band[1]", L.band[1], L.band[0], nyquist,
                     "Hz (above band[0], at most the Nyquist frequency of "
                     "periods.learner_sample)")
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
                     "s (at most learner.window * periods.learner_sample)")
    require_one_of("learner.model", L.model, LEARNER_MODELS)
    validate_local_bayes(L.bayes, L.window * periods.learner_sample)
    E = scenario.excitation
    require_nonnegative("excitation.amplitude", E.amplitude, "N m")
    if E.joint_scale:
        _require_length("excitation.joint_scale", E.joint_scale, n,
                        "one per joint, or none")
        for i, factor in enumerate(E.joint_scale):
            require_in_range(f"excitation.joint_scale[{i}]", factor, 0.0, 1.0)
    _require_length("excitation.frequencies", E.frequencies, 2,
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
        _require_length(f"learner.bayes.{name}", values, 2, "[low, high]")
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


def _require_length(name: str, values, n: int, meaning: str = "one per joint"
                    ) -> None:
    if len(values) != n:
        raise ConfigError(f"{name} has {len(values)} entries; allowed: {n} "
                          f"({meaning})")


def paper_scenario() -> Scenario:
    """The paper's scenario (1500 s): the defaults, with the paper's premise of an
    exact LHS model stated (learner.bayes.model_error 0: the controller's model is
    the robot, its inertias identified from momentum); scenarios/paper.yaml is its
    file."""
    scenario = Scenario()
    scenario.learner.bayes.model_error = 0.0
    return scenario


def short_scenario() -> Scenario:
    """The paper's phases compressed to 2 + 8 + 8 + 8 s (tests and a quick look);
    scenarios/short.yaml is its file."""
    return Scenario(phases=Phases(warmup=2.0, linear=8.0, nonlinear=8.0, disturbance=8.0))


# The sections a described arm's scenario changes from the planar defaults.

def described_arm_periods() -> Periods:
    """RHS integrator and observer < LHS < learner sampling < training (the gain
    rule with K_d = damping_rate M asks for periods.rhs <= 1.25 ms)."""
    return Periods(rhs=5e-4, lhs=1e-3, learner=0.1, learner_sample=1e-2, log=1e-2)


def described_arm_rhs() -> Rhs:
    """chi forgets over 0.25 s (the planar default is 2 s): the arm starts at rest
    with a 0.3 rad error, and the sliding mode's first request (73 N m at the
    6-DOF shoulder) passes through e_tau once, at the observer's one-sample
    pairing; a 2 s window would keep chi near 30 N m for seconds."""
    return Rhs(chi_window=0.25)


def described_arm_learner() -> Learner:
    """The learner on joints whose inertias lie decades apart (docs/results/spatial.md):
    8 high-pass sections (with the planar 4, the slow reference's N m
    torques leak into the band and leave 10-92 % of the heavy joints' in-band port
    torque unexplained by the true model: 1-5 % with 8); the prior weighted 0.1
    (heavy joints' damping torque is under 1 % of their in-band inertial torque: D
    stays at D0 there instead of drifting); the couplings from heavy into light
    joints scaled by their inertia ratio (unscaled, their errors perturbed the
    wrist: 3-8x the learner-off tracking error); each B_ij held by its own inputs'
    mean square (pooled, the shoulders' inputs held the wrist's B_ii at B0); the
    prior published while the network does not beat it (prior_fallback)."""
    return Learner(momentum_scale=0.5, prior_weight=0.1, band_sections=[8, 8],
                   coupling="inertia", prior_scale="per_input", prior_fallback=True)


def six_dof_uncertainty(scale: float = 1.0) -> Uncertainty:
    """The ground truth's RHS of satellite_6dof, the paper's form sized to each joint.

    Dampings and momentum terms scaled to the joint's inertia and momentum
    (shoulder p ~ 0.8, wrist p ~ 0.02 kg m^2/s on the shipped reference).

    Args:
        scale: The factor on both groups (linear_scale and nonlinear_scale).

    Returns:
        The Uncertainty section."""
    pair = np.array([[-0.1, 0.0], [0.05, 0.15]])
    coupling = np.zeros((6, 6))
    coupling[:2, :2] = [[0.0, -0.1], [0.4, 0.0]]
    return Uncertainty(
        B0=[1.0] * 6, D0=[0.2, 0.2, 0.1, 0.01, 0.01, 0.005],
        D_offset=[0.04, 0.05, 0.02, 0.002, 0.003, 0.001],
        D_linear=[0.05, 0.15, 0.1, 0.1, 0.1, 0.1],
        D_quadratic=[-0.01, 0.1, 0.1, 1.0, -1.0, 1.0],
        B_linear=np.kron(np.eye(3), pair).tolist(),
        B_quadratic=[0.02, -0.5, 0.5, 5.0, -5.0, 5.0],
        B_q1_squared=coupling.tolist(), linear_scale=scale, nonlinear_scale=scale)


def six_dof_disturbance(scale: float = 1.0) -> Disturbance:
    """The shipped 6-DOF arm's disturbance d(t).

    Args:
        scale: The factor on d(t) (Disturbance.scale).

    Returns:
        The Disturbance section."""
    return Disturbance(
        scale=scale, lf_offset=[0.03, -0.02, 0.02, -0.002, 0.002, -0.001],
        lf_amplitude=[0.02, 0.02, 0.01, 0.002, 0.002, 0.001],
        lf_frequency=[0.05, 0.07, 0.06, 0.08, 0.09, 0.1],
        hf_direction=[1.0, -1.0, 0.5, -0.1, 0.1, -0.05])


SATELLITE_PHASES = dict(warmup=2.0, linear=4.0, nonlinear=4.0, disturbance=4.0)


def satellite_6dof_scenario() -> Scenario:
    """The 6-DOF example (scenarios/satellite_6dof.yaml): 2 s warm-up on the
    nominal RHS, then 4 s each of linear uncertainty, nonlinear uncertainty and the
    disturbance."""
    return Scenario(
        robot=DescribedArm("satellite_6dof"), task=EndEffectorAttitude(),
        q0=[0.3, -0.8, 1.6, 0.2, 0.6, -0.3], phases=Phases(**SATELLITE_PHASES),
        rhs=described_arm_rhs(), periods=described_arm_periods(),
        uncertainty=six_dof_uncertainty(), disturbance=six_dof_disturbance(),
        learner=described_arm_learner())


def satellite_3dof_scenario() -> Scenario:
    """The 3-DOF variant (scenarios/satellite_3dof.yaml) with the same phases and
    an uncertainty of the same form sized to its joints (shoulder yaw p ~ 0.3,
    pitch p ~ 1.1, forearm roll p ~ 5e-4 kg m^2/s)."""
    return Scenario(
        robot=DescribedArm("satellite_3dof"), task=EndEffectorAttitude(),
        q0=[0.3, -0.8, 1.6], phases=Phases(**SATELLITE_PHASES),
        rhs=described_arm_rhs(), periods=described_arm_periods(),
        uncertainty=Uncertainty(
            B0=[1.0] * 3, D0=[0.2, 0.2, 0.01], D_offset=[0.04, 0.05, 0.002],
            D_linear=[0.15, 0.05, 0.1], D_quadratic=[0.1, -0.01, 1.0],
            B_linear=[[-0.1, 0.0, 0.0], [0.05, 0.15, 0.0], [0.0, 0.0, 0.1]],
            B_quadratic=[0.5, 0.02, 5.0],
            B_q1_squared=[[0.0, -0.1, 0.0], [0.4, 0.0, 0.0], [0.0, 0.0, 0.0]]),
        disturbance=Disturbance(lf_offset=[0.03, -0.02, 0.002],
                                lf_amplitude=[0.02, 0.02, 0.002],
                                lf_frequency=[0.05, 0.07, 0.09],
                                hf_direction=[1.0, -1.0, 0.1]),
        learner=described_arm_learner())


BUILT_IN_SCENARIOS = {"paper": paper_scenario, "short": short_scenario,
                      "satellite_6dof": satellite_6dof_scenario,
                      "satellite_3dof": satellite_3dof_scenario}
