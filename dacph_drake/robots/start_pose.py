"""Where a described arm starts and what the attitude task asks of it: a kinematic
rehearsal (ReferenceRehearsal) follows qdot = D^+ (omega_d(t) - Lambda e) from q0
without dynamics, the base turning as zero momentum implies; its momenta p = M(q) qdot
and their rates size the gains (robots.sizing), its excursion checks limits."""
from dataclasses import dataclass
from typing import Callable, List, Optional, Sequence, Tuple

import numpy as np
from pydrake.common.eigen_geometry import AngleAxis
from pydrake.math import RotationMatrix
from pydrake.multibody.tree import Frame

from dacph_drake.dynamics.floating_model import FloatingBaseModel, arm_joints
from dacph_drake.dynamics.plant import END_EFFECTOR
from dacph_drake.scenario import EndEffectorAttitude
from dacph_drake.dynamics.attitude import (attitude_error, damped_pseudo_inverse,
                                        reference_at, reference_start)

# The smallest singular value of D (rad/s of the end effector per rad/s of the
# joints) a start must have: below it, one end-effector rate asks for joint rates
# 1 / SINGULAR_BOUND times larger. REFUSED_SINGULAR_VALUE: a given q0 closer than this
# to a singularity is refused.
SINGULAR_BOUND, REFUSED_SINGULAR_VALUE = 0.2, 0.02
# The same for the pose's 6 rows, whose linear rows are lever arms [m]: 5 cm (the
# shipped arms' wrists give their smallest singular value 0.06-0.18 at their starts).
POSE_BOUNDS = (0.05, 0.005)


# The same for the position's 3 linear rows alone, whose singular values are lever arms
# of any size: their smallest over their largest (the tool placed no worse than 20x
# slower in one direction than in the best), so that a 20 cm arm and a 2 m arm are
# judged alike.
POSITION_BOUNDS = (0.05, 0.005)
# The GJM's rows of the attitude task (its angular ones) and of the position task.
ATTITUDE_ROWS, POSITION_ROWS = (0, 1, 2), (3, 4, 5)


def singular_bounds(rows: Sequence[int]) -> tuple:
    """(the bound a chosen start keeps, the bound below which q0 is refused) on regularity()
    for the task's rows (attitude, position or POSE_BOUNDS).

    Args:
        rows: The task Jacobian's rows of the GJM (tasks.task.Task.jacobian_rows)."""
    if tuple(rows) == POSITION_ROWS:
        return POSITION_BOUNDS
    angular = all(row < 3 for row in rows)
    return (SINGULAR_BOUND, REFUSED_SINGULAR_VALUE) if angular else POSE_BOUNDS


def tracked(rows: Sequence[int]) -> str:
    """What a task with these GJM rows tracks: "attitude", "position" or "pose".

    Args:
        rows: The task Jacobian's rows of the GJM."""
    return {ATTITUDE_ROWS: "attitude", POSITION_ROWS: "position"}.get(tuple(rows), "pose")


def regularity(D: np.ndarray, rows: Sequence[int]) -> float:
    """D's smallest singular value (position rows alone: smallest over largest).

    Args:
        D: The task Jacobian (rows x n).
        rows: Its rows of the GJM."""
    sigma = np.linalg.svd(D, compute_uv=False)
    if tuple(rows) == POSITION_ROWS:
        return float(sigma[-1] / sigma[0]) if sigma[0] > 0 else 0.0
    return float(sigma[-1])
LIMIT_MARGIN = 0.1          # [-] share of a joint's range kept free at each end
CLEARANCE_BOUND = 0.05      # [m] link-base clearance a chosen start keeps
CANDIDATES = 256            # starts sampled by choose_start
REHEARSED = 24              # of which those with the largest singular value rehearsed
IDLE_NULL_SPACE_RATE = 1e-3     # [rad/s] the clearance potential's ||xi|| counted as idle
IDLE_CHECK_STRIDE = 25          # rehearsal samples between checks of it (0.5 s)
REHEARSAL_STEP = 0.02       # [s]


