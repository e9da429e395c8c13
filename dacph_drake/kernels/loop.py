"""Compiled bodies of the closed loop's systems: LhsController, TrueRhs (with d(t)),
PortObserver and RhsIntegrator; each system's docstring states the equations."""
from typing import Sequence, Tuple, Union

import numpy as np
from numba import njit

from dacph_drake.kernels.arm import (_joint_momentum_into, dot, matvec,
                                     reduced_dynamics)
from dacph_drake.kernels.potential import potential
from dacph_drake.kernels.spatial import joint_momentum


@njit(cache=True)
def disturbance(t: float, model: np.ndarray) -> np.ndarray:
    """d(t) [N m] (n) = scale (offset + amplitude sin(omega t + quadrature) + hf
    sin(hf_omega t)), zero before start (DisturbanceSource).

    Args:
        t: The time [s].
        model: [start [s], scale, hf_omega [rad/s], offset, amplitude [N m], omega [rad/s],
            quadrature [rad], hf [N m]] (the last five n each; 3 + 5 n)."""
    n = (model.shape[0] - 3) // 5
    d = np.zeros(n)
    _add_disturbance(t, model, d)
    return d


@njit(cache=True)
def _add_disturbance(t, model, out):
    """out += d(t) (disturbance), in place."""
    n = (model.shape[0] - 3) // 5
    if t < model[0]:
        return
    hf = np.sin(model[2] * t)
    for i in range(n):
        lf = model[3 + i] + model[3 + n + i] * np.sin(model[3 + 2 * n + i] * t
                                                      + model[3 + 3 * n + i])
        out[i] += model[1] * (lf + model[3 + 4 * n + i] * hf)


