"""The reduced model of a spatial free-floating arm, compiled (dynamics.floating_model
documents it): a tree of revolute joints and welds on a free base at its identity pose.
Spatial vectors are (angular; linear) about the world origin O; S_j = (a_j; p_j x a_j),
S_b the base's, I_i body i's spatial inertia, Ic_j the composite joint j moves:

    H_bb = S_b^T (sum_i I_i) S_b,  H_bj = S_b^T Ic_j S_j,
    H_jl = S_j^T Ic_l S_l (l at or below j; 0 on separate branches),
    dS_j/dq_k = S_k x S_j (j below k),  dIc'/dq_k = crf(S_k) Ic' - Ic' crm(S_k),
    M = H_mm - H_bm^T A,  A = H_bb^-1 H_bm,
    dM_k = dH_mm - dH_bm^T A - A^T dH_bm + A^T dH_bb A    (docs/equations.md E5-E9),

Ic' the part of a composite that joint k moves, and C' the Christoffel form of dM."""
from typing import Tuple

import numpy as np
from numba import njit

from dacph_drake.kernels.arm import dot, matmul, matvec


@njit(cache=True)
def _rotation(axis, angle):
    """Rodrigues: the rotation by ``angle`` about the unit ``axis``."""
    R = np.empty((3, 3))
    _rotation_into(axis, angle, R)
    return R


@njit(cache=True)
def _cross(a, b):
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


@njit(cache=True)
def _skew(v):
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


@njit(cache=True)
def forward_kinematics(parent: np.ndarray, joint: np.ndarray, X_PF: np.ndarray,
                       axis: np.ndarray, X_MC: np.ndarray, q: np.ndarray
                       ) -> Tuple[np.ndarray, np.ndarray]:
    """(X_WC (nodes, 4, 4), S (n, 6)): the bodies' poses and joints' motion subspaces
    S_j = (a_j; p_j x a_j) about O in world axes, the base at the identity.

    Args:
        parent: Each node's parent node (nodes,), -1 for the base (node 0).
        joint: The joint moving each node (nodes,) (0..n-1), -1 for a weld.
        X_PF: Each joint's frame F in its parent body's frame (nodes, 4, 4) [m].
        axis: Each joint's unit axis in its frame F (nodes, 3) (zero for a weld).
        X_MC: Each body's frame C in its joint's moving frame M (nodes, 4, 4) [m].
        q: The joint angles (n) [rad]."""
    nodes, n = parent.shape[0], q.shape[0]
    X = np.empty((nodes, 4, 4))
    S = np.zeros((n, 6))
    X[0] = np.eye(4)
    X_WF, X_WM, R, RR = np.empty((4, 4)), np.empty((4, 4)), np.empty((3, 3)), \
        np.empty((3, 3))
    for node in range(1, nodes):
        _product_into(X[parent[node]], X_PF[node], X_WF)
        j = joint[node]
        if j >= 0:
            a0, a1, a2 = 0.0, 0.0, 0.0                  # a = R_WF axis (matvec)
            for k in range(3):
                a0 += X_WF[0, k] * axis[node, k]
                a1 += X_WF[1, k] * axis[node, k]
                a2 += X_WF[2, k] * axis[node, k]
            S[j, 0], S[j, 1], S[j, 2] = a0, a1, a2
            p0, p1, p2 = X_WF[0, 3], X_WF[1, 3], X_WF[2, 3]
            S[j, 3], S[j, 4], S[j, 5] = p1 * a2 - p2 * a1, p2 * a0 - p0 * a2, \
                p0 * a1 - p1 * a0
            _rotation_into(axis[node], q[j], R)
            _product_into(X_WF[:3, :3], R, RR)
            X_WM[:, :] = X_WF
            X_WM[:3, :3] = RR
            _product_into(X_WM, X_MC[node], X[node])
        else:
            _product_into(X_WF, X_MC[node], X[node])
    return X, S


