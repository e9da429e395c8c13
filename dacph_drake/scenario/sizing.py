"""The scenario of an arm from its own description (scenario.DescribedArm), or of a
planar arm of other than the paper's two links (scenario.PlanarArm), with every
per-joint setting sized to the arm, so that a scenario naming only the robot (and
q0) runs DAC (scenario files: scenario.files.load_scenario starts from it; Python:
arm_scenario, planar_arm_scenario).

The rule. Scales per joint j, from the description at q0 and the task's reference:

    M_j = M_jj(q0)      the joint's inertia in the reduced model (docs/equations.md
                        E5-E9: base free, zero momentum) [kg m^2]
    w   = 2 pi a / T    the reference's peak angular rate (task.reference amplitude
                        a, at least MIN_AMPLITUDE, period T) [rad/s];
    p_j = max(M_j w, max_t |p_j(t)|)            the joint's momentum [kg m^2/s]
    tau_j = max(M_j w 2 pi / T, max_t |dp_j/dt|)  its inertial torque [N m]
                        (t past the warm-up, when the uncertainty starts)

with p(t) = M(q) qdot along a kinematic rehearsal of the task from q0 for the
warm-up and one reference period (robots.start_pose.rehearse; a planar arm: M_j w
and M_j times the peak acceleration): the coupling M_jk qdot_k drives a light
joint's momentum far beyond M_j w, where the quadratic terms below would take its
true actuator gain through zero; and the ground truth's RHS of the paper's form
(eq. 19, scenario.Uncertainty) sized by them, signs alternating as the paper's two:

    B0_j = 1,  D0_j = DAMPING_RATE M_j
    D_offset_j = 0.25 D0_j,  D_linear_j = 0.25 D0_j / p_j,  D_quadratic_j = -+0.1 D0_j / p_j^2
        (the linear group adds 0.5 D0_j at p_j, the nonlinear one -+0.1 D0_j)
    B_linear: the paper's 2x2 block [[-0.1, 0], [0.05, 0.15]] on each pair of joints
        [1/rad];  B_quadratic_j = +-0.1 / p_j^2;  B_q1_squared: the paper's
        [[0, -0.1], [0.4, 0]] between joints 1 and 2
    d: lf_offset_j = +-0.3 tau_j, lf_amplitude_j = 0.2 tau_j, lf_frequency_j =
        0.05 + 0.01 j Hz, hf_amplitude = 0.05 max_j tau_j along hf_direction_j =
        +-tau_j / max_k tau_k (at the paper's 20 Hz)

For a described arm, five factors on top: B_q1_squared is divided by the largest
q1^2 past the warm-up where that exceeds 1 rad^2 (the paper's arm keeps |q1| <= 1
rad); B~'s couplings (j, k) are multiplied by min(1, tau_j / tau_k)
(scale_couplings); d's scale keeps the accelerations it causes through M^-1 within
DISTURBANCE_ACCELERATION times the reference's (disturbance_scale); the excitation's
per-joint scale keeps the motion it causes within EXCITATION_MOTION
(excitation_scale); the clearance potential's margin is at most half the start's
clearance (potential_margin). The ground truth's fixed RK2 step is the largest that
keeps h lambda <= 1 for the fastest damping mode (truth_step). A described arm's q0,
when the file gives none, is robots.start_pose.choose_start's; its other sections
are the shipped spatial scenarios' (satellite_6dof: scenario.SATELLITE_PHASES,
described_arm_periods, described_arm_rhs, described_arm_learner). A planar arm's are
the paper's (Scenario's defaults); its reference alpha_d = sum_i a_i sin(2 pi t / T_i)
gives w = sum_i 2 pi a_i / T_i and the peak acceleration sum_i a_i (2 pi / T_i)^2
(tau_j = M_j times it), M_j from the true arm."""
import copy
from typing import TYPE_CHECKING, Optional, Sequence, Union

import numpy as np

from dacph_drake.errors import require_positive
from dacph_drake.scenario.planar_arm import RobotParams
from dacph_drake.scenario.simulator import FixedStepConfig
from dacph_drake.scenario import (DescribedArm, Disturbance, EndEffectorAngle,
                                  EndEffectorAttitude, Excitation, Phases, PlanarArm,
                                  Scenario, Uncertainty)
