"""The reduced model of a spatial free-floating arm (dynamics.floating_model's, which
computes it with Drake's AutoDiff), compiled: for a kinematic tree of revolute joints
and welds on a free base (dynamics.kinematic_tree.KinematicTree), at the base's
identity pose (M and C' do not depend on it; Jacobians are turned to the base's
attitude by the caller).

Spatial vectors are (angular; linear) about the world origin O, in world axes
(Featherstone's Plucker coordinates). Joint j's motion subspace is
S_j = (a_j; p_j x a_j) (axis a_j through the point p_j); the base's velocities have
the subspace S_b (KinematicTree.base_subspace: the identity for a free base's
(omega, v_O)). With I_i body i's spatial inertia about O and Ic_j the composite
inertia of the bodies joint j moves,

    H_bb = S_b^T (sum_i I_i) S_b,  H_bj = S_b^T Ic_j S_j,
    H_jl = S_j^T Ic_l S_l (j at or above l, 0 on separate branches),

and a change of q_k turns everything joint k moves about S_k:
dS_j/dq_k = crm(S_k) S_j for a joint j below k, dIc/dq_k = crf(S_k) Ic' - Ic' crm(S_k)
for the part Ic' of a composite that joint k moves. The reduced model is then
M = H_mm - H_bm^T A, A = H_bb^-1 H_bm, with
dM_k = dH_mm - dH_bm^T A - A^T dH_bm + A^T dH_bb A (docs/equations.md E5-E9), and
C' the Christoffel form of dM (floating_model.FloatingBaseModel.Coriolis)."""
import numpy as np
from numba import njit

from dacph_drake.kernels.arm import matmul, matvec


@njit(cache=True)
def _rotation(axis, angle):
    """Rodrigues: the rotation by ``angle`` about the unit ``axis``."""
    x, y, z = axis[0], axis[1], axis[2]
    c, s = np.cos(angle), np.sin(angle)
    t = 1.0 - c
    R = np.empty((3, 3))
    R[0, 0], R[0, 1], R[0, 2] = t * x * x + c, t * x * y - s * z, t * x * z + s * y
    R[1, 0], R[1, 1], R[1, 2] = t * x * y + s * z, t * y * y + c, t * y * z - s * x
    R[2, 0], R[2, 1], R[2, 2] = t * x * z - s * y, t * y * z + s * x, t * z * z + c
    return R


@njit(cache=True)
def _cross(a, b):
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


@njit(cache=True)
def _dot(a, b):
    out = 0.0
    for i in range(a.shape[0]):
        out += a[i] * b[i]
    return out


@njit(cache=True)
def _skew(v):
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


@njit(cache=True)
def forward_kinematics(parent, joint, X_PF, axis, X_MC, q):
    """(X_WC (nodes, 4, 4), S (n, 6)): every body's pose and every joint's motion
    subspace, the base at the identity."""
    nodes, n = parent.shape[0], q.shape[0]
    X = np.empty((nodes, 4, 4))
    S = np.zeros((n, 6))
    X[0] = np.eye(4)
    for node in range(1, nodes):
        X_WF = matmul(X[parent[node]], X_PF[node])
        j = joint[node]
        if j >= 0:
            a = matvec(X_WF[:3, :3], axis[node])
            S[j, :3] = a
            S[j, 3:] = _cross(X_WF[:3, 3], a)
            X_WM = X_WF.copy()
            X_WM[:3, :3] = matmul(X_WF[:3, :3], _rotation(axis[node], q[j]))
            X[node] = matmul(X_WM, X_MC[node])
        else:
            X[node] = matmul(X_WF, X_MC[node])
    return X, S


@njit(cache=True)
def _spatial_inertias(X, mass, moment, inertia):
    """Each body's spatial inertia about O in world axes (zero for a massless body),
    from its mass, first moment m c and rotational inertia about its origin (body
    frame)."""
    nodes = X.shape[0]
    out = np.zeros((nodes, 6, 6))
    for node in range(nodes):
        m = mass[node]
        if m <= 0.0:
            continue
        R, p = X[node, :3, :3], X[node, :3, 3]
        c_B = moment[node] / m
        I_c = inertia[node] + m * matmul(_skew(c_B), _skew(c_B))   # about the c.o.m.
        c = p + matvec(R, c_B)
        C = _skew(c)
        out[node, :3, :3] = matmul(matmul(R, I_c), R.T) - m * matmul(C, C)
        out[node, :3, 3:] = m * C
        out[node, 3:, :3] = -m * C
        for i in range(3):
            out[node, 3 + i, 3 + i] = m
    return out


