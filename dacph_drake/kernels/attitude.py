"""The AttitudeController's task, compiled (systems/attitude_controller.py states the
law): the reference R_d(t), the attitude error and the reference joint rates with
their exact rate along the motion, at a configuration of the compiled reduced model
(kernels/spatial.py); and the base's attitude turned along the motion."""
from typing import Tuple

import numpy as np
from numba import njit

from dacph_drake.kernels.arm import inverse3, matmul, matvec
from dacph_drake.kernels.spatial import (_cholesky_solve, _cross, _rotation, _skew,
                                         christoffel, reduced_model)

COUPLING_ITERATIONS = 40        # power iterations of coupling_ratio (rho to ~1e-3)


@njit(cache=True)
def quaternion_rotation(quaternion: np.ndarray) -> np.ndarray:
    """The rotation matrix of a quaternion.

    Args:
        quaternion: (w, x, y, z) (normalized here).

    Returns:
        R (3 x 3)."""
    w, x, y, z = quaternion / np.sqrt(np.sum(quaternion * quaternion))
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


@njit(cache=True)
def rotation_quaternion(R: np.ndarray) -> np.ndarray:
    """The quaternion of a rotation matrix, with w >= 0 (Shepperd's method).

    Args:
        R: The rotation matrix (3 x 3).

    Returns:
        (w, x, y, z)."""
    trace = R[0, 0] + R[1, 1] + R[2, 2]
    out = np.empty(4)
    if trace >= max(R[0, 0], R[1, 1], R[2, 2]):
        r = np.sqrt(1.0 + trace)
        out[0], out[1] = 0.5 * r, 0.5 * (R[2, 1] - R[1, 2]) / r
        out[2], out[3] = 0.5 * (R[0, 2] - R[2, 0]) / r, 0.5 * (R[1, 0] - R[0, 1]) / r
    elif R[0, 0] >= R[1, 1] and R[0, 0] >= R[2, 2]:
        r = np.sqrt(1.0 + R[0, 0] - R[1, 1] - R[2, 2])
        out[0], out[1] = 0.5 * (R[2, 1] - R[1, 2]) / r, 0.5 * r
        out[2], out[3] = 0.5 * (R[0, 1] + R[1, 0]) / r, 0.5 * (R[0, 2] + R[2, 0]) / r
    elif R[1, 1] >= R[2, 2]:
        r = np.sqrt(1.0 - R[0, 0] + R[1, 1] - R[2, 2])
        out[0], out[1] = 0.5 * (R[0, 2] - R[2, 0]) / r, 0.5 * (R[0, 1] + R[1, 0]) / r
        out[2], out[3] = 0.5 * r, 0.5 * (R[1, 2] + R[2, 1]) / r
    else:
        r = np.sqrt(1.0 - R[0, 0] - R[1, 1] + R[2, 2])
        out[0], out[1] = 0.5 * (R[1, 0] - R[0, 1]) / r, 0.5 * (R[0, 2] + R[2, 0]) / r
        out[2], out[3] = 0.5 * (R[1, 2] + R[2, 1]) / r, 0.5 * r
    if out[0] < 0:
        out = -out
    return out


@njit(cache=True)
def turned(quaternion: np.ndarray, rotation_vector: np.ndarray) -> np.ndarray:
    """An attitude turned by a rotation vector in the world frame.

    Args:
        quaternion: The attitude (w, x, y, z).
        rotation_vector: The turn, axis times angle (3) [rad], in the world frame.

    Returns:
        The turned attitude's quaternion (w, x, y, z), w >= 0."""
    angle = np.sqrt(np.sum(rotation_vector * rotation_vector))
    R = quaternion_rotation(quaternion)
    if angle > 0:
        R = matmul(_rotation(rotation_vector / angle, angle), R)
    return rotation_quaternion(R)