@njit(cache=True)
def _product_into(A, B, out):
    """out = A B, summed as arm.matmul sums it."""
    for i in range(A.shape[0]):
        for j in range(B.shape[1]):
            out[i, j] = 0.0
        for k in range(A.shape[1]):
            a = A[i, k]
            for j in range(B.shape[1]):
                out[i, j] += a * B[k, j]


@njit(cache=True)
def _rotation_into(axis, angle, R):
    """_rotation written into R."""
    x, y, z = axis[0], axis[1], axis[2]
    c, s = np.cos(angle), np.sin(angle)
    t = 1.0 - c
    R[0, 0], R[0, 1], R[0, 2] = t * x * x + c, t * x * y - s * z, t * x * z + s * y
    R[1, 0], R[1, 1], R[1, 2] = t * x * y + s * z, t * y * y + c, t * y * z - s * x
    R[2, 0], R[2, 1], R[2, 2] = t * x * z - s * y, t * y * z + s * x, t * z * z + c


@njit(cache=True)
def _spatial_inertias(X, mass, moment, inertia):
    """Each body's spatial inertia about O in world axes (zero if massless):
    [[R I_c R^T - m [c]x^2, m [c]x], [-m [c]x, m 1]], c = p + R c_B."""
    nodes = X.shape[0]
    out = np.zeros((nodes, 6, 6))
    I_c, RI = np.empty((3, 3)), np.empty((3, 3))
    for node in range(nodes):
        m = mass[node]
        if m <= 0.0:
            continue
        c_B = moment[node] / m
        cc = c_B[0] * c_B[0] + c_B[1] * c_B[1] + c_B[2] * c_B[2]
        for i in range(3):                  # parallel axes: I_c = I_o - m (|c|^2 1 - c c^T)
            for j in range(3):
                I_c[i, j] = inertia[node, i, j] + m * c_B[i] * c_B[j]
            I_c[i, i] -= m * cc
        c = np.empty(3)
        for i in range(3):
            c[i] = X[node, i, 3]
            for k in range(3):
                c[i] += X[node, i, k] * c_B[k]
        for i in range(3):
            for j in range(3):
                value = 0.0
                for k in range(3):
                    value += X[node, i, k] * I_c[k, j]
                RI[i, j] = value
        cc = c[0] * c[0] + c[1] * c[1] + c[2] * c[2]
        for i in range(3):
            for j in range(3):
                value = 0.0
                for k in range(3):
                    value += RI[i, k] * X[node, j, k]
                out[node, i, j] = value - m * c[i] * c[j]    # - m [c]x^2
            out[node, i, i] += m * cc
            out[node, 3 + i, 3 + i] = m
        out[node, 0, 4], out[node, 0, 5] = -m * c[2], m * c[1]      # m [c]x
        out[node, 1, 3], out[node, 1, 5] = m * c[2], -m * c[0]
        out[node, 2, 3], out[node, 2, 4] = -m * c[1], m * c[0]
        for i in range(3):
            for j in range(3):
                out[node, 3 + i, j] = out[node, j, 3 + i]            # -m [c]x = (m [c]x)^T
    return out


@njit(cache=True)
def _motion_cross_matrix(a, out):
    """out = crm(a), the 6 x 6 matrix of m -> a x m (_motion_cross)."""
    out[:] = 0.0
    for block in range(2):
        o = 3 * block
        out[o, o + 1], out[o, o + 2] = -a[2], a[1]
        out[o + 1, o], out[o + 1, o + 2] = a[2], -a[0]
        out[o + 2, o], out[o + 2, o + 1] = -a[1], a[0]
    out[3, 1], out[3, 2] = -a[5], a[4]
    out[4, 0], out[4, 2] = a[5], -a[3]
    out[5, 0], out[5, 1] = -a[4], a[3]