from dacph_drake.scenario.built_in import (SATELLITE_PHASES, described_arm_learner,
                                           described_arm_periods, described_arm_rhs)

if TYPE_CHECKING:
    from dacph_drake.dynamics.floating_model import FloatingBaseModel
    from dacph_drake.dynamics.reduced_model import ReducedOrderModel

# [1/s] the planar LHS damping's largest rate Kd / inf_q lambda_min(M), 0.5 per 1 ms
# LHS period (the paper's arm: 0.5 N m s / 0.0051 kg m^2 = 98 1/s). At 2 per period
# (8 tapering links at Kd = 0.5) the sampled sliding mode grows 3.5x a period.
LHS_DAMPING_RATE = 500.0
DAMPING_RATE = 2.0              # [1/s] D0_j / M_j: a free joint's speed decays over 0.5 s
MIN_AMPLITUDE = 0.1             # [rad] the amplitude the scales assume for a still reference
DEFAULT_STEP = 2.5e-4           # [s] loop.simulator.FixedStepConfig's
STEP_RATE_PRODUCT = 1.0         # h lambda of the fastest damping mode (RK2: stable to 2)
# [rad] the most a joint moves under the learner's excitation (half the 1e-4 rad
# tracking target; 2e-4 N m at 4.3 Hz move a 0.0067 kg m^2 wrist 4e-5 rad, a
# 4e-5 kg m^2 one 7e-3 rad).
EXCITATION_MOTION = 5e-5
DISTURBANCE_ACCELERATION = 5.0  # the most d accelerates a joint, per reference's peak


def arm_scenario(robot: DescribedArm, q0: Optional[Sequence[float]] = None,
                 task: Optional[EndEffectorAttitude] = None) -> Scenario:
    """The scenario of an arm, its per-joint settings sized by the module's rule
    (unsized where q0 has not one entry per joint: its validation names q0's length).

    Args:
        robot: The arm's robot section.
        q0: The initial joint angles [rad] (default: robots.start_pose.choose_start).
        task: The task it tracks (default EndEffectorAttitude()).

    Raises:
        ConfigError: Bad assembly settings, an unloadable description, no start found."""
    from dacph_drake.dynamics.floating_model import FloatingBaseModel
    from dacph_drake.errors import ConfigError
    from dacph_drake.robots.described import (joint_friction, link_base_clearance,
                                              null_space_rate,
                                              require_every_joint_moves_inertia)
    from dacph_drake.robots.description import ParsedDescription
    from dacph_drake.robots.described import validate_assembly
    from dacph_drake.robots.start_pose import choose_start, rehearse, tracked
    validate_assembly(robot)
    parsed = ParsedDescription(robot)
    model = FloatingBaseModel(parsed.plant)
    require_every_joint_moves_inertia(model, robot.description)
    from dacph_drake.tasks.registry import TASKS
    task = EndEffectorAttitude() if task is None else task
    rows = TASKS[type(task)].jacobian_rows
    # The reference sizes the arm: its attitude's, or (a position task) its position's.
    reference = getattr(task, "reference", None) or task.position
    rehearsal_time = SATELLITE_PHASES["warmup"] + reference.period
    clearance = link_base_clearance(parsed, model)     # one SceneGraph context
    if q0 is None:
        try:
            q0 = choose_start(model, task, clearance,
                              null_space_rate(parsed, model, robot.potential),
                              rehearsal_time, rows)
        except ValueError as e:
            what = tracked(rows)
            how = {"attitude": "turn about every axis",
                   "position": "move in every direction"}.get(
                what, "turn about every axis and move in every direction")
            raise ConfigError(
                f"robot.description {robot.description!r}: no start pose found for "
                f"the end-effector {what} task ({e}); allowed: a q0 in the file, or "
                f"an arm whose end effector can {how}") from e
    q0 = np.asarray(q0, float)
    robot = copy.deepcopy(robot)
    if len(q0) == model.num_joints:
        robot.potential.margin = potential_margin(robot.potential.margin,
                                                  clearance(q0))
    scenario = Scenario(robot=robot, task=task, q0=[float(x) for x in q0],
                        phases=Phases(**SATELLITE_PHASES), rhs=described_arm_rhs(),
                        periods=described_arm_periods(), learner=described_arm_learner())
    if len(q0) != model.num_joints:
        return scenario         # Validate names q0's length; nothing to size by
    rate = 2 * np.pi * max(_reference_angle(model, q0, task), MIN_AMPLITUDE) \
        / reference.period
    M = model.MassMatrix(q0)
    inertia = np.diag(M)
    rehearsal = rehearse(model, q0, task, rehearsal_time)
    # Past the warm-up: the uncertainty and the disturbance act from phase 1 on, when
    # the start's error has decayed (the rehearsal also starts with a jump in p).
    steady = rehearsal.time >= SATELLITE_PHASES["warmup"]
    momentum = np.maximum(inertia * rate, np.max(np.abs(rehearsal.p[steady]), axis=0))
    torque = np.maximum(inertia * rate * 2 * np.pi / reference.period,
                        np.max(np.abs(rehearsal.p_rate[steady]), axis=0))
    scenario.uncertainty = sized_uncertainty(inertia, momentum)
    # The paper's q1^2 coupling at the angles the task reaches: at most its size at
    # |q1| = 1 rad (the paper's arm stays within it). From a start at q1 = 2.9 rad
    # (a UR5's chosen start) it would put 3.5 of joint 1's command into joint 2's
    # torque, and the true RHS loop lost its margin (spectral radius 0.97 > 0.95).
    reach = float(np.max(rehearsal.q[steady, 0] ** 2))
    if reach > 1.0:
        scenario.uncertainty.B_q1_squared = (
            np.asarray(scenario.uncertainty.B_q1_squared) / reach).tolist()
    scale_couplings(scenario.uncertainty, torque)
    scenario.disturbance = sized_disturbance(torque)
    scenario.disturbance.scale = disturbance_scale(
        scenario.disturbance, M, rate * 2 * np.pi / reference.period)
    scenario.excitation.joint_scale = excitation_scale(scenario.excitation, M)
    scenario.simulator = FixedStepConfig(step=truth_step(
        model, rehearsal.q, scenario.uncertainty, scenario.periods.rhs,
        joint_friction(parsed, model)))
    return scenario


