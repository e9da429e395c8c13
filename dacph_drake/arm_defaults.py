"""The scenario of an arm from its own description (scenario.DescribedArm), or of a
planar arm of other than the paper's two links (scenario.PlanarArm), with every
per-joint setting sized to the arm, so that a scenario naming only the robot (and
q0) runs DAC (scenario files: scenario_files.load_scenario starts from it; Python:
arm_scenario, planar_arm_scenario).

The rule. Two scales per joint j, from the description at q0 and the task's
reference:

    M_j = M_jj(q0)      the joint's inertia in the reduced model (docs/equations.md
                        E5-E9: base free, zero momentum) [kg m^2]
    w   = 2 pi a / T    the reference's peak angular rate (task.reference amplitude
                        a, at least MIN_AMPLITUDE, period T) [rad/s];
                        p_j = M_j w, the joint's momentum turning at that rate
                        [kg m^2/s]; tau_j = M_j w 2 pi / T, its inertial torque at
                        the reference's peak acceleration [N m]

and the ground truth's RHS of the paper's form (eq. 19, scenario.Uncertainty) sized
by them, with signs alternating over the joints as the paper's two:

    B0_j = 1,  D0_j = DAMPING_RATE M_j
    D_offset_j = 0.25 D0_j,  D_linear_j = 0.25 D0_j / p_j,  D_quadratic_j = -+0.1 D0_j / p_j^2
        (the linear group adds 0.5 D0_j at p_j, the nonlinear one -+0.1 D0_j)
    B_linear: the paper's 2x2 block [[-0.1, 0], [0.05, 0.15]] on each pair of joints
        [1/rad];  B_quadratic_j = +-0.1 / p_j^2;  B_q1_squared: the paper's
        [[0, -0.1], [0.4, 0]] between joints 1 and 2
    d: lf_offset_j = +-0.3 tau_j, lf_amplitude_j = 0.2 tau_j, lf_frequency_j =
        0.05 + 0.01 j Hz, hf_amplitude = 0.05 max_j tau_j along hf_direction_j =
        +-tau_j / max_k tau_k (at the paper's 20 Hz)

The other sections are those of the shipped spatial scenarios (satellite_6dof):
scenario.SATELLITE_PHASES, described_arm_periods, described_arm_rhs and
described_arm_learner. A planar arm's are the paper's (Scenario's defaults); its
reference alpha_d = sum_i a_i sin(2 pi t / T_i) gives w = sum_i 2 pi a_i / T_i and
the peak acceleration sum_i a_i (2 pi / T_i)^2 (tau_j = M_j times it), M_j from the
true arm."""
import copy
from typing import TYPE_CHECKING, Optional, Sequence

import numpy as np

from dacph_drake.scenario import (SATELLITE_PHASES, DescribedArm, Disturbance,
                                  EndEffectorAngle, EndEffectorAttitude, Phases,
                                  PlanarArm, Scenario, Uncertainty,
                                  described_arm_learner, described_arm_periods,
                                  described_arm_rhs)

if TYPE_CHECKING:
    from dacph_drake.dynamics.floating_model import FloatingBaseModel
    from dacph_drake.dynamics.reduced_model import ReducedOrderModel

# [1/s] the planar LHS damping's largest rate Kd / inf_q lambda_min(M), 0.5 per 1 ms
# LHS period (the paper's arm: 0.5 N m s / 0.0051 kg m^2 = 98 1/s). At 2 per period
# (8 tapering links at Kd = 0.5) the sampled sliding mode grows 3.5x a period.
LHS_DAMPING_RATE = 500.0
DAMPING_RATE = 2.0              # [1/s] D0_j / M_j: a free joint's speed decays over 0.5 s
MIN_AMPLITUDE = 0.1             # [rad] the amplitude the scales assume for a still reference


def arm_scenario(robot: DescribedArm, q0: Optional[Sequence[float]] = None,
                 task: Optional[EndEffectorAttitude] = None) -> Scenario:
    """The scenario of an arm, its per-joint settings sized by the module's rule.

    Args:
        robot: The arm's robot section.
        q0: The initial joint angles [rad] (default: every joint at 0, or at the
            middle of its limits where 0 lies outside them).
        task: The task it tracks (default EndEffectorAttitude()).

    Returns:
        The scenario (unsized where q0 does not have one entry per joint: its
            validation names q0's length).

    Raises:
        ConfigError: The robot section's assembly settings are invalid
            (DescribedArm.ValidateAssembly) or its description cannot be
            loaded."""
    from dacph_drake.dynamics.floating_model import FloatingBaseModel
    from dacph_drake.robots.described import require_every_joint_moves_inertia
    from dacph_drake.robots.description import MakeRobotPlant
    robot.ValidateAssembly()
    model = FloatingBaseModel(MakeRobotPlant(robot))
    require_every_joint_moves_inertia(model, robot.description)
    q0 = np.asarray(rest_configuration(model) if q0 is None else q0, float)
    task = EndEffectorAttitude() if task is None else task
    scenario = Scenario(robot=robot, task=task, q0=[float(x) for x in q0],
                        phases=Phases(**SATELLITE_PHASES), rhs=described_arm_rhs(),
                        periods=described_arm_periods(), learner=described_arm_learner())
    if len(q0) != model.num_joints:
        return scenario         # Validate names q0's length; nothing to size by
    reference = task.reference
    rate = 2 * np.pi * max(reference.amplitude, MIN_AMPLITUDE) / reference.period
    inertia = np.diag(model.MassMatrix(q0))
    scenario.uncertainty = sized_uncertainty(inertia, rate)
    scenario.disturbance = sized_disturbance(inertia * rate * 2 * np.pi / reference.period)
    return scenario