@njit(cache=True)
def mass_matrix_and_derivatives(base_subspace: np.ndarray, parent: np.ndarray,
                                joint: np.ndarray, X_PF: np.ndarray, axis: np.ndarray,
                                X_MC: np.ndarray, below: np.ndarray,
                                joint_below: np.ndarray, mass: np.ndarray,
                                moment: np.ndarray, inertia: np.ndarray,
                                reflected: np.ndarray, q: np.ndarray, derivatives: bool
                                ) -> Tuple[np.ndarray, np.ndarray, np.ndarray,
                                           np.ndarray]:
    """(H (nb + n)^2 in (base; joints) order, dH[k] = dH/dq_k, X, S) at the base's identity
    pose, the reflected inertias on H's joint diagonal as Drake adds them.

    Args:
        base_subspace: S_b, the base velocities' motion subspace (6, nb; nb = 6 or 3).
        parent: Each node's parent node (nodes,), -1 for the base (node 0).
        joint: The joint moving each node (nodes,) (0..n-1), -1 for a weld.
        X_PF: Each joint's frame F in its parent body's frame (nodes, 4, 4) [m].
        axis: Each joint's unit axis in its frame F (nodes, 3) (zero for a weld).
        X_MC: Each body's frame C in its joint's moving frame M (nodes, 4, 4) [m].
        below: True where joint k moves the node (n, nodes).
        joint_below: True where joint k moves joint j's axis, j != k (n, n).
        mass: Each body's mass (nodes,) [kg] (zero: a massless body).
        moment: Each body's first moment m c in its frame (nodes, 3) [kg m].
        inertia: Each body's rotational inertia about its origin, in its frame [kg m^2].
        reflected: Each joint's reflected inertia rho^2 I_r (n,) [kg m^2].
        q: The joint angles (n) [rad].
        derivatives: Whether to compute dH (zero otherwise)."""
    n, nodes, nb = q.shape[0], parent.shape[0], base_subspace.shape[1]
    X, S = forward_kinematics(parent, joint, X_PF, axis, X_MC, q)
    I = _spatial_inertias(X, mass, moment, inertia)
    Sb, SbT = base_subspace, base_subspace.T
    total = np.zeros((6, 6))
    for node in range(nodes):
        total += I[node]
    Ic = np.zeros((n, 6, 6))
    for j in range(n):
        for node in range(nodes):
            if below[j, node]:
                Ic[j] += I[node]
    N = nb + n
    H = np.zeros((N, N))
    dH = np.zeros((n, N, N))
    H[:nb, :nb] = matmul(SbT, matmul(total, Sb))
    IcS = np.empty((n, 6))
    for j in range(n):
        IcS[j] = matvec(Ic[j], S[j])
        column = matvec(SbT, IcS[j])
        H[:nb, nb + j] = column
        H[nb + j, :nb] = column
    for j in range(n):
        for l in range(n):
            if j == l or joint_below[j, l]:
                value = dot(S[j], IcS[l])
                H[nb + j, nb + l] = value
                H[nb + l, nb + j] = value
        H[nb + j, nb + j] += reflected[j]
    if not derivatives:
        return H, dH, X, S
    dS = np.zeros((n, 6))                 # dS_j/dq_k
    dIcS = np.zeros((n, 6))               # d(Ic_j S_j)/dq_k
    crm = np.empty((6, 6))                # S_k x (a motion)
    turned = np.empty((6, 6))             # crf(S_k) Ic_k - Ic_k crm(S_k)
    turned_Sb = np.empty((6, nb))
    for k in range(n):
        # Joint k turns what it moves about S_k: a motion m by S_k x m, an
        # inertia's action Ic S by S_k x* (Ic S) - Ic (S_k x S); crf = -crm^T.
        _motion_cross_matrix(S[k], crm)
        for i in range(6):
            for c in range(6):
                value = 0.0
                for m in range(6):
                    value -= crm[m, i] * Ic[k, m, c] + Ic[k, i, m] * crm[m, c]
                turned[i, c] = value
        for j in range(n):
            moved = joint_below[k, j]           # Ic_j and S_j turn as one
            partly = j == k or joint_below[j, k]  # the part of Ic_j below k moves
            for i in range(6):
                motion, force = 0.0, 0.0
                if moved:
                    for m in range(6):
                        motion += crm[i, m] * S[j, m]
                        force -= crm[m, i] * IcS[j, m]
                elif partly:
                    for m in range(6):
                        force += turned[i, m] * S[j, m]
                dS[j, i], dIcS[j, i] = motion, force   # else nothing of either moves
        for i in range(6):
            for c in range(nb):
                value = 0.0
                for m in range(6):
                    value += turned[i, m] * Sb[m, c]
                turned_Sb[i, c] = value
        for r in range(nb):
            for c in range(nb):
                value = 0.0
                for m in range(6):
                    value += Sb[m, r] * turned_Sb[m, c]
                dH[k, r, c] = value
            for j in range(n):
                value = 0.0
                for m in range(6):
                    value += Sb[m, r] * dIcS[j, m]
                dH[k, r, nb + j] = value
                dH[k, nb + j, r] = value
        for j in range(n):
            for l in range(n):
                if j == l or joint_below[j, l]:
                    value = dot(dS[j], IcS[l]) + dot(S[j], dIcS[l])
                    dH[k, nb + j, nb + l] = value
                    dH[k, nb + l, nb + j] = value
    return H, dH, X, S