def scale_couplings(uncertainty: Uncertainty, torque: np.ndarray) -> None:
    """Scales the true actuators' couplings to the joint they act on: B~'s off-diagonal
    entry (j, k) (B_linear and B_q1_squared) puts a fraction of actuator k's command
    u_k ~ tau_k into joint j (the paper's 0.05 to 0.4, between joints of similar size);
    each is multiplied by min(1, tau_j / tau_k), so that a heavy joint's actuator leaks
    into a light one at most that fraction of the light joint's own torque (unscaled,
    its true RHS may no longer be dominated by its own actuator).

    Args:
        uncertainty: The sized uncertainty (changed in place).
        torque: The joints' torque scales tau_j [N m]."""
    torque = np.asarray(torque, float)
    ratio = np.minimum(1.0, torque[:, None] / torque[None, :])
    np.fill_diagonal(ratio, 1.0)
    uncertainty.B_linear = (np.asarray(uncertainty.B_linear) * ratio).tolist()
    uncertainty.B_q1_squared = (np.asarray(uncertainty.B_q1_squared) * ratio).tolist()


def potential_margin(margin: float, clearance: float) -> float:
    """The clearance potential's margin [m] for a start's link-base clearance: at most
    half of it (unchanged for a start inside the base, which validation refuses). A
    link that always stays near the base (a UR arm's shoulder) otherwise keeps the
    potential pushing through the whole run, its gradient jumping as the nearest mesh
    features change.

    Args:
        margin: The margin otherwise (robot.potential.margin) [m].
        clearance: The start's link-base clearance [m] (inf: beyond the query)."""
    return min(margin, 0.5 * clearance) if clearance > 0 else margin


