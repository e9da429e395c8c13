"""The rule that sizes every per-joint setting of a scenario to its arm, so that a scenario
naming only the robot (and q0) runs DAC (each robot kind's SizedScenario applies it).
Per joint j, from the description at q0 and the task's reference:

    M_j = M_jj(q0)                                the reduced model's inertia [kg m^2]
    w   = 2 pi a / T                              peak reference rate, a >= MIN_AMPLITUDE
    p_j = max(M_j w, max_t |p_j(t)|)              momentum [kg m^2/s]
    tau_j = max(M_j w 2 pi / T, max_t |dp_j/dt|)  inertial torque past the warm-up [N m]

with p(t) = M(q) qdot along a kinematic rehearsal (robots.start_pose.rehearse), as the
coupling M_jk qdot_k drives a light joint far beyond M_j w. The truth's RHS (eq. 19),
signs alternating as the paper's:

    B0_j = 1,  D0_j = DAMPING_RATE M_j
    D_offset_j = 0.25 D0_j,  D_linear_j = 0.25 D0_j / p_j,  D_quadratic_j = -+0.1 D0_j / p_j^2
    B_linear: the paper's 2x2 block [[-0.1, 0], [0.05, 0.15]] on each pair of joints
        [1/rad];  B_quadratic_j = +-0.1 / p_j^2;  B_q1_squared: the paper's
        [[0, -0.1], [0.4, 0]] between joints 1 and 2
    d: lf_offset_j = +-0.3 tau_j, lf_amplitude_j = 0.2 tau_j, lf_frequency_j =
        0.05 + 0.01 j Hz, hf_amplitude = 0.05 max_j tau_j along hf_direction_j =
        +-tau_j / max_k tau_k (at the paper's 20 Hz)

A described arm adds B_q1_squared over the largest q1^2 > 1 rad^2, scale_couplings,
disturbance_scale, excitation_scale, potential_margin and truth_step. A planar arm
(no rehearsal; M_j the true arm's): p_j = M_j w, w = sum_i 2 pi a_i / T_i, and tau_j =
M_j sum_i a_i (2 pi / T_i)^2."""
from typing import Optional

import numpy as np

from dacph_drake.dynamics.floating_model import FloatingBaseModel
from dacph_drake.dynamics.reduced_model import ReducedOrderModel, mass_matrix_bounds
from dacph_drake.gain_rule import WELL_DAMPED_LOOP_GAIN, c_lower_bound
from dacph_drake.kernels.loop import FRICTION_VELOCITY
from dacph_drake.scenario import Disturbance, Excitation, Scenario, Uncertainty

# [1/s] the planar LHS damping's largest rate Kd / inf_q lambda_min(M), 0.5 per 1 ms
# LHS period (the paper's arm: 0.5 N m s / 0.0051 kg m^2 = 98 1/s). At 2 per period
# (8 tapering links at Kd = 0.5) the sampled sliding mode grows 3.5x a period.
LHS_DAMPING_RATE = 500.0
DAMPING_RATE = 2.0              # [1/s] D0_j / M_j: a free joint's speed decays over 0.5 s
MIN_AMPLITUDE = 0.1             # [rad] the amplitude the scales assume for a still reference
DEFAULT_STEP = 2.5e-4           # [s] scenario.simulator.FixedStepConfig's
STEP_RATE_PRODUCT = 1.0         # h lambda of the fastest damping mode (RK2: stable to 2)
# [rad] the most a joint moves under the learner's excitation (half the 1e-4 rad
# tracking target; 2e-4 N m at 4.3 Hz move a 0.0067 kg m^2 wrist 4e-5 rad, a
# 4e-5 kg m^2 one 7e-3 rad).
EXCITATION_MOTION = 5e-5
DISTURBANCE_ACCELERATION = 5.0  # the most d accelerates a joint, per reference's peak


