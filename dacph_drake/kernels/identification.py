"""The inertial identifier's compiled body for a batch: the information Y^T Y of the
momentum regressor ([L about O; P] = Y(x) pi) and the reduced mass matrix M(q) of given
pi. The trials share one topology and stack their fixed transforms along a first axis."""
import numpy as np
from numba import njit

from dacph_drake.kernels.spatial import (base_pose_and_twist, body_twist_into,
                                         forward_kinematics, reduced_model)

PER_BODY = 10           # inertial_parameters.PER_BODY: [m, h (3), I (6)] per body


@njit(cache=True)
def momentum_regressor(base_subspace: np.ndarray, parent: np.ndarray, joint: np.ndarray,
                       X_PF: np.ndarray, axis: np.ndarray, X_MC: np.ndarray,
                       below: np.ndarray, nodes: np.ndarray, base_pose: np.ndarray,
                       base_velocity: np.ndarray, q: np.ndarray, qdot: np.ndarray
                       ) -> np.ndarray:
    """Y (6 x 10 bodies) at the state: [L about the world origin; P] = Y pi.

    Args:
        base_subspace: S_b, the base velocities' motion subspace (6, nb; nb = 6 or 3).
        parent: Each node's parent node (nodes,), -1 for the base (node 0).
        joint: The joint moving each node (nodes,) (0..n-1), -1 for a weld.
        X_PF: Each joint's frame F in its parent body's frame (nodes, 4, 4) [m].
        axis: Each joint's unit axis in its frame F (nodes, 3) (zero for a weld).
        X_MC: Each body's frame C in its joint's moving frame M (nodes, 4, 4) [m].
        below: True where joint k moves the node (n, nodes).
        nodes: Each parameter-carrying body's node (bodies,), in InertialParameters order.
        base_pose: Planar (x, y, theta) [m, rad] or floating (qw, qx, qy, qz, x, y, z) [m].
        base_velocity: Planar (vx, vy, omega) or floating (omega, v), world [rad/s, m/s].
        q: The joint angles (n) [rad].
        qdot: The joint rates (n) [rad/s]."""
    X, S = forward_kinematics(parent, joint, X_PF, axis, X_MC, q)
    R_WB, p_WB, omega_B, v_B = base_pose_and_twist(base_subspace, base_pose, base_velocity)
    Y = np.zeros((6, PER_BODY * nodes.shape[0]))
    R, o, omega, v = np.empty((3, 3)), np.empty(3), np.empty(3), np.empty(3)
    V, local = np.empty(6), np.empty(3)
    for b in range(nodes.shape[0]):
        node = nodes[b]
        body_twist_into(V, omega_B, v_B, S, qdot, below, node)
        # The origin's velocity in B's axes: V_lin + V_ang x p_BC.
        pc = X[node, :3, 3]
        local[0] = V[3] + V[1] * pc[2] - V[2] * pc[1]
        local[1] = V[4] + V[2] * pc[0] - V[0] * pc[2]
        local[2] = V[5] + V[0] * pc[1] - V[1] * pc[0]
        for i in range(3):
            o[i], omega[i], v[i] = p_WB[i], 0.0, 0.0
            for k in range(3):
                o[i] += R_WB[i, k] * pc[k]
                omega[i] += R_WB[i, k] * V[k]
                v[i] += R_WB[i, k] * local[k]
                value = 0.0
                for m in range(3):
                    value += R_WB[i, m] * X[node, m, k]
                R[i, k] = value
        _body_block(Y, PER_BODY * b, R, o, omega, v)
    return Y


@njit(cache=True)
def _body_block(Y, c, R, o, omega, v):
    """Body columns c..c+9 of Y: dP/dm = v, dP/dh = [omega]x R, dL/dm = o x v,
    dL/dh = -[v]x R + [o]x [omega]x R, dL/dI = R W(R^T omega)."""
    wR = np.empty((3, 3))
    for k in range(3):                       # [omega]x R, column k = omega x R_k
        wR[0, k] = omega[1] * R[2, k] - omega[2] * R[1, k]
        wR[1, k] = omega[2] * R[0, k] - omega[0] * R[2, k]
        wR[2, k] = omega[0] * R[1, k] - omega[1] * R[0, k]
    for i in range(3):
        Y[3 + i, c] = v[i]
        for k in range(3):
            Y[3 + i, c + 1 + k] = wR[i, k]
    Y[0, c] = o[1] * v[2] - o[2] * v[1]
    Y[1, c] = o[2] * v[0] - o[0] * v[2]
    Y[2, c] = o[0] * v[1] - o[1] * v[0]
    for k in range(3):   # -v x R_k + o x (omega x R_k)
        Y[0, c + 1 + k] = (-(v[1] * R[2, k] - v[2] * R[1, k])
                           + o[1] * wR[2, k] - o[2] * wR[1, k])
        Y[1, c + 1 + k] = (-(v[2] * R[0, k] - v[0] * R[2, k])
                           + o[2] * wR[0, k] - o[0] * wR[2, k])
        Y[2, c + 1 + k] = (-(v[0] * R[1, k] - v[1] * R[0, k])
                           + o[0] * wR[1, k] - o[1] * wR[0, k])
    w = np.zeros(3)                          # R^T omega
    for i in range(3):
        for k in range(3):
            w[i] += R[k, i] * omega[k]
    # W(w) theta = I w for theta = [Ixx, Iyy, Izz, Ixy, Ixz, Iyz].
    W = np.zeros((3, 6))
    W[0, 0], W[0, 3], W[0, 4] = w[0], w[1], w[2]
    W[1, 1], W[1, 3], W[1, 5] = w[1], w[0], w[2]
    W[2, 2], W[2, 4], W[2, 5] = w[2], w[0], w[1]
    for i in range(3):
        for k in range(6):
            value = 0.0
            for m in range(3):
                value += R[i, m] * W[m, k]
            Y[i, c + 4 + k] = value