@njit(cache=True)
def _crm(v):
    """The motion cross product matrix: crm(v) w = v x w (spatial motions)."""
    out = np.zeros((6, 6))
    W, V = _skew(v[:3]), _skew(v[3:])
    out[:3, :3] = W
    out[3:, :3] = V
    out[3:, 3:] = W
    return out


@njit(cache=True)
def mass_matrix_and_derivatives(base_subspace, parent, joint, X_PF, axis, X_MC, below,
                                joint_below, mass, moment, inertia, q, derivatives):
    """(H (nb + n)^2, dH (n, nb + n, nb + n), X (nodes, 4, 4), S (n, 6)): the
    plant's mass matrix in (base; joints) order at the base's identity pose, its
    derivatives by q (zero unless ``derivatives``), the bodies' poses and the
    joints' motion subspaces."""
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
    crm = np.empty((n, 6, 6))
    turned = np.empty((n, 6, 6))          # X_k(Ic_k) = crf(S_k) Ic_k - Ic_k crm(S_k)
    for k in range(n):
        crm[k] = _crm(S[k])
        turned[k] = -matmul(crm[k].T, Ic[k]) - matmul(Ic[k], crm[k])
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
                value = _dot(S[j], IcS[l])
                H[nb + j, nb + l] = value
                H[nb + l, nb + j] = value
    dS = np.zeros((n, 6))
    dIcS = np.zeros((n, 6))               # d(Ic_l S_l)/dq_k
    for k in range(n if derivatives else 0):
        # Joint k turns what it moves about S_k: a motion m by crm(S_k) m, an
        # inertia's action Ic S by crf(S_k) Ic S - Ic crm(S_k) S.
        for j in range(n):
            if joint_below[k, j]:
                dS[j] = matvec(crm[k], S[j])
            else:
                dS[j] = 0.0
        for j in range(n):
            if joint_below[k, j]:               # Ic_j moves whole
                part, partS = Ic[j], IcS[j]
            elif j == k or joint_below[j, k]:   # the part of Ic_j below k moves
                part, partS = Ic[k], matvec(Ic[k], S[j])
            else:
                dIcS[j] = 0.0                   # nothing of Ic_j moves, S_j neither
                continue
            dIcS[j] = (-matvec(crm[k].T, partS) - matvec(part, matvec(crm[k], S[j]))
                       + matvec(Ic[j], dS[j]))
        dH[k, :nb, :nb] = matmul(SbT, matmul(turned[k], Sb))
        for j in range(n):
            column = matvec(SbT, dIcS[j])
            dH[k, :nb, nb + j] = column
            dH[k, nb + j, :nb] = column
        for j in range(n):
            for l in range(n):
                if j == l or joint_below[j, l]:
                    value = _dot(dS[j], IcS[l]) + _dot(S[j], dIcS[l])
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
def reduced_model(base_subspace, parent, joint, X_PF, axis, X_MC, below, joint_below,
                  mass, moment, inertia, q, derivatives=True):
    """(M, dM (n, n, n), A = H_bb^-1 H_bm (nb, n), X, S): the reduced model and what
    the Jacobians need (dM zero unless ``derivatives``)."""
    n, nb = q.shape[0], base_subspace.shape[1]
    H, dH, X, S = mass_matrix_and_derivatives(base_subspace, parent, joint, X_PF, axis,
                                              X_MC, below, joint_below, mass, moment,
                                              inertia, q, derivatives)
    Hbb, Hbm, Hmm = H[:nb, :nb], H[:nb, nb:], H[nb:, nb:]
    A = _cholesky_solve(Hbb, Hbm)
    M = Hmm - matmul(Hbm.T, A)
    dM = np.zeros((n, n, n))
    for k in range(n if derivatives else 0):
        dbb, dbm, dmm = dH[k, :nb, :nb], dH[k, :nb, nb:], dH[k, nb:, nb:]
        dM[k] = (dmm - matmul(dbm.T, A) - matmul(A.T, dbm)
                 + matmul(A.T, matmul(dbb, A)))
    return M, dM, A, X, S


@njit(cache=True)
def christoffel(dM, qdot):
    """C'(q, qdot)_ij = sum_k (dM_ij/dq_k + dM_ik/dq_j - dM_jk/dq_i) qdot_k / 2."""
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
def point_jacobian(base_subspace, parent, joint, X, S, A, node, p_W):
    """J_bar (6, n) of the point p_W (world, the base at the identity) fixed in the
    body ``node``: (omega; v) of the point = J_bar qdot at zero momentum."""
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