@njit(cache=True)
def _cholesky_solve(A, B):
    """A^-1 B for a symmetric positive definite A (small: the base's 6 x 6)."""
    m = A.shape[0]
    L = np.zeros((m, m))
    for i in range(m):
        for j in range(i + 1):
            s = A[i, j]
            for k in range(j):
                s -= L[i, k] * L[j, k]
            L[i, j] = np.sqrt(s) if i == j else s / L[j, j]
    Y = B.copy()
    for i in range(m):
        for k in range(i):
            Y[i] -= L[i, k] * Y[k]
        Y[i] /= L[i, i]
    for i in range(m - 1, -1, -1):
        for k in range(i + 1, m):
            Y[i] -= L[k, i] * Y[k]
        Y[i] /= L[i, i]
    return Y


@njit(cache=True)
def reduced_model(base_subspace: np.ndarray, parent: np.ndarray, joint: np.ndarray,
                  X_PF: np.ndarray, axis: np.ndarray, X_MC: np.ndarray,
                  below: np.ndarray, joint_below: np.ndarray, mass: np.ndarray,
                  moment: np.ndarray, inertia: np.ndarray, reflected: np.ndarray,
                  q: np.ndarray, derivatives: bool = True) -> tuple:
    """(M (n, n), dM (n, n, n), A = H_bb^-1 H_bm (nb, n), dA (n, nb, n), X, S),
    dA_k = H_bb^-1 (dH_bm/dq_k - dH_bb/dq_k A).

    Args:
        base_subspace: S_b, the base velocities' motion subspace (6, nb; nb = 6 or 3).
        parent: Each node's parent node (nodes,), -1 for the base (node 0).
        joint: The joint moving each node (nodes,) (0..n-1), -1 for a weld.
        X_PF: Each joint's frame F in its parent body's frame (nodes, 4, 4) [m].
        axis: Each joint's unit axis in its frame F (nodes, 3) (zero for a weld).
        X_MC: Each body's frame C in its joint's moving frame M (nodes, 4, 4) [m].
        below: True where joint k moves the node (n, nodes).
        joint_below: True where joint k moves joint j's axis, j != k (n, n).
        mass: Each body's mass (nodes,) [kg] (zero: a massless body).
        moment: Each body's first moment m c in its frame (nodes, 3) [kg m].
        inertia: Each body's rotational inertia about its origin, in its frame [kg m^2].
        reflected: Each joint's reflected inertia rho^2 I_r (n,) [kg m^2].
        q: The joint angles (n) [rad].
        derivatives: Whether to compute dM and dA (zero otherwise)."""
    n, nb = q.shape[0], base_subspace.shape[1]
    H, dH, X, S = mass_matrix_and_derivatives(base_subspace, parent, joint, X_PF, axis,
                                              X_MC, below, joint_below, mass, moment,
                                              inertia, reflected, q, derivatives)
    Hbb, Hbm, Hmm = H[:nb, :nb], H[:nb, nb:], H[nb:, nb:]
    A = _cholesky_solve(Hbb, Hbm)
    M = Hmm - matmul(Hbm.T, A)
    dM = np.zeros((n, n, n))
    dA = np.zeros((n, nb, n))
    if not derivatives:
        return M, dM, A, dA, X, S
    moved = np.empty((nb, n * n))     # T_k = dH_bm - dH_bb A, side by side
    for k in range(n):
        for r in range(nb):
            for c in range(n):
                value = dH[k, r, nb + c]
                for m in range(nb):
                    value -= dH[k, r, m] * A[m, c]
                moved[r, k * n + c] = value
        for i in range(n):            # dM_k = dH_mm - dH_bm^T A - A^T T_k
            for j in range(n):
                value = dH[k, nb + i, nb + j]
                for m in range(nb):
                    value -= dH[k, m, nb + i] * A[m, j] + A[m, i] * moved[m, k * n + j]
                dM[k, i, j] = value
    solved = _cholesky_solve(Hbb, moved)
    for k in range(n):
        dA[k] = solved[:, k * n:(k + 1) * n]
    return M, dM, A, dA, X, S