@dataclass
class ReferenceRehearsal:
    """The task followed kinematically from a start (module docstring).

    Attributes:
        time: The samples' times (T) [s].
        q: The joint angles at each sample (T x n) [rad].
        p: The joint momenta M(q) qdot (T x n) [kg m^2/s].
        p_rate: Their time derivatives (T x n) [N m].
        singular_value: D's regularity() at each sample (T)."""
    time: np.ndarray
    q: np.ndarray
    p: np.ndarray
    p_rate: np.ndarray
    singular_value: np.ndarray


def end_effector_frame(model: FloatingBaseModel) -> Frame:
    """The plant frame the attitude task tracks: the model's END_EFFECTOR frame.

    Args:
        model: The arm's model."""
    return model.plant.GetFrameByName(END_EFFECTOR)


def task_jacobian(model: FloatingBaseModel, q: np.ndarray,
                  base_positions: Optional[np.ndarray] = None,
                  rows: Sequence[int] = ATTITUDE_ROWS) -> np.ndarray:
    """D(q) (rows x n): the GJM's rows ``rows`` (0-2 angular, 3-5 linear).

    Args:
        model: The arm's model.
        q: The joint angles [rad].
        base_positions: The base joint's coordinates (default: the identity pose).
        rows: The task's rows (tasks.task.Task.jacobian_rows)."""
    return model.GeneralizedJacobian(np.asarray(q, float), end_effector_frame(model),
                                     base_positions=base_positions)[list(rows)]


def rehearse(model: FloatingBaseModel, q0: Sequence[float], task: EndEffectorAttitude,
             duration: float, rows: Sequence[int] = ATTITUDE_ROWS) -> ReferenceRehearsal:
    """Follows the task's reference kinematically from q0 (module docstring): its attitude
    reference, or without one its position reference by the linear rows.

    Args:
        model: The arm's model.
        q0: The start [rad].
        task: The task (its reference, Lambda and task_damping).
        duration: How long [s].
        rows: The task Jacobian's rows whose smallest singular value is recorded."""
    frame, reference, gains = (end_effector_frame(model), getattr(task, "reference", None),
                               task.gains)
    q = np.asarray(q0, float).copy()
    base = RotationMatrix()
    evaluation = model.Evaluate(q, derivatives=False)
    node, X_CE = model.FrameNode(frame)
    # The end effector's position, the base at the origin at the start, integrated
    # along the rehearsal by the GJM's linear rows (the base moves with the arm).
    p_E = evaluation[4][node, :3, :3] @ X_CE[:3, 3] + evaluation[4][node, :3, 3]
    position = _PositionReference(task, p_E)
    R_d0 = None if position else reference_start(
        reference, RotationMatrix(model.FramePose(frame, evaluation)))
    steps = max(int(np.ceil(duration / REHEARSAL_STEP)), 2)
    qs, ps, sigmas = [], [], []
    for k in range(steps + 1):
        positions = np.concatenate([base.ToQuaternion().wxyz(), np.zeros(3)])
        evaluation = model.Evaluate(q, derivatives=False)
        J = model.GeneralizedJacobian(q, frame, base_positions=positions,
                                      evaluation=evaluation)
        if position is None:
            R_WE = RotationMatrix(model.FramePose(frame, evaluation, positions))
            R_d, omega_d = reference_at(reference, R_d0, k * REHEARSAL_STEP)
            D, r = J[:3], omega_d - gains.Lambda * attitude_error(R_WE, R_d)
        else:
            p_d, v_d = position(k * REHEARSAL_STEP)
            D, r = J[3:], v_d - gains.Lambda * (p_E - p_d)
        qdot = damped_pseudo_inverse(D, gains.task_damping) @ r
        p_E = p_E + REHEARSAL_STEP * (J[3:] @ qdot)
        qs.append(q.copy())
        ps.append(evaluation[0] @ qdot)
        sigmas.append(regularity(J[list(rows)], rows))
        omega_base = model.BaseVelocity(q, qdot, positions)[:3]
        angle = np.linalg.norm(omega_base) * REHEARSAL_STEP
        if angle > 0:
            base = RotationMatrix(AngleAxis(angle, omega_base / np.linalg.norm(
                omega_base))) @ base
        q = q + REHEARSAL_STEP * qdot
    p = np.array(ps)
    return ReferenceRehearsal(time=REHEARSAL_STEP * np.arange(len(qs)),
                              q=np.array(qs), p=p,
                              p_rate=np.gradient(p, REHEARSAL_STEP, axis=0),
                              singular_value=np.array(sigmas))