def scale_couplings(uncertainty: Uncertainty, torque: np.ndarray) -> None:
    """Multiplies B~'s off-diagonal entries (j, k) (B_linear, B_q1_squared) by
    min(1, tau_j / tau_k), so that a heavy joint's actuator leaks into a light one at most
    the paper's fraction of the light joint's own torque.

    Args:
        uncertainty: The sized uncertainty (changed in place).
        torque: The joints' torque scales tau_j [N m]."""
    torque = np.asarray(torque, float)
    ratio = np.minimum(1.0, torque[:, None] / torque[None, :])
    np.fill_diagonal(ratio, 1.0)
    uncertainty.B_linear = (np.asarray(uncertainty.B_linear) * ratio).tolist()
    uncertainty.B_q1_squared = (np.asarray(uncertainty.B_q1_squared) * ratio).tolist()


def potential_margin(margin: float, clearance: float) -> float:
    """The clearance potential's margin [m]: at most half the start's link-base clearance
    (unchanged for a start inside the base, which validation refuses), so that a link
    always near the base does not keep the potential pushing through the whole run.

    Args:
        margin: The margin otherwise (robot.potential.margin) [m].
        clearance: The start's link-base clearance [m] (inf: beyond the query)."""
    return min(margin, 0.5 * clearance) if clearance > 0 else margin


def disturbance_scale(disturbance: Disturbance, M: np.ndarray,
                      acceleration: float) -> float:
    """disturbance.scale = min(1, DISTURBANCE_ACCELERATION acceleration / max_i
    sum_j |(M^-1)_ij| d_j), d_j = |lf_offset_j| + lf_amplitude_j + hf_amplitude
    |hf_direction_j| the peak of d_j.

    Args:
        disturbance: The sized disturbance (its factor not yet applied).
        M: The reduced mass matrix at the start [kg m^2] (n x n).
        acceleration: The reference's peak angular acceleration [rad/s^2]."""
    peak = (np.abs(disturbance.lf_offset) + np.abs(disturbance.lf_amplitude)
            + disturbance.hf_amplitude * np.abs(disturbance.hf_direction))
    reach = float(np.max(np.abs(np.linalg.inv(M)) @ peak))
    limit = DISTURBANCE_ACCELERATION * acceleration
    return 1.0 if reach <= limit else limit / reach


def excitation_scale(excitation: Excitation, M: np.ndarray) -> list:
    """excitation.joint_scale: min(1, EXCITATION_MOTION omega_j^2 / (amplitude
    max_i |(M^-1)_ij|)) per joint (None where all are 1), as a_j sin(omega_j t) on joint j
    moves joint i by about |(M^-1)_ij| a_j / omega_j^2.

    Args:
        excitation: The excitation (its amplitude and frequencies).
        M: The reduced mass matrix at the start [kg m^2] (n x n)."""
    if excitation.amplitude <= 0:
        return []
    omega = 2 * np.pi * excitation.Frequencies(len(M))
    reach = np.max(np.abs(np.linalg.inv(M)), axis=0)
    scale = np.minimum(1.0, omega**2 * EXCITATION_MOTION / (excitation.amplitude * reach))
    return [] if np.all(scale >= 1.0) else [float(x) for x in scale]