@njit(cache=True)
def christoffel(dM: np.ndarray, qdot: np.ndarray) -> np.ndarray:
    """C' (n, n): C'(q, qdot)_ij = sum_k (dM_ij/dq_k + dM_ik/dq_j - dM_jk/dq_i) qdot_k / 2.

    Args:
        dM: dM[k] = dM/dq_k (n, n, n).
        qdot: The joint rates (n) [rad/s]."""
    n = qdot.shape[0]
    C = np.zeros((n, n))
    for i in range(n):
        for j in range(n):
            value = 0.0
            for k in range(n):
                value += (dM[k, i, j] + dM[j, i, k] - dM[i, j, k]) * qdot[k]
            C[i, j] = 0.5 * value
    return C


@njit(cache=True)
def point_jacobian(base_subspace: np.ndarray, parent: np.ndarray, joint: np.ndarray,
                   X: np.ndarray, S: np.ndarray, A: np.ndarray, node: int,
                   p_W: np.ndarray) -> np.ndarray:
    """The GJM J_bar (6, n) of a body's point: (omega; v) = J_bar qdot at zero momentum.

    Args:
        base_subspace: S_b, the base velocities' motion subspace (6, nb; nb = 6 or 3).
        parent: Each node's parent node (nodes,), -1 for the base (node 0).
        joint: The joint moving each node (nodes,) (0..n-1), -1 for a weld.
        X: The bodies' poses (nodes, 4, 4) (forward_kinematics; unused here).
        S: The joints' motion subspaces (n, 6) (forward_kinematics).
        A: H_bb^-1 H_bm (nb, n) (reduced_model).
        node: The body's node.
        p_W: The point (3) [m], in the world, the base at the identity."""
    n, nb = S.shape[0], base_subspace.shape[1]
    J = np.zeros((6, nb + n))
    J[:, :nb] = base_subspace
    ancestor = node
    while ancestor > 0:
        j = joint[ancestor]
        if j >= 0:
            J[:, nb + j] = S[j]
        ancestor = parent[ancestor]
    P = _skew(p_W)
    out = np.empty((6, nb + n))
    out[:3] = J[:3]
    out[3:] = J[3:] - matmul(P, J[:3])    # v_P = v_O + omega x p
    return out[:, nb:] - matmul(out[:, :nb], A)