def _PositionReference(task, p_E0: np.ndarray
                       ) -> Optional[Callable[[float], Tuple[np.ndarray, np.ndarray]]]:
    """t -> (p_d, v_d) [m, m/s] of a task that tracks a position and no attitude
    (p_d(0) = p_E(q0) + initial_offset, p_E0 [m]), else None."""
    if getattr(task, "reference", None) is not None:
        return None
    p = task.position
    axis = np.asarray(p.axis, float) / np.linalg.norm(p.axis)
    origin = p_E0 + np.asarray(p.initial_offset, float)
    omega = 2 * np.pi / p.period
    return lambda t: (origin + axis * p.amplitude * np.sin(omega * t),
                      axis * p.amplitude * omega * np.cos(omega * t))


def joint_limits(model: FloatingBaseModel) -> tuple:
    """The position limits (lower, upper) [rad] of the arm's joints, +-inf where none.

    Args:
        model: The arm's model."""
    plant, joint_q = model.plant, model.coordinates.joint_q
    return (plant.GetPositionLowerLimits()[joint_q],
            plant.GetPositionUpperLimits()[joint_q])


def _allowed_box(model: FloatingBaseModel) -> tuple:
    """Each joint's sampling range: its limits less LIMIT_MARGIN, else [-pi, pi]."""
    lower, upper = joint_limits(model)
    wide = ~(np.isfinite(lower) & np.isfinite(upper)) | (upper - lower > 2 * np.pi)
    margin = LIMIT_MARGIN * (upper - lower)
    low = np.where(wide, -np.pi, lower + margin)
    high = np.where(wide, np.pi, upper - margin)
    return low, high


def within_limits(model: FloatingBaseModel, q: np.ndarray) -> bool:
    """Whether every sample of ``q`` keeps LIMIT_MARGIN of each joint's range free.

    Args:
        model: The arm's model.
        q: Joint angles, one sample (n) or many (k x n) [rad]."""
    lower, upper = joint_limits(model)
    finite = np.isfinite(lower) & np.isfinite(upper)
    margin = np.where(finite, LIMIT_MARGIN * (upper - lower), 0.0)
    q = np.atleast_2d(q)
    return bool(np.all((q >= lower + margin) & (q <= upper - margin)))