def truth_step(model: FloatingBaseModel, configurations: np.ndarray,
               uncertainty: Uncertainty, rhs_period: float,
               friction: Optional[np.ndarray] = None) -> float:
    """The ground truth's fixed RK2 step [s]: h lambda <= STEP_RATE_PRODUCT (RK2 is stable
    to 2) for the fastest mode, the largest generalized eigenvalue of (D, M(q)) over the
    configurations, D the joint damping plus 1.5 D0 (D0, D_offset, D_linear at p_j) and f /
    FRICTION_VELOCITY; at most DEFAULT_STEP, dividing the RHS period, at least 1e-7 s.

    Args:
        model: The arm's model (its plant's joint damping).
        configurations: Joint angles to take the largest rate over (k x n) [rad].
        uncertainty: The sized RHS (D0 and its offset).
        rhs_period: periods.rhs [s].
        friction: The joints' Coulomb friction f (n) [N m] (None: none)."""
    damping = model.joint_damping + 1.5 * np.asarray(uncertainty.D0, float)
    if friction is not None:
        damping = damping + np.asarray(friction, float) / FRICTION_VELOCITY
    rate = 0.0
    for q in configurations[::max(len(configurations) // 16, 1)]:
        M = model.MassMatrix(q)
        L = np.linalg.cholesky(M)
        Linv = np.linalg.inv(L)
        rate = max(rate, float(np.max(np.linalg.eigvalsh(
            Linv @ np.diag(damping) @ Linv.T))))
    step = min(DEFAULT_STEP, STEP_RATE_PRODUCT / rate) if rate > 0 else DEFAULT_STEP
    # Never below what simulator.max_step_size allows: a description that asks for
    # less is refused at the build, naming its joint (DescribedRobot).
    return max(rhs_period / int(np.ceil(rhs_period / step - 1e-9)), 1e-7)


def rhs_period(scenario: Scenario, nominal: ReducedOrderModel) -> float:
    """periods.rhs [s], or a shorter one dividing periods.lhs where the RHS loop's largest
    rate c = (1 + rhs.c_margin) c_min(rhs.beta_max) (eq. 48) asks for h <= 1 / (4 c).

    Args:
        scenario: The scenario (its rhs settings, task.gains.Kd and periods).
        nominal: The controller's model of the arm (mass_matrix_bounds)."""
    rhs, periods = scenario.rhs, scenario.periods
    largest = (1 + rhs.c_margin) * c_lower_bound(
        rhs.Td, scenario.task.gains.Kd, mass_matrix_bounds(nominal)[0], rhs.beta_max)
    bound = WELL_DAMPED_LOOP_GAIN / largest
    if periods.rhs <= bound:
        return periods.rhs
    return periods.lhs / int(np.ceil(periods.lhs / bound))


def _alternating(n: int, first: float = 1.0) -> np.ndarray:
    return first * (-1.0) ** np.arange(n)


def sized_uncertainty(inertia: np.ndarray, momentum: np.ndarray) -> Uncertainty:
    """The ground truth's RHS (Uncertainty section) sized to the joints (module docstring).

    Args:
        inertia: The joints' inertias M_j [kg m^2].
        momentum: The joints' momentum scales p_j [kg m^2/s]."""
    n = len(inertia)
    D0 = DAMPING_RATE * inertia
    p = np.asarray(momentum, float)
    block = np.array([[-0.1, 0.0], [0.05, 0.15]])
    B_linear = np.zeros((n, n))
    for k in range(0, n - 1, 2):
        B_linear[k:k + 2, k:k + 2] = block
    if n % 2:
        B_linear[n - 1, n - 1] = block[0, 0]
    coupling = np.zeros((n, n))
    coupling[:2, :2] = np.array([[0.0, -0.1], [0.4, 0.0]])[:n, :n]
    return Uncertainty(
        B0=[1.0] * n, D0=D0.tolist(), D_offset=(0.25 * D0).tolist(),
        D_linear=(0.25 * D0 / p).tolist(),
        D_quadratic=(_alternating(n, -0.1) * D0 / p**2).tolist(),
        B_linear=B_linear.tolist(), B_quadratic=(_alternating(n, 0.1) / p**2).tolist(),
        B_q1_squared=coupling.tolist())


def sized_disturbance(torque: np.ndarray) -> Disturbance:
    """The disturbance d(t) (Disturbance section) sized to the joints (module docstring).

    Args:
        torque: The joints' inertial torques tau_j at the reference's peak [N m]."""
    n, largest = len(torque), float(np.max(torque))
    return Disturbance(
        lf_offset=(_alternating(n, 0.3) * torque).tolist(),
        lf_amplitude=(0.2 * torque).tolist(),
        lf_frequency=(0.05 + 0.01 * np.arange(n)).tolist(),
        hf_amplitude=0.05 * largest,
        hf_direction=(_alternating(n) * torque / largest).tolist())