def planar_arm_scenario(robot: PlanarArm, q0: Optional[Sequence[float]] = None,
                        task: Optional[EndEffectorAngle] = None) -> Scenario:
    """The scenario of a planar arm of any number of links, sized by the module's
    rule: its uncertainty and disturbance from the true arm's joint inertias at q0
    and the reference's rates; without a task, the LHS damping K_d = Kd I at most
    LHS_DAMPING_RATE inf_q lambda_min(M), so that the sampled LHS loop stays well
    damped on an arm with light distal links; periods.rhs shortened where the gain
    rule asks for it (rhs_period: c grows as Kd / inf lambda_min).

    Args:
        robot: The robot section; the defaults' nominal arm is a copy of its truth
            (a file that names robot.nominal overrides it).
        q0: The start (default: the paper's q1 = 0.3 rad and its elbow's 1 rad
            spread evenly over the other joints).
        task: The task (default EndEffectorAngle(): the paper's reference and gains).

    Returns:
        The scenario (the paper's phases, periods, RHS and learner settings)."""
    from dacph_drake.dynamics.plant import MakeArmPlant
    from dacph_drake.dynamics.reduced_model import ReducedOrderModel, mass_matrix_bounds
    n = robot.truth.num_links
    robot = copy.deepcopy(robot)
    robot.nominal = copy.deepcopy(robot.truth)
    robot.Validate()            # names a bad link before its plant is built
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
    scenario.uncertainty = sized_uncertainty(inertia, rate)
    scenario.disturbance = sized_disturbance(inertia * acceleration)
    scenario.periods.rhs = rhs_period(scenario, nominal)
    return scenario


def rhs_period(scenario: Scenario, nominal: "ReducedOrderModel") -> float:
    """The scenario's periods.rhs, or a shorter one where the gain rule asks for it.

    The RHS loop's largest rate c = (1 + rhs.c_margin) c_min(rhs.beta_max) (eq. 48)
    grows as 1 / inf_q lambda_min(M): an arm with light distal links needs a
    faster loop than the paper's (gain_rule.check_rhs_period: periods.rhs <=
    1 / (4 c)). The period returned divides periods.lhs evenly.

    Args:
        scenario: The scenario (its rhs settings, task.gains.Kd and periods).
        nominal: The controller's model of the arm (mass_matrix_bounds).

    Returns:
        periods.rhs [s]."""
    from dacph_drake.dynamics.reduced_model import mass_matrix_bounds
    from dacph_drake.gain_rule import WELL_DAMPED_LOOP_GAIN, c_lower_bound
    rhs, periods = scenario.rhs, scenario.periods
    largest = (1 + rhs.c_margin) * c_lower_bound(
        rhs.Td, scenario.task.gains.Kd, mass_matrix_bounds(nominal)[0], rhs.beta_max)
    bound = WELL_DAMPED_LOOP_GAIN / largest
    if periods.rhs <= bound:
        return periods.rhs
    return periods.lhs / int(np.ceil(periods.lhs / bound))


def rest_configuration(model: "FloatingBaseModel") -> np.ndarray:
    """The arm's rest configuration.

    Args:
        model: The arm's model.

    Returns:
        q [rad]: every joint at 0, or at the middle of its position limits where 0
            lies outside them."""
    plant, q = model.plant, np.zeros(model.num_joints)
    lower = plant.GetPositionLowerLimits()[model.coordinates.joint_q]
    upper = plant.GetPositionUpperLimits()[model.coordinates.joint_q]
    outside = (lower > 0) | (upper < 0)
    q[outside] = 0.5 * (lower[outside] + upper[outside])
    return q


def _alternating(n: int, first: float = 1.0) -> np.ndarray:
    return first * (-1.0) ** np.arange(n)


def sized_uncertainty(inertia: np.ndarray, rate: float) -> Uncertainty:
    """The ground truth's RHS sized to the joints (module docstring).

    Args:
        inertia: The joints' inertias M_j [kg m^2].
        rate: The reference's peak angular rate w [rad/s].

    Returns:
        The Uncertainty section."""
    n = len(inertia)
    D0 = DAMPING_RATE * inertia
    p = inertia * rate
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
    """The disturbance d(t) sized to the joints (module docstring).

    Args:
        torque: The joints' inertial torques tau_j at the reference's peak
            acceleration [N m].

    Returns:
        The Disturbance section."""
    n, largest = len(torque), float(np.max(torque))
    return Disturbance(
        lf_offset=(_alternating(n, 0.3) * torque).tolist(),
        lf_amplitude=(0.2 * torque).tolist(),
        lf_frequency=(0.05 + 0.01 * np.arange(n)).tolist(),
        hf_amplitude=0.05 * largest,
        hf_direction=(_alternating(n) * torque / largest).tolist())