@njit(cache=True)
def base_pose_and_twist(base_subspace: np.ndarray, base_pose: np.ndarray,
                        base_velocity: np.ndarray
                        ) -> Tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(R_WB (3, 3), p_WB (3) [m], omega_B (3) [rad/s], v_B (3) [m/s]): the base's pose and
    twist in its own axes (the quaternion normalized).

    Args:
        base_subspace: S_b (6, nb): nb = 3 for a planar base, 6 for a free one.
        base_pose: Planar (x, y, theta) [m, rad] or floating (qw, qx, qy, qz, x, y, z) [m].
        base_velocity: Planar (vx, vy, omega) or floating (omega, v), world [rad/s, m/s]."""
    R, p = np.zeros((3, 3)), np.zeros(3)
    omega_W, v_W = np.zeros(3), np.zeros(3)
    if base_subspace.shape[1] == 3:
        c, s = np.cos(base_pose[2]), np.sin(base_pose[2])
        R[0, 0], R[0, 1], R[1, 0], R[1, 1], R[2, 2] = c, -s, s, c, 1.0
        p[0], p[1] = base_pose[0], base_pose[1]
        v_W[0], v_W[1], omega_W[2] = base_velocity[0], base_velocity[1], base_velocity[2]
    else:
        norm = np.sqrt(base_pose[0]**2 + base_pose[1]**2 + base_pose[2]**2
                       + base_pose[3]**2)
        w, x, y, z = (base_pose[0] / norm, base_pose[1] / norm, base_pose[2] / norm,
                      base_pose[3] / norm)
        R[0, 0], R[0, 1], R[0, 2] = 1 - 2 * (y * y + z * z), 2 * (x * y - w * z), \
            2 * (x * z + w * y)
        R[1, 0], R[1, 1], R[1, 2] = 2 * (x * y + w * z), 1 - 2 * (x * x + z * z), \
            2 * (y * z - w * x)
        R[2, 0], R[2, 1], R[2, 2] = 2 * (x * z - w * y), 2 * (y * z + w * x), \
            1 - 2 * (x * x + y * y)
        for i in range(3):
            p[i] = base_pose[4 + i]
            omega_W[i], v_W[i] = base_velocity[i], base_velocity[3 + i]
    omega_B, v_B = np.zeros(3), np.zeros(3)
    for i in range(3):
        for k in range(3):
            omega_B[i] += R[k, i] * omega_W[k]
            v_B[i] += R[k, i] * v_W[k]
    return R, p, omega_B, v_B


@njit(cache=True)
def body_twist_into(V: np.ndarray, omega_B: np.ndarray, v_B: np.ndarray,
                    S: np.ndarray, qdot: np.ndarray, below: np.ndarray,
                    node: int) -> None:
    """V = (omega; v_O) of a body about the base's origin in its axes: (omega_B; v_B) plus
    S_k qdot_k of every joint k moving it.

    Args:
        V: The output (6), overwritten.
        omega_B: The base's angular velocity in its axes (3) [rad/s].
        v_B: The velocity of the base's origin in its axes (3) [m/s].
        S: The joints' motion subspaces (n, 6) (forward_kinematics).
        qdot: The joint rates (n) [rad/s].
        below: True where joint k moves the node (n, nodes).
        node: The body's node."""
    for r in range(3):
        V[r], V[3 + r] = omega_B[r], v_B[r]
    for k in range(qdot.shape[0]):
        if below[k, node]:
            for r in range(6):
                V[r] += S[k, r] * qdot[k]