@njit(cache=True)
def reference_rates(D: np.ndarray, D_dot: np.ndarray, r: np.ndarray, r_dot: np.ndarray,
                    xi: np.ndarray, xi_dot: np.ndarray, damping: float
                    ) -> Tuple[np.ndarray, np.ndarray]:
    """The reference joint rates nu and their rate.

    nu = D^+ r + (I - D^+ D) xi, D^+ = D^T G^-1, G = D D^T + mu^2 I
    (dynamics.attitude.reference_rates with r = omega_d - Lambda e), and its rate

        nu_dot = dD^+ (r - D xi) + D^+ (r_dot - D_dot xi - D xi_dot) + xi_dot,
        dD^+ = D_dot^T G^-1 - D^T G^-1 (D_dot D^T + D D_dot^T) G^-1.

    Args:
        D: The task Jacobian (m x n, m = 3: attitude; 6: pose).
        D_dot: Its rate along the motion (m x n).
        r: The task rate asked for, e.g. omega_d - Lambda e (m).
        r_dot: Its rate (m).
        xi: The secondary motion (n) [rad/s].
        xi_dot: Its rate (n) [rad/s^2].
        damping: The damped pseudo-inverse's mu.

    Returns:
        (nu, nu_dot) (n each)."""
    G = matmul(D, D.T)
    m = D.shape[0]
    for i in range(m):
        G[i, i] += damping * damping
    G_inverse = inverse3(G) if m == 3 else _cholesky_solve(G, np.eye(m))
    D_plus = matmul(D.T, G_inverse)
    G_dot = matmul(D_dot, D.T)
    G_dot = G_dot + G_dot.T
    D_plus_dot = (matmul(D_dot.T, G_inverse)
                  - matmul(D_plus, matmul(G_dot, G_inverse)))
    task = r - matvec(D, xi)
    nu = matvec(D_plus, task) + xi
    nu_dot = (matvec(D_plus_dot, task)
              + matvec(D_plus, r_dot - matvec(D_dot, xi) - matvec(D, xi_dot)) + xi_dot)
    return nu, nu_dot