def choose_start(model: FloatingBaseModel, task: EndEffectorAttitude,
                 clearance: Callable[[np.ndarray], float],
                 null_space_rate: Optional[Callable[[np.ndarray], float]],
                 duration: float, rows: Sequence[int] = ATTITUDE_ROWS) -> np.ndarray:
    """The start q0 [rad] a scenario file does not give. Candidates: the middle of the
    limits and CANDIDATES quasi-random points within them. One qualifies when D stays
    regular (SINGULAR_BOUND) along its rehearsal within the limits and its links are
    CLEARANCE_BOUND (or half the best clearance) off the base; of the REHEARSED candidates
    pushed least at the start, the one pushed least along its rehearsal (then the
    best-conditioned) wins.

    Args:
        model: The arm's model.
        task: The task.
        clearance: q -> the link-base clearance [m].
        null_space_rate: q -> ||xi|| of the clearance potential [rad/s] (None: none).
        duration: How long the rehearsal runs [s].
        rows: The task Jacobian's rows that must stay regular (task_jacobian).

    Raises:
        ValueError: No candidate qualifies (naming the test that failed most)."""
    low, high = _allowed_box(model)
    n = model.num_joints
    points = _halton(CANDIDATES, n)
    candidates = np.vstack([0.5 * (low + high), low + points * (high - low)])
    sigma = np.array([regularity(task_jacobian(model, q, rows=rows), rows)
                      for q in candidates])
    best, best_key = None, None
    failures = {"limits": 0, "singular": 0, "clearance": 0}
    bound = singular_bounds(rows)[0]
    regular = np.flatnonzero(sigma >= bound)
    failures["singular"] = len(candidates) - len(regular)
    clearances = np.array([clearance(candidates[k]) for k in regular])
    near = min(CLEARANCE_BOUND, 0.5 * float(np.max(clearances, initial=0.0)))
    clear = regular[clearances > max(near, 0.0)]
    failures["clearance"] = len(regular) - len(clear)
    pushing = np.array([null_space_rate(candidates[k]) if null_space_rate else 0.0
                        for k in clear])
    order = sorted(range(len(clear)), key=lambda i: (
        max(pushing[i], IDLE_NULL_SPACE_RATE), -sigma[clear[i]]))
    for k in clear[order[:REHEARSED]]:
        q = candidates[k]
        rehearsal = rehearse(model, q, task, duration, rows)
        if not within_limits(model, rehearsal.q):
            failures["limits"] += 1
            continue
        smallest = float(np.min(rehearsal.singular_value))
        if smallest < bound:
            failures["singular"] += 1
            continue
        push = (0.0 if null_space_rate is None else max(
            null_space_rate(x) for x in rehearsal.q[::IDLE_CHECK_STRIDE]))
        key = (max(push, IDLE_NULL_SPACE_RATE), -smallest)
        if best_key is None or key < best_key:
            best, best_key = q, key
    if best is None:
        raise ValueError(f"no start of {len(candidates)} tried qualifies ({failures})")
    return best.copy()


def task_singularity(model: FloatingBaseModel, q0: Sequence[float],
                     rows: Sequence[int] = ATTITUDE_ROWS) -> Optional[str]:
    """A sentence naming the singularity and the joints that turn the end effector least if
    D's smallest singular value at q0 < REFUSED_SINGULAR_VALUE, else None.

    Args:
        model: The arm's model.
        q0: The start [rad].
        rows: The task Jacobian's rows (task_jacobian)."""
    D = task_jacobian(model, q0, rows=rows)
    _, sigma, Vt = np.linalg.svd(D)
    refused = singular_bounds(rows)[1]
    measure = regularity(D, rows)
    if measure >= refused:
        return None
    # The joint-rate directions that leave the end effector's attitude (nearly)
    # still beyond the null space a redundant arm has anyway.
    direction = Vt[len(sigma) - 1]
    names = [joint.name() for joint in arm_joints(model)]
    involved = [names[k] for k in np.argsort(-np.abs(direction))
                if abs(direction[k]) >= 0.3]
    what = tracked(rows)
    how = "turn it about the same axis" if what == "attitude" else "move it the same way"
    measured = ("smallest singular value over its largest"
                if tuple(rows) == POSITION_ROWS else "smallest singular value")
    return (f"the end effector's {what} is singular there (the task Jacobian's "
            f"{measured} {measure:.2g} < {refused:g}): "
            f"joints {', '.join(repr(name) for name in involved)} {how}")


def _halton(count: int, dimension: int) -> np.ndarray:
    """The first ``count`` points of the Halton sequence in [0, 1)^dimension."""
    primes: List[int] = []
    candidate = 2
    while len(primes) < dimension:
        if all(candidate % p for p in primes):
            primes.append(candidate)
        candidate += 1
    points = np.zeros((count, dimension))
    for d, base in enumerate(primes):
        for i in range(count):
            f, r, k = 1.0, 0.0, i + 1
            while k:
                f /= base
                r += f * (k % base)
                k //= base
            points[i, d] = r
    return points