@njit(cache=True)
def add_momentum_information(base_subspace: np.ndarray, parent: np.ndarray,
                             joint: np.ndarray, X_PFs: np.ndarray, axes: np.ndarray,
                             X_MCs: np.ndarray, below: np.ndarray, nodes: np.ndarray,
                             base_poses: np.ndarray, base_velocities: np.ndarray,
                             q: np.ndarray, qdot: np.ndarray,
                             information: np.ndarray) -> None:
    """information[i] += vec(Y_i^T Y_i) for every trial i (momentum_regressor at its rows).

    Args:
        base_subspace: S_b, the base velocities' motion subspace (6, nb; nb = 6 or 3).
        parent: Each node's parent node (nodes,), -1 for the base (node 0).
        joint: The joint moving each node (nodes,) (0..n-1), -1 for a weld.
        X_PFs: Each trial's joint frames F in their parent bodies (trials, nodes, 4, 4) [m].
        axes: Each trial's joint axes in F (trials, nodes, 3) (zero for a weld).
        X_MCs: Each trial's body frames C in the joints' frames M (trials, nodes, 4, 4) [m].
        below: True where joint k moves the node (n, nodes).
        nodes: Each parameter-carrying body's node (bodies,), in InertialParameters order.
        base_poses: Each trial's base joint positions (trials, base positions).
        base_velocities: Each trial's base joint velocities in the world (trials, nb).
        q: Each trial's joint angles (trials, n) [rad].
        qdot: Each trial's joint rates (trials, n) [rad/s].
        information: Each trial's vec(sum Y^T Y) (trials, (10 bodies)^2), added to."""
    size = PER_BODY * nodes.shape[0]
    for i in range(q.shape[0]):
        Y = momentum_regressor(base_subspace, parent, joint, X_PFs[i], axes[i], X_MCs[i],
                               below, nodes, base_poses[i], base_velocities[i], q[i],
                               qdot[i])
        for r in range(size):
            for c in range(size):
                value = 0.0
                for k in range(6):
                    value += Y[k, r] * Y[k, c]
                information[i, r * size + c] += value


@njit(cache=True)
def reduced_mass_matrices(base_subspace: np.ndarray, parent: np.ndarray,
                          joint: np.ndarray, X_PFs: np.ndarray, axes: np.ndarray,
                          X_MCs: np.ndarray, below: np.ndarray, joint_below: np.ndarray,
                          masses: np.ndarray, moments: np.ndarray, inertias: np.ndarray,
                          reflecteds: np.ndarray, nodes: np.ndarray, pis: np.ndarray,
                          q: np.ndarray
                          ) -> np.ndarray:
    """M(q_i) (trials, n, n), bodies at pis[i]; non-finite where H_bb is not PD.

    Args:
        base_subspace: S_b, the base velocities' motion subspace (6, nb; nb = 6 or 3).
        parent: Each node's parent node (nodes,), -1 for the base (node 0).
        joint: The joint moving each node (nodes,) (0..n-1), -1 for a weld.
        X_PFs: Each trial's joint frames F in their parent bodies (trials, nodes, 4, 4) [m].
        axes: Each trial's joint axes in F (trials, nodes, 3) (zero for a weld).
        X_MCs: Each trial's body frames C in the joints' frames M (trials, nodes, 4, 4) [m].
        below: True where joint k moves the node (n, nodes).
        joint_below: True where joint k moves joint j's axis, j != k (n, n).
        masses: Each trial's body masses (trials, nodes) [kg]; those in ``nodes`` replaced.
        moments: Each trial's first moments m c in body frames (trials, nodes, 3) [kg m].
        inertias: Each trial's rotational inertias about body origins (..., 3, 3) [kg m^2].
        reflecteds: Each trial's joints' reflected inertias (trials, n) [kg m^2].
        nodes: Each parameter-carrying body's node (bodies,), in InertialParameters order.
        pis: Each trial's inertial parameters (trials, 10 bodies; InertialParameters).
        q: Each trial's joint angles (trials, n) [rad]."""
    trials, n = q.shape[0], q.shape[1]
    out = np.empty((trials, n, n))
    for i in range(trials):
        mass, moment, inertia = masses[i].copy(), moments[i].copy(), inertias[i].copy()
        for b in range(nodes.shape[0]):
            node, block = nodes[b], pis[i, PER_BODY * b:PER_BODY * (b + 1)]
            mass[node] = block[0]
            for k in range(3):
                moment[node, k] = block[1 + k]
            xx, yy, zz, xy, xz, yz = block[4], block[5], block[6], block[7], block[8], \
                block[9]
            inertia[node, 0, 0], inertia[node, 1, 1], inertia[node, 2, 2] = xx, yy, zz
            inertia[node, 0, 1] = inertia[node, 1, 0] = xy
            inertia[node, 0, 2] = inertia[node, 2, 0] = xz
            inertia[node, 1, 2] = inertia[node, 2, 1] = yz
        out[i] = reduced_model(base_subspace, parent, joint, X_PFs[i], axes[i], X_MCs[i],
                               below, joint_below, mass, moment, inertia, reflecteds[i],
                               q[i], False)[0]
    return out