def disturbance_scale(disturbance: Disturbance, M: np.ndarray,
                      acceleration: float) -> float:
    """disturbance.scale = min(1, DISTURBANCE_ACCELERATION acceleration / max_i
    sum_j |(M^-1)_ij| d_j): it keeps the accelerations the disturbance causes within
    DISTURBANCE_ACCELERATION times the reference's peak, as d_j's peak |lf_offset_j| +
    lf_amplitude_j + hf_amplitude |hf_direction_j| accelerates joint i by up to
    sum_j |(M^-1)_ij| d_j (on arms whose light joints are coupled to heavy ones: a tiny
    wrist, a chain of nine joints, a heavy tool).

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
    """excitation.joint_scale: each factor min(1, EXCITATION_MOTION omega_j^2 /
    (amplitude max_i |(M^-1)_ij|)), or none where every factor is 1, so that every
    joint's motion under the excitation is at most EXCITATION_MOTION: the request
    a_j sin(omega_j t) on joint j moves joint i by about |(M^-1)_ij| a_j / omega_j^2.

    Args:
        excitation: The excitation (its amplitude and frequencies).
        M: The reduced mass matrix at the start [kg m^2] (n x n)."""
    if excitation.amplitude <= 0:
        return []
    omega = 2 * np.pi * excitation.Frequencies(len(M))
    reach = np.max(np.abs(np.linalg.inv(M)), axis=0)
    scale = np.minimum(1.0, omega**2 * EXCITATION_MOTION / (excitation.amplitude * reach))
    return [] if np.all(scale >= 1.0) else [float(x) for x in scale]


def truth_step(model: "FloatingBaseModel", configurations: np.ndarray,
               uncertainty: Uncertainty, rhs_period: float,
               friction: Optional[np.ndarray] = None) -> float:
    """The ground truth's fixed RK2 step [s] for an arm's fastest damping mode.

    The explicit scheme is stable for a mode decaying at rate lambda while
    h lambda <= 2; the step keeps h lambda <= STEP_RATE_PRODUCT for the fastest
    mode, the largest generalized eigenvalue of (D, M(q)) with D the description's
    joint damping plus D0, D_offset and D_linear at the sized momentum and the joint
    friction's steepest slope f / FRICTION_VELOCITY (kernels.loop.add_friction), over
    the configurations given. At most the default step (loop.simulator), and
    dividing the RHS period evenly (the discrete updates stop the integrator at
    every RHS sample anyway); at least 1e-7 s (simulator.max_step_size's lower
    bound).

    Args:
        model: The arm's model (its plant's joint damping).
        configurations: Joint angles to take the largest rate over (k x n) [rad].
        uncertainty: The sized RHS (D0 and its offset).
        rhs_period: periods.rhs [s].
        friction: The joints' Coulomb friction f (n) [N m] (None: none)."""
    from dacph_drake.kernels.loop import FRICTION_VELOCITY
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


def planar_arm_scenario(robot: PlanarArm, q0: Optional[Sequence[float]] = None,
                        task: Optional[EndEffectorAngle] = None) -> Scenario:
    """The scenario of a planar arm of any number of links, sized by the module's
    rule: its uncertainty and disturbance from the true arm's joint inertias at q0
    and the reference's rates; without a task, the LHS damping K_d = Kd I at most
    LHS_DAMPING_RATE inf_q lambda_min(M), so that the sampled LHS loop stays well
    damped on an arm with light distal links; periods.rhs shortened where the gain
    rule asks for it (rhs_period: c grows as Kd / inf lambda_min); the paper's phases,
    periods, RHS and learner settings.

    Args:
        robot: The robot section (the defaults' nominal arm: a copy of its truth).
        q0: The start (default: the paper's q1 = 0.3 rad, its elbow's 1 rad spread evenly).
        task: The task (default EndEffectorAngle(): the paper's reference and gains)."""
    from dacph_drake.dynamics.plant import MakeArmPlant
    from dacph_drake.robots.planar import validate_planar_arm
    from dacph_drake.dynamics.reduced_model import ReducedOrderModel, mass_matrix_bounds
    n = robot.truth.num_links
    robot = copy.deepcopy(robot)
    robot.nominal = copy.deepcopy(robot.truth)
    validate_planar_arm(robot)  # names a bad link before its plant is built
    nominal = ReducedOrderModel(MakeArmPlant(robot.nominal))
    if task is None:
        task = EndEffectorAngle()
        task.gains.Kd = min(task.gains.Kd,
                            LHS_DAMPING_RATE * mass_matrix_bounds(nominal)[0])
    q0 = np.asarray([0.3] + [1.0 / max(n - 1, 1)] * (n - 1) if q0 is None else q0,
                    float)
    scenario = Scenario(robot=robot, task=task, q0=[float(x) for x in q0])
    if len(q0) != n:
        return scenario         # Validate names q0's length; nothing to size by
    reference = task.reference
    amplitudes = np.maximum(np.asarray(reference.amplitudes, float), 0.0)
    periods = np.asarray(reference.periods, float)
    if not (len(periods) and np.all(periods > 0) and len(amplitudes) == len(periods)):
        return scenario         # Validate names the reference's problem
    if not np.any(amplitudes > 0):
        amplitudes = np.full_like(periods, MIN_AMPLITUDE / len(periods))
    rate = float(np.sum(2 * np.pi * amplitudes / periods))
    acceleration = float(np.sum(amplitudes * (2 * np.pi / periods) ** 2))
    inertia = np.diag(nominal.MassMatrix(q0))   # the defaults' nominal is the truth
    scenario.uncertainty = sized_uncertainty(inertia, inertia * rate)
    scenario.disturbance = sized_disturbance(inertia * acceleration)
    scenario.periods.rhs = rhs_period(scenario, nominal)
    return scenario


