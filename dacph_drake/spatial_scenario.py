"""SpatialScenario: the settings of a closed loop on a spatial free-floating robot
(a description file, description.py) tracking a 3D end-effector attitude
reference (spatial_diagrams.py: the DAC loop, its learning ablation and the
model-based baseline). The port's RHS chain (true RHS, integrator, observer,
learner) takes the planar scenario's sections (scenario.py: rhs, uncertainty,
disturbance, learner, excitation, stress, phases), sized for the robot's joints."""
from dataclasses import dataclass, field
from typing import List

import numpy as np
from pydrake.common.eigen_geometry import AngleAxis
from pydrake.common.yaml import yaml_dump_typed
from pydrake.math import RotationMatrix
from pydrake.systems.analysis import SimulatorConfig

from dacph_drake.errors import (ConfigError, require_finite_numbers, require_in_range,
                                require_nonnegative, require_positive)
from dacph_drake.scenario import (Disturbance, Excitation, InertiaIdentification,
                                  Learner, Periods, Phases, Rhs, Stress, Uncertainty,
                                  validate_phases, validate_port_settings,
                                  validate_seed)
from dacph_drake.simulation import FixedStepConfig, validate_simulator_config


@dataclass
class AttitudeReference:
    """R_d(t) = R_d(0) Rot(axis, amplitude sin(2 pi t / period)) (a body-fixed
    axis), with R_d(0) the end effector's attitude at q0 turned by
    ``initial_error`` [rad] about ``initial_error_axis`` (world frame)."""
    axis: List[float] = field(default_factory=lambda: [0.0, 0.6, 0.8])
    amplitude: float = 0.4          # [rad]
    period: float = 8.0             # [s]
    initial_error: float = 0.3      # [rad]
    initial_error_axis: List[float] = field(default_factory=lambda: [0.6, 0.0, 0.8])

    def Start(self, R_WE0: RotationMatrix) -> RotationMatrix:
        """R_d(0) from the end effector's attitude at the start."""
        axis = np.asarray(self.initial_error_axis, float)
        return RotationMatrix(AngleAxis(self.initial_error,
                                        axis / np.linalg.norm(axis))) @ R_WE0

    def At(self, R_d0: RotationMatrix, t: float):
        """(R_d(t), omega_d(t) in the world frame [rad/s])."""
        axis = np.asarray(self.axis, float) / np.linalg.norm(self.axis)
        w = 2 * np.pi / self.period
        phi, phi_dot = self.amplitude * np.sin(w * t), self.amplitude * w * np.cos(w * t)
        return (R_d0 @ RotationMatrix(AngleAxis(phi, axis)),
                R_d0.matrix() @ axis * phi_dot)


@dataclass
class AttitudeGains:
    """nu = D^+ (omega_d - Lambda e) + (I - D^+ D) xi with a damped pseudo-inverse
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
    (its bound on ||e_tau||) and is ``chi_model_based`` in the baseline."""
    Lambda: float = 2.0             # [1/s]
    damping_rate: float = 20.0      # [1/s]
    task_damping: float = 1e-3      # mu [-]
    epsilon: float = 1e-3           # [N m s]
    boundary_rate: float = 20.0     # [1/s]
    chi_model_based: float = 0.0    # [N m]


@dataclass
class ClearancePotential:
    """The null-space potential (spatial_potential.BaseClearancePotential):
    U = gain / 2 sum_k max(0, margin - phi_k)^2 over the link-base signed distances,
    xi = -eta grad U; gain = 0 switches it off."""
    gain: float = 1.0
    margin: float = 0.1             # [m]
    eta: float = 20.0               # [1/s]


def _six_dof_uncertainty() -> Uncertainty:
    """The ground truth's RHS of satellite_6dof, the paper's form (scenario.Uncertainty)
    sized to each joint: dampings and momentum terms scaled to the joint's inertia and
    momentum (shoulder p ~ 0.8, wrist p ~ 0.02 kg m^2/s on the shipped reference)."""
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
        B_q1_squared=coupling.tolist(), linear_scale=0.0, nonlinear_scale=0.0)