@njit(cache=True)
def joint_momentum(base_subspace: np.ndarray, parent: np.ndarray, joint: np.ndarray,
                   X_PF: np.ndarray, axis: np.ndarray, X_MC: np.ndarray,
                   below: np.ndarray, mass: np.ndarray, moment: np.ndarray,
                   inertia: np.ndarray, reflected: np.ndarray, base_pose: np.ndarray,
                   base_velocity: np.ndarray, q: np.ndarray, qdot: np.ndarray
                   ) -> np.ndarray:
    """p (n), the joint rows of H(q) v, about the base's origin in its axes:

        p_j = S_j . sum_{bodies C joint j moves} h_C,   h_C = (L_C; P_C),
        V_C = (omega; v_O) = (omega_B; v_B) + sum_{joints k moving C} S_k qdot_k,
        P_C = m (v_O + omega x c),  L_C = R I_c R^T omega + c x P_C,

    c the centre of mass, I_c the inertia about it; plus the reflected inertias' rates.

    Args:
        base_subspace: S_b, the base velocities' motion subspace (6, nb; nb = 6 or 3).
        parent: Each node's parent node (nodes,), -1 for the base (node 0).
        joint: The joint moving each node (nodes,) (0..n-1), -1 for a weld.
        X_PF: Each joint's frame F in its parent body's frame (nodes, 4, 4) [m].
        axis: Each joint's unit axis in its frame F (nodes, 3) (zero for a weld).
        X_MC: Each body's frame C in its joint's moving frame M (nodes, 4, 4) [m].
        below: True where joint k moves the node (n, nodes).
        mass: Each body's mass (nodes,) [kg] (zero: a massless body).
        moment: Each body's first moment m c in its frame (nodes, 3) [kg m].
        inertia: Each body's rotational inertia about its origin, in its frame [kg m^2].
        reflected: Each joint's reflected inertia rho^2 I_r (n,) [kg m^2].
        base_pose: Planar (x, y, theta) [m, rad] or floating (qw, qx, qy, qz, x, y, z) [m].
        base_velocity: Planar (vx, vy, omega) or floating (omega, v), world [rad/s, m/s].
        q: The joint angles (n) [rad].
        qdot: The joint rates (n) [rad/s]."""
    n, nodes = q.shape[0], parent.shape[0]
    X, S = forward_kinematics(parent, joint, X_PF, axis, X_MC, q)
    _, _, omega_B, v_B = base_pose_and_twist(base_subspace, base_pose, base_velocity)
    p = np.zeros(n)
    V, h, c_B, c, w, Iw = (np.empty(6), np.empty(6), np.empty(3), np.empty(3),
                           np.empty(3), np.empty(3))
    for node in range(nodes):
        m = mass[node]
        if m <= 0.0:
            continue
        body_twist_into(V, omega_B, v_B, S, qdot, below, node)
        cc = 0.0
        for r in range(3):
            c_B[r] = moment[node, r] / m
            cc += c_B[r] * c_B[r]
        for r in range(3):          # c = p + R c_B, w = R^T omega (body axes)
            c[r], w[r] = X[node, r, 3], 0.0
            for k in range(3):
                c[r] += X[node, r, k] * c_B[k]
                w[r] += X[node, k, r] * V[k]
        for r in range(3):          # I_c w, I_c = I_o - m (|c_B|^2 1 - c_B c_B^T)
            value = -m * cc * w[r]
            for k in range(3):
                value += (inertia[node, r, k] + m * c_B[r] * c_B[k]) * w[k]
            Iw[r] = value
        # P = m (v_O + omega x c); L = R (I_c w) + c x P.
        h[3] = m * (V[3] + V[1] * c[2] - V[2] * c[1])
        h[4] = m * (V[4] + V[2] * c[0] - V[0] * c[2])
        h[5] = m * (V[5] + V[0] * c[1] - V[1] * c[0])
        for r in range(3):
            h[r] = X[node, r, 0] * Iw[0] + X[node, r, 1] * Iw[1] + X[node, r, 2] * Iw[2]
        h[0] += c[1] * h[5] - c[2] * h[4]
        h[1] += c[2] * h[3] - c[0] * h[5]
        h[2] += c[0] * h[4] - c[1] * h[3]
        for j in range(n):
            if below[j, node]:
                p[j] += dot(S[j], h)
    for j in range(n):
        p[j] += reflected[j] * qdot[j]
    return p