@njit(cache=True)
def desired_attitude(R_d0: np.ndarray, axis: np.ndarray, amplitude: float, omega: float,
                     t: float) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The reference attitude of scenario.AttitudeReference.At and its rates.

    Args:
        R_d0: The reference's starting attitude (3 x 3).
        axis: The unit axis of the oscillation, in R_d0's frame (3).
        amplitude: The oscillation's amplitude [rad].
        omega: Its angular frequency 2 pi / period [rad/s].
        t: The time [s].

    Returns:
        (R_d(t) (3 x 3), omega_d(t) [rad/s], omega_d_dot(t) [rad/s^2]), world frame."""
    phi = amplitude * np.sin(omega * t)
    phi_dot = amplitude * omega * np.cos(omega * t)
    phi_ddot = -omega * omega * phi
    axis_W = matvec(R_d0, axis)
    return matmul(R_d0, _rotation(axis, phi)), axis_W * phi_dot, axis_W * phi_ddot


@njit(cache=True)
def desired_position(position: np.ndarray, t: float
                     ) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """p_d(t) = p_d0 + axis amplitude sin(omega t) and its rates (world).

    Args:
        position: [p_CE (3), p_d0 (3), unit axis (3, world), amplitude [m],
            omega [rad/s], 1 for the position rows alone else 0].
        t: The time [s].

    Returns:
        (p_d [m], v_d [m/s], a_d [m/s^2]) (3 each)."""
    axis, amplitude, omega = position[6:9], position[9], position[10]
    return (position[3:6] + axis * (amplitude * np.sin(omega * t)),
            axis * (amplitude * omega * np.cos(omega * t)),
            axis * (-amplitude * omega * omega * np.sin(omega * t)))


@njit(cache=True)
def twist_jacobian(base_subspace: np.ndarray, parent: np.ndarray, joint: np.ndarray,
                   joint_below: np.ndarray, evaluation: tuple, qdot: np.ndarray,
                   node: int, rows: int) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """G = S_m - S_b A, the twist of a node's body about the base origin per qdot at zero
    momentum (base at the identity), its rate G_dot (columns crm(w_j) S_j - S_b dA qdot,
    w_j the twist of the joints above j) and the joints' own twist of the body.

    Args:
        base_subspace: S_b (6, nb).
        parent: Each node's parent node, -1 for the base.
        joint: The joint moving each node, -1 for a weld.
        joint_below: True where joint k moves joint j's axis (n, n).
        evaluation: The compiled model at the configuration (M, dM, A, dA, X, S).
        qdot: The joint rates (n) [rad/s].
        node: The body's node.
        rows: 3: the angular rows only (the linear ones left 0); 6: all.

    Returns:
        (G (6 x n), G_dot (6 x n), sum over the body's joints of S_j qdot_j (6))."""
    A, dA, S = evaluation[2], evaluation[3], evaluation[5]
    n, nb = qdot.shape[0], base_subspace.shape[1]
    G, G_dot = np.zeros((6, n)), np.zeros((6, n))
    for i in range(rows):
        for c in range(n):
            value, rate = 0.0, 0.0
            for m in range(nb):
                value -= base_subspace[i, m] * A[m, c]
                for k in range(n):
                    rate -= base_subspace[i, m] * dA[k, m, c] * qdot[k]
            G[i, c], G_dot[i, c] = value, rate
    relative, w = np.zeros(6), np.empty(6)
    twist = 3 if rows == 3 else 6          # the entries of w the rows need
    ancestor = node
    while ancestor > 0:
        j = joint[ancestor]
        if j >= 0:
            w[:] = 0.0
            for k in range(n):
                if joint_below[k, j]:
                    for i in range(twist):
                        w[i] += qdot[k] * S[k, i]
            for i in range(6):
                if i < rows:
                    G[i, j] += S[j, i]
                relative[i] += qdot[j] * S[j, i]
            G_dot[0, j] += w[1] * S[j, 2] - w[2] * S[j, 1]
            G_dot[1, j] += w[2] * S[j, 0] - w[0] * S[j, 2]
            G_dot[2, j] += w[0] * S[j, 1] - w[1] * S[j, 0]
            if rows == 6:                  # omega_w x S_lin + v_w x S_ang
                G_dot[3, j] += (w[1] * S[j, 5] - w[2] * S[j, 4]
                                + w[4] * S[j, 2] - w[5] * S[j, 1])
                G_dot[4, j] += (w[2] * S[j, 3] - w[0] * S[j, 5]
                                + w[5] * S[j, 0] - w[3] * S[j, 2])
                G_dot[5, j] += (w[0] * S[j, 4] - w[1] * S[j, 3]
                                + w[3] * S[j, 1] - w[4] * S[j, 0])
        ancestor = parent[ancestor]
    return G, G_dot, relative


@njit(cache=True)
def position_rows(base_subspace: np.ndarray, parent: np.ndarray, joint: np.ndarray,
                  joint_below: np.ndarray, evaluation: tuple, qdot: np.ndarray,
                  quaternion: np.ndarray, base_position: np.ndarray,
                  base_velocity: np.ndarray, node: int, p_CE: np.ndarray
                  ) -> Tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The end effector's position p_E, velocity v_E and the GJM's linear rows with their
    exact rate (world frame): J = G_lin + G_ang x p, J_dot = G_lin_dot + G_ang_dot x p
    + G_ang x p_dot (G from twist_jacobian); D = R_WB J, D_dot = [omega_b]x D + R_WB J_dot,
    v_E = v_b + omega_b x (R_WB p) + R_WB p_dot.

    Args:
        base_subspace: S_b (6, nb).
        parent: Each node's parent node, -1 for the base.
        joint: The joint moving each node, -1 for a weld.
        joint_below: True where joint k moves joint j's axis (n, n).
        evaluation: The compiled model at the configuration (M, dM, A, dA, X, S).
        qdot: The joint rates (n) [rad/s].
        quaternion: The base's attitude (w, x, y, z).
        base_position: The base's origin in the world [m].
        base_velocity: The base's (omega_W, v_W) (6).
        node: The end effector's node.
        p_CE: E's position in its node's body [m].

    Returns:
        (p_E [m], v_E [m/s], D (3 x n), D_dot (3 x n))."""
    X, n = evaluation[4], qdot.shape[0]
    G, G_dot, relative = twist_jacobian(base_subspace, parent, joint, joint_below,
                                        evaluation, qdot, node, 6)
    p = matvec(X[node, :3, :3], p_CE) + X[node, :3, 3]
    p_dot = relative[3:] + _cross(relative[:3], p)
    J, J_dot = np.empty((3, n)), np.empty((3, n))
    for c in range(n):
        J[:, c] = G[3:, c] + _cross(G[:3, c], p)
        J_dot[:, c] = (G_dot[3:, c] + _cross(G_dot[:3, c], p)
                       + _cross(G[:3, c], p_dot))
    R_WB = quaternion_rotation(quaternion)
    omega_base = base_velocity[:3]
    D = matmul(R_WB, J)
    D_dot = matmul(_skew(omega_base), D) + matmul(R_WB, J_dot)
    p_W = matvec(R_WB, p)
    v_E = base_velocity[3:] + _cross(omega_base, p_W) + matvec(R_WB, p_dot)
    return base_position + p_W, v_E, D, D_dot


@njit(cache=True)
def attitude_rows(base_subspace: np.ndarray, parent: np.ndarray, joint: np.ndarray,
                  joint_below: np.ndarray, evaluation: tuple, qdot: np.ndarray,
                  quaternion: np.ndarray, omega_base: np.ndarray, t: float,
                  reference: tuple, end_effector: tuple, Lambda: float) -> tuple:
    """The attitude task's rows (task_rates states them): D, D_dot, the task rate
    r = omega_d - Lambda e asked for and its rate, e and R_d.

    Args:
        base_subspace: S_b (6, nb).
        parent: Each node's parent node, -1 for the base.
        joint: The joint moving each node, -1 for a weld.
        joint_below: True where joint k moves joint j's axis (n, n).
        evaluation: The compiled model at the configuration.
        qdot: The joint rates (n) [rad/s].
        quaternion: The base's attitude (w, x, y, z).
        omega_base: omega_b (3) [rad/s], world frame.
        t: The time [s].
        reference: (R_d0, unit axis, amplitude, 2 pi / period).
        end_effector: (node, R_CE).
        Lambda: [1/s].

    Returns:
        (D (3 x n), D_dot, r (3), r_dot (3), e (3), R_d (3 x 3))."""
    X = evaluation[4]
    node, R_CE = end_effector
    R_WB = quaternion_rotation(quaternion)
    R_WE = matmul(R_WB, matmul(X[node, :3, :3], R_CE))
    R_d, omega_d, omega_d_dot = desired_attitude(reference[0], reference[1],
                                                 reference[2], reference[3], t)
    R_err = matmul(R_WE, R_d.T)
    error = rotation_quaternion(R_err)                  # eta >= 0
    e = 2.0 * error[1:]
    G, G_dot, relative = twist_jacobian(base_subspace, parent, joint, joint_below,
                                        evaluation, qdot, node, 3)
    D = matmul(R_WB, G[:3])
    D_dot = matmul(_skew(omega_base), D) + matmul(R_WB, G_dot[:3])
    omega_error = omega_base + matvec(R_WB, relative[:3]) - matvec(R_err, omega_d)
    e_dot = error[0] * omega_error + _cross(omega_error, error[1:])
    return D, D_dot, omega_d - Lambda * e, omega_d_dot - Lambda * e_dot, e, R_d


@njit(cache=True)
def task_rates(base_subspace: np.ndarray, parent: np.ndarray, joint: np.ndarray,
               joint_below: np.ndarray, evaluation: tuple, qdot: np.ndarray,
               quaternion: np.ndarray, omega_base: np.ndarray, t: float,
               reference: tuple, end_effector: tuple, xi: np.ndarray,
               xi_dot: np.ndarray, Lambda: float, damping: float
               ) -> Tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The reference joint rates nu, their exact rate nu_dot and the attitude error e:

        D = R_WB D_B,  D_B = sum over the end effector's joints of a_j e_j^T - S_b A
        D_dot = [omega_b]x D + R_WB (sum_j (w_j x a_j) e_j^T - S_b A_dot),
        A_dot = sum_k dA_k qdot_k, w_j = sum of a_k qdot_k over the joints k above j
        e_dot = eta omega_err + omega_err x epsilon,  omega_err = omega_E - R_err omega_d

    (a_j joint j's axis in the base frame, (eta, epsilon) the quaternion of
    R_err = R_WE R_d^T, omega_E = omega_b + R_WB sum_j a_j qdot_j).

    Args:
        base_subspace: S_b (6, nb) (KinematicTree.base_subspace).
        parent: Each node's parent node, -1 for the base (node 0).
        joint: The joint moving each node (0..n-1), -1 for a weld.
        joint_below: True where joint k moves joint j's axis, j != k (n, n).
        evaluation: FloatingBaseModel.Evaluate with derivatives (M, dM, A, dA, X, S).
        qdot: The joint rates (n) [rad/s].
        quaternion: The base's attitude (w, x, y, z).
        omega_base: The base's angular velocity omega_b (3) [rad/s], world frame.
        t: The time [s].
        reference: (R_d0, unit axis, amplitude, 2 pi / period) (desired_attitude).
        end_effector: (node, R_CE): its node and its frame's rotation in the node's body.
        xi: The secondary motion (n) [rad/s].
        xi_dot: Its rate (n) [rad/s^2].
        Lambda: The task error's gain Lambda [1/s].
        damping: The damped pseudo-inverse's mu (reference_rates).

    Returns:
        (nu (n), nu_dot (n), e (3), R_d (3 x 3))."""
    D, D_dot, r, r_dot, e, R_d = attitude_rows(
        base_subspace, parent, joint, joint_below, evaluation, qdot, quaternion,
        omega_base, t, reference, end_effector, Lambda)
    nu, nu_dot = reference_rates(D, D_dot, r, r_dot, xi, xi_dot, damping)
    return nu, nu_dot, e, R_d


@njit(cache=True)
def pose_rates(base_subspace: np.ndarray, parent: np.ndarray, joint: np.ndarray,
               joint_below: np.ndarray, evaluation: tuple, qdot: np.ndarray,
               base_pose: np.ndarray, base_velocity: np.ndarray, t: float,
               reference: tuple, end_effector: tuple, position: np.ndarray, xi: np.ndarray,
               xi_dot: np.ndarray, Lambda: float, damping: float) -> tuple:
    """The pose task's reference joint rates: attitude_rows and position_rows stacked,
    r = [omega_d - Lambda e; v_d - Lambda e_p], e_p = p_E - p_d(t).

    Args:
        base_subspace: S_b (6, nb).
        parent: Each node's parent node, -1 for the base.
        joint: The joint moving each node, -1 for a weld.
        joint_below: True where joint k moves joint j's axis (n, n).
        evaluation: The compiled model at the configuration.
        qdot: The joint rates (n) [rad/s].
        base_pose: The base's (qw, qx, qy, qz, x, y, z).
        base_velocity: The base's (omega_W, v_W) (6).
        t: The time [s].
        reference: The attitude reference (desired_attitude).
        end_effector: (node, R_CE).
        position: desired_position's arguments (p_CE first).
        xi: The secondary motion (n) [rad/s].
        xi_dot: Its rate (n).
        Lambda: [1/s].
        damping: mu.

    Returns:
        (nu, nu_dot, e (3), R_d, e_p (3) [m], p_d (3) [m])."""
    D, D_dot, r, r_dot, e, R_d = attitude_rows(
        base_subspace, parent, joint, joint_below, evaluation, qdot, base_pose[:4],
        base_velocity[:3], t, reference, end_effector, Lambda)
    D_p, D_p_dot, r_p, r_p_dot, e_p, p_d = position_task_rows(
        base_subspace, parent, joint, joint_below, evaluation, qdot, base_pose,
        base_velocity, t, end_effector, position, Lambda)
    nu, nu_dot = reference_rates(
        np.vstack((D, D_p)), np.vstack((D_dot, D_p_dot)), np.concatenate((r, r_p)),
        np.concatenate((r_dot, r_p_dot)), xi, xi_dot, damping)
    return nu, nu_dot, e, R_d, e_p, p_d


@njit(cache=True)
def position_task_rows(base_subspace: np.ndarray, parent: np.ndarray, joint: np.ndarray,
                       joint_below: np.ndarray, evaluation: tuple, qdot: np.ndarray,
                       base_pose: np.ndarray, base_velocity: np.ndarray, t: float,
                       end_effector: tuple, position: np.ndarray, Lambda: float) -> tuple:
    """The position rows (position_rows) with their reference: r_p = v_d - Lambda e_p,
    e_p = p_E - p_d(t), r_p_dot = a_d - Lambda (v_E - v_d).

    Args:
        base_subspace: S_b (6, nb).
        parent: Each node's parent node, -1 for the base.
        joint: The joint moving each node, -1 for a weld.
        joint_below: True where joint k moves joint j's axis (n, n).
        evaluation: The compiled model at the configuration.
        qdot: The joint rates (n) [rad/s].
        base_pose: The base's (qw, qx, qy, qz, x, y, z).
        base_velocity: The base's (omega_W, v_W) (6).
        t: The time [s].
        end_effector: (node, R_CE).
        position: desired_position's arguments (p_CE first).
        Lambda: [1/s].

    Returns:
        (D_p (3 x n) [m], D_p_dot, r_p [m/s], r_p_dot [m/s^2], e_p [m], p_d [m])."""
    p_E, v_E, D_p, D_p_dot = position_rows(
        base_subspace, parent, joint, joint_below, evaluation, qdot, base_pose[:4],
        base_pose[4:], base_velocity, end_effector[0], position[:3])
    p_d, v_d, a_d = desired_position(position, t)
    e_p = p_E - p_d
    return D_p, D_p_dot, v_d - Lambda * e_p, a_d - Lambda * (v_E - v_d), e_p, p_d


@njit(cache=True)
def position_rates(base_subspace: np.ndarray, parent: np.ndarray, joint: np.ndarray,
                   joint_below: np.ndarray, evaluation: tuple, qdot: np.ndarray,
                   base_pose: np.ndarray, base_velocity: np.ndarray, t: float,
                   end_effector: tuple, position: np.ndarray, xi: np.ndarray,
                   xi_dot: np.ndarray, Lambda: float, damping: float) -> tuple:
    """The position task's reference joint rates from position_task_rows alone.

    Args:
        base_subspace: S_b (6, nb).
        parent: Each node's parent node, -1 for the base.
        joint: The joint moving each node, -1 for a weld.
        joint_below: True where joint k moves joint j's axis (n, n).
        evaluation: The compiled model at the configuration.
        qdot: The joint rates (n) [rad/s].
        base_pose: The base's (qw, qx, qy, qz, x, y, z).
        base_velocity: The base's (omega_W, v_W) (6).
        t: The time [s].
        end_effector: (node, R_CE).
        position: desired_position's arguments (p_CE first).
        xi: The secondary motion (n) [rad/s].
        xi_dot: Its rate (n).
        Lambda: [1/s].
        damping: mu.

    Returns:
        (nu, nu_dot, e_p (3) [m], p_d (3) [m])."""
    D_p, D_p_dot, r_p, r_p_dot, e_p, p_d = position_task_rows(
        base_subspace, parent, joint, joint_below, evaluation, qdot, base_pose,
        base_velocity, t, end_effector, position, Lambda)
    nu, nu_dot = reference_rates(D_p, D_p_dot, r_p, r_p_dot, xi, xi_dot, damping)
    return nu, nu_dot, e_p, p_d


@njit(cache=True)
def coupling_ratio(M: np.ndarray) -> float:
    """rho = lambda_max(diag(M)^1/2 M^-1 diag(M)^1/2) >= 1 (1 for a diagonal M): how much
    lighter the lightest coupled motion is than M_ii say, by power iteration.

    Args:
        M: The reduced mass matrix (n x n), symmetric positive definite.

    Returns:
        rho."""
    n = M.shape[0]
    root = np.empty(n)
    for i in range(n):
        root[i] = np.sqrt(M[i, i])
    normalized = np.empty((n, n))
    for i in range(n):
        for j in range(n):
            normalized[i, j] = M[i, j] / (root[i] * root[j])
    inverse = _cholesky_solve(normalized, np.eye(n))
    v = np.ones(n) / np.sqrt(n)
    rho = 1.0
    for _ in range(COUPLING_ITERATIONS):
        w = matvec(inverse, v)
        rho = np.sqrt(np.sum(w * w))
        v = w / rho
    return rho


@njit(cache=True)
def attitude_update(tree: tuple, q: np.ndarray, qdot: np.ndarray, base_pose: np.ndarray,
                    base_velocity: np.ndarray, t: float, reference: tuple,
                    end_effector: tuple, position: np.ndarray, xi: np.ndarray,
                    xi_dot: np.ndarray, gains: np.ndarray, chi: float,
                    excitation: np.ndarray) -> tuple:
    """One AttitudeController update (its docstring states the law), from the compiled
    model at q: nu, nu_dot and e from task_rates (pose_rates for the pose task).

    Args:
        tree: The model's kernel arguments (FloatingBaseModel.kernel_tree).
        q: The joint angles (n) [rad].
        qdot: The joint rates (n) [rad/s].
        base_pose: The base's (qw, qx, qy, qz, x, y, z).
        base_velocity: The base's (omega_W, v_W) (6), world frame.
        t: The time [s].
        reference: (R_d0, unit axis, amplitude, 2 pi / period) (desired_attitude).
        end_effector: (node, R_CE) (task_rates).
        position: desired_position's arguments; an amplitude < 0: the attitude task.
        xi: The secondary motion (n) [rad/s].
        xi_dot: Its rate along the motion (n) [rad/s^2].
        gains: (Lambda, task_damping, damping_rate, epsilon, boundary_rate, rho_allowed,
            b_1, ..., b_n), b the joint damping [N m s/rad] (AttitudeController).
        chi: The robust term's gain chi (in DAC the RHS loop's bound on ||e_tau||) [N m].
        excitation: (a_1, ..., a_n, 2 pi f_1, ..., 2 pi f_n) of tau_pe, a [N m].

    Returns:
        (tau, M, C', [e, |e|, ||s||, V], the quaternion of R_d, [e_p, |e_p|, p_d]
            (zero for the attitude task))."""
    base_subspace, parent, joint, joint_below = tree[0], tree[1], tree[2], tree[7]
    evaluation = reduced_model(tree[0], tree[1], tree[2], tree[3], tree[4], tree[5],
                               tree[6], tree[7], tree[8], tree[9], tree[10], tree[11], q,
                               True)
    Lambda, damping, damping_rate, epsilon, boundary_rate = (
        gains[0], gains[1], gains[2], gains[3], gains[4])
    position_log = np.zeros(7)
    if position[9] < 0:
        nu, nu_dot, e, R_d = task_rates(base_subspace, parent, joint, joint_below,
                                        evaluation, qdot, base_pose[:4],
                                        base_velocity[:3], t, reference, end_effector,
                                        xi, xi_dot, Lambda, damping)
    elif position[11] > 0:
        nu, nu_dot, e_p, p_d = position_rates(
            base_subspace, parent, joint, joint_below, evaluation, qdot, base_pose,
            base_velocity, t, end_effector, position, xi, xi_dot, Lambda, damping)
        e, R_d = np.zeros(3), np.eye(3)
        position_log[:3], position_log[3] = e_p, np.sqrt(np.sum(e_p * e_p))
        position_log[4:] = p_d
    else:
        nu, nu_dot, e, R_d, e_p, p_d = pose_rates(
            base_subspace, parent, joint, joint_below, evaluation, qdot, base_pose,
            base_velocity, t, reference, end_effector, position, xi, xi_dot, Lambda,
            damping)
        position_log[:3], position_log[3] = e_p, np.sqrt(np.sum(e_p * e_p))
        position_log[4:] = p_d
    M, dM = evaluation[0], evaluation[1]
    C = christoffel(dM, qdot)
    s = qdot - nu
    Ms = matvec(M, s)
    phi = epsilon + chi * max(1.0, coupling_ratio(M) / gains[5]) / boundary_rate
    tau = matvec(M, nu_dot) + matvec(C, nu) - damping_rate * Ms
    for i in range(q.shape[0]):
        tau[i] += gains[6 + i] * nu[i] - chi * np.tanh(M[i, i] * s[i] / phi)
        if excitation[i] > 0:
            tau[i] += excitation[i] * np.sin(excitation[q.shape[0] + i] * t)
    log = np.array([e[0], e[1], e[2], np.sqrt(np.sum(e * e)), np.sqrt(np.sum(s * s)),
                    0.5 * np.sum(s * Ms)])
    return tau, M, C, log, rotation_quaternion(R_d), position_log