def _six_dof_disturbance() -> Disturbance:
    return Disturbance(
        scale=0.0, lf_offset=[0.03, -0.02, 0.02, -0.002, 0.002, -0.001],
        lf_amplitude=[0.02, 0.02, 0.01, 0.002, 0.002, 0.001],
        lf_frequency=[0.05, 0.07, 0.06, 0.08, 0.09, 0.1],
        hf_direction=[1.0, -1.0, 0.5, -0.1, 0.1, -0.05])


@dataclass(eq=False)
class SpatialScenario:
    robot: str = "satellite_6dof"   # a shipped robot or a .urdf/.sdf path
    q0: List[float] = field(default_factory=lambda: [0.3, -0.8, 1.6, 0.2, 0.6, -0.3])
    duration: float = 8.0           # [s]
    reference: AttitudeReference = field(default_factory=AttitudeReference)
    gains: AttitudeGains = field(default_factory=AttitudeGains)
    potential: ClearancePotential = field(default_factory=ClearancePotential)
    # The controller's model error: one factor per body with mass, in the
    # description's order (base first; inertial_parameters.InertialParameters):
    # the controller's model has that body's mass and rotational inertia times it
    # (its centre of mass where it is). Empty: the description's own inertias.
    nominal_inertia_scale: List[float] = field(default_factory=list)
    inertia: InertiaIdentification = field(default_factory=InertiaIdentification)
    # The port's RHS chain (scenario.py's sections). By default the uncertainty
    # and the disturbance are scaled to zero (the ground truth is the nominal RHS,
    # B0 u - D0 qdot); the shipped scenarios (spatial_run.BUILT_IN_SPATIAL_SCENARIOS)
    # switch them on at the phases' starts.
    phases: Phases = field(default_factory=lambda: Phases(
        warmup=2.0, linear=2.0, nonlinear=2.0, disturbance=2.0))
    uncertainty: Uncertainty = field(default_factory=_six_dof_uncertainty)
    disturbance: Disturbance = field(default_factory=_six_dof_disturbance)
    # chi forgets over 0.25 s (the planar default is 2 s): the arm starts at rest
    # with a 0.3 rad error, and the sliding mode's first request (73 N m at the
    # 6-DOF shoulder) passes through e_tau once, at the observer's one-sample
    # pairing; a 2 s window would keep chi near 30 N m for seconds.
    rhs: Rhs = field(default_factory=lambda: Rhs(chi_window=0.25))
    # The learner on joints whose inertias lie decades apart (README, "Spatial
    # robots"): 8 high-pass sections (with the planar 4, the slow reference's
    # N m torques leak into the band and leave 10-92 % of the heavy joints'
    # in-band port torque unexplained by the true model: 1-5 % with 8); the prior
    # weighted 0.1 (heavy joints' damping torque is under 1 % of their in-band
    # inertial torque: D stays at D0 there instead of drifting); the couplings
    # from heavy into light joints scaled by their inertia ratio (unscaled, their
    # errors perturbed the wrist: 3-8x the learner-off tracking error); each B_ij
    # held by its own inputs' mean square (pooled, the shoulders' inputs held the
    # wrist's B_ii at B0).
    learner: Learner = field(default_factory=lambda: Learner(
        momentum_scale=0.5, prior_weight=0.1, band_sections=[8, 8], coupling="inertia",
        prior_scale="per_input"))
    excitation: Excitation = field(default_factory=Excitation)
    stress: Stress = field(default_factory=Stress)
    # Discrete periods [s]: RHS integrator and observer < LHS < learner sampling <
    # training (the gain rule with K_d = damping_rate M asks for rhs <= 1.25 ms).
    rhs_period: float = 5e-4
    lhs_period: float = 1e-3
    learner_sample_period: float = 1e-2
    learner_period: float = 0.1
    log_period: float = 1e-2
    simulator: SimulatorConfig = field(default_factory=FixedStepConfig)
    seed: int = 0

    def __eq__(self, other) -> bool:
        """Equal settings: the same YAML form (SimulatorConfig compares by identity)."""
        return (isinstance(other, SpatialScenario)
                and yaml_dump_typed(self) == yaml_dump_typed(other))

    @property
    def periods(self) -> Periods:
        """The discrete periods as the planar scenario's Periods (the RHS chain's
        systems read them from there)."""
        return Periods(rhs=self.rhs_period, lhs=self.lhs_period,
                       learner=self.learner_period,
                       learner_sample=self.learner_sample_period, log=self.log_period)

    @property
    def disturbance_start(self) -> float:
        return (self.disturbance.start if self.disturbance.start >= 0
                else self.phases.disturbance_start)

    def Validate(self, num_joints: int, num_bodies: int = None) -> None:
        """ConfigError naming the first invalid setting and its allowed range
        (``num_bodies``: the description's bodies with mass, for
        nominal_inertia_scale's length)."""
        if len(self.nominal_inertia_scale) not in (0, num_bodies or
                                                   len(self.nominal_inertia_scale)):
            raise ConfigError(f"nominal_inertia_scale has {len(self.nominal_inertia_scale)} "
                              f"entries; allowed: {num_bodies} (one per body with mass, "
                              "base first) or none")
        for i, f in enumerate(self.nominal_inertia_scale):
            require_in_range(f"nominal_inertia_scale[{i}]", f, 0.1, 10.0)
        require_in_range("inertia.prior_weight", self.inertia.prior_weight, 1e-14, 1.0)
        require_nonnegative("inertia.start", self.inertia.start, "s")
        require_positive("inertia.duration", self.inertia.duration, "s")
        require_in_range("inertia.change_threshold", self.inertia.change_threshold,
                         0.0, 1.0)
        if len(self.q0) != num_joints:
            raise ConfigError(f"q0 has {len(self.q0)} entries; allowed: {num_joints} "
                              "(one per joint of the robot)")
        require_finite_numbers("q0", list(self.q0))
        require_positive("duration", self.duration, "s")
        require_positive("reference.period", self.reference.period, "s")
        require_nonnegative("reference.amplitude", self.reference.amplitude, "rad")
        require_in_range("reference.initial_error", self.reference.initial_error,
                         0.0, np.pi, "rad")
        for name in ("axis", "initial_error_axis"):
            axis = getattr(self.reference, name)
            require_finite_numbers(f"reference.{name}", list(axis))
            if len(axis) != 3 or np.linalg.norm(axis) == 0:
                raise ConfigError(f"reference.{name} = {list(axis)}; allowed: a "
                                  "non-zero 3-vector")
        require_positive("gains.Lambda", self.gains.Lambda, "1/s")
        require_positive("gains.damping_rate", self.gains.damping_rate, "1/s")
        require_nonnegative("gains.task_damping", self.gains.task_damping)
        require_nonnegative("potential.gain", self.potential.gain)
        require_positive("potential.margin", self.potential.margin, "m")
        require_nonnegative("potential.eta", self.potential.eta, "1/s")
        require_positive("lhs_period", self.lhs_period, "s")
        if self.gains.damping_rate * self.lhs_period > 0.5:
            raise ConfigError(
                f"gains.damping_rate = {self.gains.damping_rate:g} 1/s with lhs_period "
                f"= {self.lhs_period:g} s; allowed: damping_rate * lhs_period <= 0.5 (the "
                "sampled sliding-mode loop stays well damped)")
        require_in_range("log_period", self.log_period, self.lhs_period, self.duration,
                         "s")
        require_positive("gains.epsilon", self.gains.epsilon, "N m s")
        require_positive("gains.boundary_rate", self.gains.boundary_rate, "1/s")
        if (self.gains.damping_rate + self.gains.boundary_rate) * self.lhs_period > 0.5:
            raise ConfigError(
                f"gains.damping_rate + gains.boundary_rate = "
                f"{self.gains.damping_rate + self.gains.boundary_rate:g} 1/s with "
                f"lhs_period = {self.lhs_period:g} s; allowed: their sum * lhs_period "
                "<= 0.5 (the sampled sliding-mode loop stays well damped)")
        require_nonnegative("gains.chi_model_based", self.gains.chi_model_based, "N m")
        validate_seed(self.seed)
        validate_phases(self.phases)
        validate_port_settings(self, num_joints, lambda key: f"{key}_period")
        validate_simulator_config(self.simulator)
        require_finite_numbers("", self)