@njit(cache=True)
def actuator_gains(t: float, actuator: np.ndarray, n: int) -> np.ndarray:
    """g(t) (n): B_scale times the gain of every fault whose time has come.

    Args:
        t: The time [s].
        actuator: [B_scale (n), (time [s], joint index from 0, gain) per fault].
        n: The number of joints."""
    gains = actuator[:n].copy()
    for k in range((actuator.shape[0] - n) // 3):
        if t >= actuator[n + 3 * k]:
            gains[int(actuator[n + 3 * k + 1])] *= actuator[n + 3 * k + 2]
    return gains


@njit(cache=True)
def true_matrices(t: float, q: np.ndarray, p: np.ndarray, B0: np.ndarray,
                  D0: np.ndarray, D_offset: np.ndarray, D_linear: np.ndarray,
                  B_linear: np.ndarray, D_quadratic: np.ndarray,
                  B_quadratic: np.ndarray, B_q1_squared: np.ndarray,
                  linear_start: float, nonlinear_start: float, actuator: np.ndarray
                  ) -> Tuple[np.ndarray, np.ndarray]:
    """(B~ (n x n), diag D~ [N m s] (n)) at (t, q, p): B~ = diag(g(t)) (B0 + Delta B),
    D~ = D0 + Delta D (uncertainty.TrueRhsModel.kernel_arguments after (t, q, p)).

    Args:
        t: The time [s].
        q: The joint angles [rad] (n).
        p: The joint momenta p = M qdot [N m s] (n).
        B0: The nominal B0's diagonal (n).
        D0: The nominal D0's diagonal [N m s] (n).
        D_offset: D~'s offset [N m s] (n).
        D_linear: D~'s coefficients of p (n).
        B_linear: B~'s diagonal's coefficients of q (n x n).
        D_quadratic: D~'s coefficients of p^2 (n).
        B_quadratic: B~'s diagonal's coefficients of p^2 (n).
        B_q1_squared: B~'s coefficients of q_1^2 (n x n).
        linear_start: When the linear terms (D_offset, D_linear, B_linear) switch on [s].
        nonlinear_start: When the p^2 and q_1^2 terms switch on [s].
        actuator: The actuators' gains' arguments (actuator_gains)."""
    n = q.shape[0]
    B, D = np.empty((n, n)), np.empty(n)
    _true_matrices_into(t, q, p, B0, D0, D_offset, D_linear, B_linear, D_quadratic,
                        B_quadratic, B_q1_squared, linear_start, nonlinear_start,
                        actuator, B, D)
    return B, D


@njit(cache=True)
def _true_matrices_into(t, q, p, B0, D0, D_offset, D_linear, B_linear, D_quadratic,
                        B_quadratic, B_q1_squared, linear_start, nonlinear_start,
                        actuator, B, D):
    """true_matrices written into B (n x n) and D (n), allocating nothing."""
    n = q.shape[0]
    nonlinear = t >= nonlinear_start
    q1_squared = q[0] * q[0]
    for i in range(n):
        gain = actuator[i]                          # actuator_gains, entry i
        for k in range((actuator.shape[0] - n) // 3):
            if t >= actuator[n + 3 * k] and int(actuator[n + 3 * k + 1]) == i:
                gain *= actuator[n + 3 * k + 2]
        if t < linear_start:
            for j in range(n):
                B[i, j] = 0.0
            B[i, i] = gain * B0[i]
            D[i] = D0[i]
            continue
        diagonal = 0.0
        for k in range(n):
            diagonal += B_linear[i, k] * q[k]
        diagonal = B0[i] + diagonal
        D[i] = D0[i] + D_offset[i] + D_linear[i] * p[i]
        for j in range(n):
            B[i, j] = 0.0 + q1_squared * B_q1_squared[i, j] if nonlinear else 0.0
        if nonlinear:
            pp = p[i] * p[i]
            D[i] = D[i] + D_quadratic[i] * pp
            diagonal = diagonal + B_quadratic[i] * pp
        B[i, i] += diagonal
        for j in range(n):
            B[i, j] *= gain


def pack_true_rhs(coefficients: Union[np.ndarray, Sequence[float]],
                  ranges: Union[np.ndarray, Sequence[float]],
                  uncertainty: Sequence[Union[np.ndarray, float]]) -> np.ndarray:
    """true_torque's constant arguments as one array [vec(coefficients), vec(ranges), the
    uncertainty's arguments, raveled] (fewer arguments: cheaper numba dispatch).

    Args:
        coefficients: The mass matrix's trigonometric coefficients (N^2 x (1 + 2 R),
            N = n + 3, R = n (n + 1) / 2); empty for a spatial arm.
        ranges: Their angle combinations (R x n); empty for a spatial arm.
        uncertainty: true_matrices' arguments after (t, q, p) (TrueRhsModel)."""
    return np.concatenate([np.ravel(a) for a in (coefficients, ranges, *uncertainty)]
                          ).astype(float)


@njit(cache=True)
def true_torque(t: float, x: np.ndarray, indices: np.ndarray, u: np.ndarray,
                disturbance_model: np.ndarray, packed: np.ndarray) -> np.ndarray:
    """tau [N m] (n) = B~(x) u - D~(x) qdot + d(t) at time t and plant state x (TrueRhs).

    Args:
        t: The time [s].
        x: The plant's state [positions, velocities].
        indices: The indices of [theta0, base velocity (3), q (n), qdot (n)] in x (int64).
        u: The command [N m] (n).
        disturbance_model: d(t)'s parameters (disturbance; 3 + 5 n).
        packed: The robot's and the uncertainty's arguments (pack_true_rhs)."""
    n = u.shape[0]
    tau = np.empty(n)
    _true_torque_into(t, x, indices, u, disturbance_model, packed, torque_scratch(n),
                      tau)
    return tau


@njit(cache=True)
def torque_scratch(n: int) -> Tuple[np.ndarray, ...]:
    """Uninitialized work arrays of _true_torque_into for n joints (one set per batch call).

    Args:
        n: The number of joints."""
    R = n * (n + 1) // 2
    return (np.empty(n), np.empty(n), np.empty(n), np.empty(R), np.empty(R),
            np.empty((n, n)), np.empty(n))


@njit(cache=True)
def _true_torque_into(t, x, indices, u, disturbance_model, packed, scratch, tau):
    """true_torque written into ``tau`` with the work arrays ``scratch``."""
    q, qdot, p, _, _, B, D = scratch
    o = _trial_state_into(x, indices, packed, scratch)
    _torque_into(t, q, p, qdot, u, disturbance_model, packed[o:], B, D, tau)


@njit(cache=True)
def _trial_state_into(x, indices, packed, scratch):
    """q, qdot, p of trial x[indices] into scratch; returns the uncertainty's offset."""
    q, qdot, p, c, si, _, _ = scratch
    n = q.shape[0]
    for j in range(n):
        q[j], qdot[j] = x[indices[4 + j]], x[indices[4 + n + j]]
    N, R = n + 3, n * (n + 1) // 2
    o = 0
    coefficients = packed[o:o + N * N * (1 + 2 * R)].reshape(N * N, 1 + 2 * R)
    o += N * N * (1 + 2 * R)
    ranges = packed[o:o + R * n].reshape(R, n)
    o += R * n
    _joint_momentum_into(x[indices[0]], x[indices[1]], x[indices[2]], x[indices[3]],
                         q, qdot, coefficients, ranges, c, si, p)
    return o


@njit(cache=True)
def true_matrices_of_trials(t: float, x: np.ndarray, indices: np.ndarray,
                            packs: np.ndarray, offsets: np.ndarray, n: int
                            ) -> np.ndarray:
    """[vec(B~) (row-major), diag(D~)] of every trial, stacked (trials (n n + n)).

    Args:
        t: The time [s].
        x: The batch's plant state [positions, velocities].
        indices: Each trial's StateIndices in x (int64, trials x (4 + 2 n)).
        packs: The trials' packed arguments, stacked (stack_packs).
        offsets: Where each trial's part of ``packs`` starts (int64, trials + 1).
        n: The number of joints."""
    trials = indices.shape[0]
    out = np.empty(trials * (n * n + n))
    scratch = torque_scratch(n)
    q, _, p, _, _, B, D = scratch
    for i in range(trials):
        packed = packs[offsets[i]:offsets[i + 1]]
        o = _trial_state_into(x, indices[i], packed, scratch)
        _matrices_into(t, q, p, packed[o:], B, D)
        start = i * (n * n + n)
        for r in range(n):
            for c in range(n):
                out[start + r * n + c] = B[r, c]
            out[start + n * n + r] = D[r]
    return out


def stack_packs(packs: Sequence[np.ndarray]) -> "tuple[np.ndarray, np.ndarray]":
    """(Packed arguments concatenated, each one's offset (int64, trials + 1)).

    Args:
        packs: Each trial's packed arguments (pack_true_rhs, pack_lhs; any lengths)."""
    offsets = np.concatenate([[0], np.cumsum([len(p) for p in packs])]).astype(np.int64)
    return np.concatenate(packs).astype(float), offsets


# true_torques' and spatial_true_torques' verdict on each trial (TrueRhsSystem).
RUNNING, STOPPED, NON_FINITE, RUNAWAY = 0, 1, 2, 3


@njit(cache=True)
def _verdict(running, state, rates, more_rates, tau, bound):
    """STOPPED, NON_FINITE (state, torque), RUNAWAY (a rate over ``bound``) or RUNNING."""
    if running <= 0:
        return STOPPED
    for value in state:
        if not np.isfinite(value):
            return NON_FINITE
    for value in tau:
        if not np.isfinite(value):
            return NON_FINITE
    for value in rates:
        if abs(value) > bound:
            return RUNAWAY
    for value in more_rates:
        if abs(value) > bound:
            return RUNAWAY
    return RUNNING


@njit(cache=True)
def true_torques(t: float, x: np.ndarray, indices: np.ndarray, u: np.ndarray,
                 disturbance_models: np.ndarray, packs: np.ndarray, offsets: np.ndarray,
                 running: np.ndarray, bound: float, verdicts: np.ndarray) -> np.ndarray:
    """The trials' tau [N m] (trials n) by true_torque; zero unless a trial is RUNNING.

    Args:
        t: The time [s].
        x: The batch's plant state [positions, velocities].
        indices: Each trial's StateIndices in x (int64, trials x (4 + 2 n)).
        u: The trials' commands [N m] (trials n).
        disturbance_models: The trials' d(t) parameters (disturbance; trials (3 + 5 n)).
        packs: The trials' packed arguments, stacked (stack_packs of pack_true_rhs).
        offsets: Where each trial's part of ``packs`` starts (int64, trials + 1).
        running: Each trial's running flag (1: runs, 0: stopped; trials).
        bound: The largest rate a running trial may have [rad/s, m/s] (RUNAWAY_RATE).
        verdicts: Written: each trial's verdict, then the largest (int64, trials + 1)."""
    trials = indices.shape[0]
    n = u.shape[0] // trials
    m = disturbance_models.shape[0] // trials
    out = np.zeros(trials * n)
    tau = np.empty(n)
    scratch = torque_scratch(n)
    verdicts[trials] = RUNNING
    for i in range(trials):
        verdict = STOPPED
        if running[i] > 0:
            _true_torque_into(t, x, indices[i], u[i * n:(i + 1) * n],
                              disturbance_models[i * m:(i + 1) * m],
                              packs[offsets[i]:offsets[i + 1]], scratch, tau)
            verdict = _planar_verdict(x, indices[i], n, tau, bound)
        _settle(out, verdicts, i, verdict, tau)
    return out


@njit(cache=True)
def _settle(out, verdicts, i, verdict, tau):
    """Records trial i's verdict (the largest: last entry) and, if RUNNING, its tau."""
    n = tau.shape[0]
    if verdict == RUNNING:
        out[i * n:(i + 1) * n] = tau
    verdicts[i] = verdict
    verdicts[verdicts.shape[0] - 1] = max(verdicts[verdicts.shape[0] - 1], verdict)


@njit(cache=True)
def _planar_verdict(x, indices, n, tau, bound):
    """_verdict of a running planar trial whose state is x[indices], read in place."""
    for k in indices:
        if not np.isfinite(x[k]):
            return NON_FINITE
    for value in tau:
        if not np.isfinite(value):
            return NON_FINITE
    for k in range(1, 4):
        if abs(x[indices[k]]) > bound:
            return RUNAWAY
    for k in range(4 + n, 4 + 2 * n):
        if abs(x[indices[k]]) > bound:
            return RUNAWAY
    return RUNNING


@njit(cache=True)
def _torque_into(t, q, p, qdot, u, disturbance_model, packed, B, D, tau):
    """tau = B~ u - D~ qdot + d(t) into ``tau``; B, D: work arrays (_matrices_into)."""
    _matrices_into(t, q, p, packed, B, D)
    _torque_of_matrices(t, qdot, u, disturbance_model, B, D, tau)


@njit(cache=True)
def _torque_of_matrices(t, qdot, u, disturbance_model, B, D, tau):
    """tau = B u - D qdot + d(t) into ``tau`` from the matrices B, diag D."""
    n = u.shape[0]
    for i in range(n):
        Bu = 0.0
        for j in range(n):
            Bu += B[i, j] * u[j]
        tau[i] = Bu - D[i] * qdot[i]
    _add_disturbance(t, disturbance_model, tau)


# [rad/s] The joint rate over which a description's Coulomb friction f reaches its full
# size in the ground truth, f tanh(qdot / FRICTION_VELOCITY): MuJoCo's frictionloss is
# a constraint that can stick; a smooth truth keeps the explicit integrator (its
# stiffest slope f / FRICTION_VELOCITY is counted in the step, robots.sizing.truth_step).
FRICTION_VELOCITY = 0.1


@njit(cache=True)
def add_friction(friction: np.ndarray, qdot: np.ndarray, D: np.ndarray) -> None:
    """Adds each joint's Coulomb friction f tanh(qdot / FRICTION_VELOCITY) to D~ as its
    secant damping f tanh(qdot / v) / qdot (f / v at rest), in place.

    Args:
        friction: Each joint's f [N m] (n).
        qdot: The joint rates [rad/s] (n).
        D: diag D~ [N m s/rad] (n), changed in place."""
    for j in range(qdot.shape[0]):
        if friction[j] > 0.0:
            x = qdot[j] / FRICTION_VELOCITY
            secant = (np.tanh(x) / x if abs(x) > 1e-8 else 1.0 - x * x / 3.0)
            D[j] += friction[j] * secant / FRICTION_VELOCITY


@njit(cache=True)
def _matrices_into(t, q, p, packed, B, D):
    """true_matrices into B and D from the uncertainty's part of a pack_true_rhs."""
    n = q.shape[0]
    B0, D0, D_offset, D_linear = (packed[0:n], packed[n:2 * n], packed[2 * n:3 * n],
                                  packed[3 * n:4 * n])
    o = 4 * n
    B_linear = packed[o:o + n * n].reshape(n, n)
    o += n * n
    D_quadratic, B_quadratic = packed[o:o + n], packed[o + n:o + 2 * n]
    o += 2 * n
    B_q1_squared = packed[o:o + n * n].reshape(n, n)
    o += n * n
    _true_matrices_into(t, q, p, B0, D0, D_offset, D_linear, B_linear, D_quadratic,
                        B_quadratic, B_q1_squared, packed[o], packed[o + 1],
                        packed[o + 2:], B, D)


@njit(cache=True)
def spatial_true_torques(t: float, x: np.ndarray, indices: np.ndarray,
                         base_subspace: np.ndarray, parent: np.ndarray,
                         joint: np.ndarray, X_PFs: np.ndarray, axes: np.ndarray,
                         X_MCs: np.ndarray, below: np.ndarray, masses: np.ndarray,
                         moments: np.ndarray, inertias: np.ndarray,
                         reflecteds: np.ndarray, frictions: np.ndarray, u: np.ndarray,
                         limits: np.ndarray, disturbance_models: np.ndarray,
                         packs: np.ndarray, offsets: np.ndarray, running: np.ndarray,
                         bound: float, verdicts: np.ndarray) -> np.ndarray:
    """true_torques of spatial arms (SpatialTrueRhs): tau = B~ u_c - D~ qdot + d(t), u_c =
    u clipped to +-limits, p from each tree, D~ with friction (add_friction).

    Args:
        t: The time [s].
        x: The batch's plant state [positions, velocities].
        indices: Each trial's indices of [base pose (7), base twist (6), q, qdot] in x.
        base_subspace: The base joint's motion subspace (6 x base velocities).
        parent: Each node's parent node, -1 for the base (nodes).
        joint: The joint moving each node (0 .. n - 1), -1 for a weld (nodes).
        X_PFs: Each trial's joint frames F in their parents (trials x nodes x 4 x 4).
        axes: Each trial's joint axes in F (trials x nodes x 3).
        X_MCs: Each trial's body poses in the joints' frames M (trials x nodes x 4 x 4).
        below: True where joint k moves the node (n x nodes).
        masses: Each trial's body masses [kg] (trials x nodes).
        moments: Each trial's first moments m c [kg m] (trials x nodes x 3).
        inertias: Each trial's rotational inertias about the body origins [kg m^2].
        reflecteds: Each trial's joints' reflected inertias (trials, n) [kg m^2].
        frictions: Each trial's joints' Coulomb friction (trials, n) [N m].
        u: The trials' commands [N m] (trials n).
        limits: The actuators' effort limits [N m] (trials x n).
        disturbance_models: The trials' d(t) parameters (disturbance; trials (3 + 5 n)).
        packs: The trials' packed uncertainties, stacked (stack_packs).
        offsets: Where each trial's part of ``packs`` starts (int64, trials + 1).
        running: Each trial's running flag (1: runs, 0: stopped; trials).
        bound: The largest velocity a running trial may have [rad/s, m/s] (RUNAWAY_RATE).
        verdicts: Written: each trial's verdict, then the largest (int64, trials + 1)."""
    trials = indices.shape[0]
    n = u.shape[0] // trials
    m = disturbance_models.shape[0] // trials
    out = np.zeros(trials * n)
    tau, clipped, B, D = np.empty(n), np.empty(n), np.empty((n, n)), np.empty(n)
    verdicts[trials] = RUNNING
    for i in range(trials):
        verdict = STOPPED
        if running[i] > 0:
            arm = x[indices[i]]
            q, qdot = arm[13:13 + n], arm[13 + n:]
            p = joint_momentum(base_subspace, parent, joint, X_PFs[i], axes[i],
                               X_MCs[i], below, masses[i], moments[i], inertias[i],
                               reflecteds[i], arm[:7], arm[7:13], q, qdot)
            for j in range(n):
                command = u[i * n + j]
                clipped[j] = min(max(command, -limits[i, j]), limits[i, j])
            _matrices_into(t, q, p, packs[offsets[i]:offsets[i + 1]], B, D)
            add_friction(frictions[i], qdot, D)
            _torque_of_matrices(t, qdot, clipped, disturbance_models[i * m:(i + 1) * m],
                                B, D, tau)
            verdict = _verdict(running[i], arm, arm[7:13], qdot, tau, bound)
        _settle(out, verdicts, i, verdict, tau)
    return out


def pack_lhs(ranges: np.ndarray, geometry: np.ndarray, link_of: np.ndarray,
             fraction: np.ndarray, radius: np.ndarray, potential_gains: np.ndarray,
             reference: np.ndarray, gains: np.ndarray, excitation: np.ndarray
             ) -> np.ndarray:
    """lhs_sample's constant arguments as one array (see pack_true_rhs).

    Args:
        ranges: The mass matrix's angle combinations (R x n).
        geometry: (half base size, shoulder x, shoulder y, link lengths (n)) [m].
        link_of: The link of each potential point (points).
        fraction: How far along its link each point lies (points).
        radius: Each point's half width [m] (points).
        potential_gains: [base_gain, base_margin, fold_gain, fold_margin] (4).
        reference: [alpha0 [rad], amplitudes (m) [rad], omegas (m) [rad/s]] (lhs_control).
        gains: [Kd, Lambda, epsilon, eta, layer_per_chi] (lhs_control).
        excitation: [amplitudes (n) [N m], omegas (n) [rad/s]] (lhs_control)."""
    return np.concatenate([[len(link_of), (len(reference) - 1) // 2],
                           *(np.ravel(a) for a in (
                               ranges, geometry, link_of, fraction, radius,
                               potential_gains, reference, gains, excitation))]
                          ).astype(float)


@njit(cache=True)
def lhs_sample(t: float, theta0: float, q: np.ndarray, qdot: np.ndarray, chi: float,
               coefficients: np.ndarray, packed: np.ndarray) -> np.ndarray:
    """lhs_control unpacking ``packed``: [tau_c^r (n), log (n + 4), vec(M), vec(C')].

    Args:
        t: The time [s].
        theta0: The base angle [rad].
        q: The joint angles [rad] (n).
        qdot: The joint rates [rad/s] (n).
        chi: The RHS loop's bound chi [N m].
        coefficients: The mass-matrix coefficients (the identification may refresh them).
        packed: The constant arguments (pack_lhs)."""
    n = q.shape[0]
    R = n * (n + 1) // 2
    points, terms = int(packed[0]), int(packed[1])
    o = 2
    ranges = packed[o:o + R * n].reshape(R, n)
    o += R * n
    geometry = packed[o:o + 3 + n]
    o += 3 + n
    link_of = packed[o:o + points].astype(np.int64)
    o += points
    fraction, radius = packed[o:o + points], packed[o + points:o + 2 * points]
    o += 2 * points
    potential_gains = packed[o:o + 4]
    o += 4
    reference = packed[o:o + 1 + 2 * terms]
    o += 1 + 2 * terms
    gains = packed[o:o + 5]
    excitation = packed[o + 5:o + 5 + 2 * n]
    tau, log, M, C = lhs_control(t, theta0, q, qdot, chi, coefficients, ranges,
                                 geometry, link_of,
                                 fraction, radius, potential_gains, reference, gains,
                                 excitation)
    out = np.empty(2 * n + 4 + 2 * n * n)
    out[:n] = tau
    out[n:2 * n + 4] = log
    out[2 * n + 4:2 * n + 4 + n * n] = M.ravel()
    out[2 * n + 4 + n * n:] = C.ravel()
    return out


@njit(cache=True)
def lhs_samples(t: float, theta0s: np.ndarray, q: np.ndarray, qdot: np.ndarray,
                chi: np.ndarray, coefficients: np.ndarray, packs: np.ndarray,
                offsets: np.ndarray) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """lhs_sample of every trial of a batch: (tau_c^r, logs, [vec(M), vec(C')]) by trial.

    Args:
        t: The time [s].
        theta0s: The trials' base angles [rad] (trials).
        q: The trials' joint angles [rad] (trials n).
        qdot: The trials' joint rates [rad/s] (trials n).
        chi: The trials' RHS bounds chi [N m] (trials).
        coefficients: The trials' mass-matrix coefficients (trials x N^2 x (1 + 2 R)).
        packs: The trials' constant arguments, stacked (stack_packs of pack_lhs).
        offsets: Where each trial's part of ``packs`` starts (int64, trials + 1)."""
    trials = theta0s.shape[0]
    n = q.shape[0] // trials
    tau, logs = np.empty(trials * n), np.empty(trials * (n + 4))
    models = np.empty(trials * 2 * n * n)
    for i in range(trials):
        sample = lhs_sample(
            t, theta0s[i], q[i * n:(i + 1) * n], qdot[i * n:(i + 1) * n], chi[i],
            coefficients[i], packs[offsets[i]:offsets[i + 1]])
        tau[i * n:(i + 1) * n] = sample[:n]
        logs[i * (n + 4):(i + 1) * (n + 4)] = sample[n:2 * n + 4]
        models[i * 2 * n * n:(i + 1) * 2 * n * n] = sample[2 * n + 4:]
    return tau, logs, models


@njit(cache=True)
def lhs_control(t: float, theta0: float, q: np.ndarray, qdot: np.ndarray, chi: float,
                coefficients: np.ndarray, ranges: np.ndarray, geometry: np.ndarray,
                link_of: np.ndarray, fraction: np.ndarray, radius: np.ndarray,
                potential_gains: np.ndarray, reference: np.ndarray, gains: np.ndarray,
                excitation: np.ndarray
                ) -> Tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(tau_c^r [N m] (n), log [s, alpha~, alpha_d, V, U] (n + 4), M, C' (n x n)): the LHS
    law (LhsController) with the boundary layer phi = epsilon + layer_per_chi chi.

    Args:
        t: The time [s].
        theta0: The base angle [rad].
        q: The joint angles [rad] (n).
        qdot: The joint rates [rad/s] (n).
        chi: The RHS loop's bound chi [N m].
        coefficients: The mass matrix's trigonometric coefficients (N^2 x (1 + 2 R)).
        ranges: Their angle combinations (R x n).
        geometry: The potential's geometry (kernels.potential.potential).
        link_of: The link of each potential point (points).
        fraction: How far along its link each point lies (points).
        radius: Each point's half width [m] (points).
        potential_gains: [base_gain, base_margin, fold_gain, fold_margin] (4).
        reference: [alpha0 [rad], a (m) [rad], omega (m) [rad/s]] of
            alpha_d(t) = alpha0 + sum_j a_j sin(omega_j t).
        gains: [Kd, Lambda, epsilon, eta, layer_per_chi] (5).
        excitation: [amplitudes (n) [N m], omegas (n) [rad/s]] of tau_pe(t) (0: off)."""
    n = q.shape[0]
    M, C, D, dD = reduced_dynamics(q, qdot, coefficients, ranges)
    m = (reference.shape[0] - 1) // 2
    alpha_d, alpha_d_dot, alpha_d_ddot = reference[0], 0.0, 0.0
    for i in range(m):
        a, w = reference[1 + i], reference[1 + m + i]
        alpha_d += a * np.sin(w * t)
        alpha_d_dot += a * w * np.cos(w * t)
        alpha_d_ddot -= a * w * w * np.sin(w * t)
    Kd, Lambda, eta = gains[0], gains[1], gains[3]
    layer = gains[2] + gains[4] * chi
    U, grad_U, grad_U_dot = potential(q, qdot, geometry, link_of, fraction, radius,
                                      potential_gains)
    # Scalar loops rather than array expressions (each of those compiles into a
    # kernel of its own). With xi = -eta grad U and P = I - D+ D:
    # P xi = xi - D+ (D xi), P_dot xi = -(D+_dot (D xi) + D+ (D_dot xi)).
    D_dot = np.zeros(n)
    alpha_error = theta0 - alpha_d
    alpha_error_dot, DDt, D_D_dot = -alpha_d_dot, 0.0, 0.0
    for i in range(n):
        for k in range(n):
            D_dot[i] += dD[k, i] * qdot[k]
        alpha_error += q[i]
        alpha_error_dot += D[i] * qdot[i]
        DDt += D[i] * D[i]
    D_xi, D_dot_xi, D_xi_dot = 0.0, 0.0, 0.0
    for i in range(n):
        D_D_dot += D[i] * D_dot[i]
        D_xi -= eta * D[i] * grad_U[i]
        D_dot_xi -= eta * D_dot[i] * grad_U[i]
        D_xi_dot -= eta * D[i] * grad_U_dot[i]
    task = alpha_d_dot - Lambda * alpha_error
    task_dot = alpha_d_ddot - Lambda * alpha_error_dot
    nu, nu_dot, s = np.empty(n), np.empty(n), np.empty(n)
    for i in range(n):
        D_pinv = D[i] / DDt
        D_pinv_dot = D_dot[i] / DDt - D[i] * (2.0 * D_D_dot / DDt**2)
        nu[i] = D_pinv * task - eta * grad_U[i] - D_pinv * D_xi
        nu_dot[i] = (D_pinv_dot * task + D_pinv * task_dot - eta * grad_U_dot[i]
                     - D_pinv_dot * D_xi - D_pinv * D_dot_xi - D_pinv * D_xi_dot)
        s[i] = qdot[i] - nu[i]
    tau = np.empty(n)
    V = 0.0
    for i in range(n):
        tau[i] = -Kd * s[i] - chi * np.tanh(s[i] / layer)
        for j in range(n):
            tau[i] += M[i, j] * nu_dot[j] + C[i, j] * nu[j]
            V += 0.5 * s[i] * M[i, j] * s[j]
        if excitation[i] > 0:
            tau[i] += excitation[i] * np.sin(excitation[n + i] * t)
    log = np.empty(n + 4)
    log[:n] = s
    log[n], log[n + 1], log[n + 2], log[n + 3] = alpha_error, alpha_d, V, U
    return tau, log, M, C


@njit(cache=True)
def observer_sample(q: np.ndarray, qdot: np.ndarray, memory: np.ndarray,
                    model: np.ndarray, u: np.ndarray, noise: np.ndarray,
                    constants: np.ndarray) -> np.ndarray:
    """A PortObserver sample [tau_obs (n), qdot(k) (n), port_sample (5 n)] (tau_obs and
    qdot_mid as PortObserver states them): port_sample = [q, p = M qdot_mid, r],
    r <- r + a ([qdot_mid, u, tau_obs] - r).

    Args:
        q: The joint angles [rad] (n).
        qdot: The joint rates qdot(k) [rad/s] (n).
        memory: [qdot(k-1) (n), port_sample (5 n)] of the last sample.
        model: [vec(M), vec(C')] (2 n^2, row-major).
        u: The command held over the interval [N m] (n).
        noise: The measurement noise on tau_obs [N m] (n).
        constants: [h [s], anti-alias factor a, LHS model damping b [N m s/rad] (n)]."""
    n = u.shape[0]
    h, a = constants[0], constants[1]
    M = model[:n * n].reshape(n, n)
    C = model[n * n:].reshape(n, n)
    qdot_mid = 0.5 * (qdot + memory[:n])
    tau = (matvec(M, (qdot - memory[:n]) / h) + matvec(C, qdot_mid)
           + constants[2:2 + n] * qdot_mid + noise)
    out = np.empty(7 * n)
    out[:n] = tau
    out[n:2 * n] = qdot
    out[2 * n:3 * n] = q
    out[3 * n:4 * n] = matvec(M, qdot_mid)
    regressed = memory[3 * n:]          # port_sample[2 n:] = [qdot, u, tau_obs]
    for i in range(n):
        out[4 * n + i] = regressed[i] + a * (qdot_mid[i] - regressed[i])
        out[5 * n + i] = regressed[n + i] + a * (u[i] - regressed[n + i])
        out[6 * n + i] = regressed[2 * n + i] + a * (tau[i] - regressed[2 * n + i])
    return out


@njit(cache=True)
def observer_samples(trials: int, q: np.ndarray, qdot: np.ndarray, memory: np.ndarray,
                     model: np.ndarray, u: np.ndarray, noise: np.ndarray,
                     constants: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    """observer_sample of each trial: (tau_obs [N m], [qdot(k), port_sample]).

    Args:
        trials: The number of trials.
        q: The trials' joint angles [rad] (trials n).
        qdot: The trials' joint rates [rad/s] (trials n).
        memory: The trials' memories (observer_sample; trials 6 n).
        model: The trials' [vec(M), vec(C')] (trials 2 n^2).
        u: The trials' commands [N m] (trials n).
        noise: The trials' measurement noise [N m] (trials n).
        constants: observer_sample's constants, every trial's."""
    n = u.shape[0] // trials
    tau, memory_out = np.empty(n * trials), np.empty(6 * n * trials)
    for i in range(trials):
        sample = observer_sample(
            q[i * n:(i + 1) * n], qdot[i * n:(i + 1) * n],
            memory[6 * n * i:6 * n * (i + 1)],
            model[2 * n * n * i:2 * n * n * (i + 1)], u[i * n:(i + 1) * n],
            noise[i * n:(i + 1) * n], constants)
        tau[i * n:(i + 1) * n] = sample[:n]
        memory_out[6 * n * i:6 * n * (i + 1)] = sample[n:]
    return tau, memory_out


@njit(cache=True)
def integrator_samples(trials: int, fast: np.ndarray, gains: np.ndarray,
                       tau_request: np.ndarray, tau_observed: np.ndarray,
                       qdot: np.ndarray, constants: np.ndarray
                       ) -> Tuple[np.ndarray, np.ndarray]:
    """integrator_sample of each trial: (fast groups, u [N m]), stacked by trial.

    Args:
        trials: The number of trials.
        fast: The trials' fast groups (integrator_sample; trials (3 n + 2)).
        gains: The trials' model groups (log_layout.RhsState; trials (n^2 + 2 n + 4)).
        tau_request: The trials' tau_c^r [N m] (trials n).
        tau_observed: The trials' tau_obs(k) [N m] (trials n).
        qdot: The trials' joint rates [rad/s] (trials n).
        constants: integrator_sample's, every trial's."""
    n = qdot.shape[0] // trials
    fast_size, gains_size = fast.shape[0] // trials, gains.shape[0] // trials
    fast_out, u = np.empty(trials * fast_size), np.empty(trials * n)
    for i in range(trials):
        sample = integrator_sample(
            fast[fast_size * i:fast_size * (i + 1)],
            gains[gains_size * i:gains_size * (i + 1)],
            tau_request[i * n:(i + 1) * n], tau_observed[i * n:(i + 1) * n],
            qdot[i * n:(i + 1) * n], constants)
        fast_out[fast_size * i:fast_size * (i + 1)] = sample[:fast_size]
        u[i * n:(i + 1) * n] = sample[fast_size:]
    return fast_out, u


@njit(cache=True)
def integrator_sample(fast: np.ndarray, gains: np.ndarray, tau_request: np.ndarray,
                      tau_observed: np.ndarray, qdot: np.ndarray, constants: np.ndarray
                      ) -> np.ndarray:
    """One RhsIntegrator sample (its law), returning [fast after it (3 n + 2), u (n)].

    Args:
        fast: [u_I (n), e_tau (n), ||e_tau||, chi, tau_c^r(k-1) (n)] (RhsState's fast part).
        gains: [vec(B_hat^-1) (n^2), D_hat (n), K (n), ...] (RhsState's model group).
        tau_request: tau_c^r(k) [N m] (n).
        tau_observed: tau_obs(k) [N m] (n).
        qdot: The joint rates [rad/s] (n).
        constants: [h [s], chi_decay = e^(-h / chi_window), chi_floor [N m]], then
            optionally noisy (1: tau_obs carries measurement noise, and e_tau is its
            low-pass at c; absent or 0: e_tau is the error itself)."""
    n = tau_request.shape[0]
    h, chi_decay, chi_floor = constants[0], constants[1], constants[2]
    out = np.empty(4 * n + 2)
    e = fast[2 * n + 2:3 * n + 2] - tau_observed
    out[:n] = fast[:n] + h * gains[n * n + n:n * n + 2 * n] * e
    if constants.shape[0] > 3 and constants[3] > 0.0:
        a = 1.0 - np.exp(-gains[n * n + 2 * n] * h)
        out[n:2 * n] = fast[n:2 * n] + a * (e - fast[n:2 * n])
    else:
        out[n:2 * n] = e
    out[2 * n] = np.sqrt(dot(out[n:2 * n], out[n:2 * n]))
    out[2 * n + 1] = max(out[2 * n], fast[2 * n + 1] * chi_decay, chi_floor)
    out[2 * n + 2:3 * n + 2] = tau_request
    out[3 * n + 2:] = (matvec(gains[:n * n].reshape(n, n),
                              tau_request + gains[n * n:n * n + n] * qdot)
                       + out[:n])
    return out