def rhs_period(scenario: Scenario, nominal: "ReducedOrderModel") -> float:
    """The scenario's periods.rhs [s], or a shorter one where the gain rule asks for it.

    The RHS loop's largest rate c = (1 + rhs.c_margin) c_min(rhs.beta_max) (eq. 48)
    grows as 1 / inf_q lambda_min(M): an arm with light distal links needs a
    faster loop than the paper's (gain_rule.check_rhs_period: periods.rhs <=
    1 / (4 c)). The period returned divides periods.lhs evenly.

    Args:
        scenario: The scenario (its rhs settings, task.gains.Kd and periods).
        nominal: The controller's model of the arm (mass_matrix_bounds)."""
    from dacph_drake.dynamics.reduced_model import mass_matrix_bounds
    from dacph_drake.gain_rule import WELL_DAMPED_LOOP_GAIN, c_lower_bound
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


def sized_defaults(robot: Union[PlanarArm, DescribedArm], q0: Optional[Sequence[float]],
                   task: Optional[object]) -> Optional[Scenario]:
    """The scenario a file naming this robot starts from: every per-joint setting sized
    to the arm (planar_arm_scenario or arm_scenario), so that a file naming only the
    robot (and q0) runs; None for the paper's planar arm (Scenario's defaults).

    Args:
        robot: The file's robot section.
        q0: The file's q0 [rad] (None where it leaves it out).
        task: The file's task (None where it leaves it out)."""
    validate_given(q0, task)
    if isinstance(robot, DescribedArm):
        return arm_scenario(robot, q0, task)
    if robot.truth == RobotParams():
        return None
    return planar_arm_scenario(robot, q0, task)


def validate_given(q0: Optional[Sequence[float]], task: Optional[object]) -> None:
    """Checks what a file gives that sizing uses (the start and the task's reference)
    before any sizing, start-pose search or plant call reads it.

    Args:
        q0: The file's q0 [rad] (None where it leaves it out).
        task: The file's task (None where it leaves it out).

    Raises:
        ConfigError: Naming the first bad setting."""
    from dacph_drake.scenario.checks import validate_start
    from dacph_drake.tasks.registry import TASKS
    if q0 is not None:
        validate_start(q0)
    if task is not None and type(task) in TASKS:
        TASKS[type(task)].Validate(task, described_arm_periods())


def _reference_angle(model: "FloatingBaseModel", q0: np.ndarray, task) -> float:
    """The reference's amplitude as a joint angle [rad]: the attitude's; a position's
    [m] over the position rows' largest singular value at q0 [m/rad] (the longest
    lever the joints move the end effector by)."""
    if getattr(task, "reference", None) is not None:
        return task.reference.amplitude
    from dacph_drake.robots.start_pose import POSITION_ROWS, task_jacobian
    lever = np.linalg.svd(task_jacobian(model, q0, rows=POSITION_ROWS),
                          compute_uv=False)[0]
    return task.position.amplitude / max(lever, 1e-9)
