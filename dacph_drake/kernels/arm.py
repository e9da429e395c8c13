"""The reduced model of a planar free-floating arm from its trigonometric mass matrix
(reduced_model.ReducedOrderModel fits and checks it): H(q) = coefficients @ psi(q),
psi = (1, cos s_r, sin s_r), s_r = the sum of the joint angles in range r."""
from typing import Tuple

import numpy as np
from numba import njit


# Small dense products as loops: numba's @ calls BLAS through SciPy, which the
# project does not need.
@njit(cache=True)
def matmul(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """A B (m x l), a new array (loops: no BLAS).

    Args:
        A: A matrix (m x k).
        B: A matrix (k x l)."""
    out = np.zeros((A.shape[0], B.shape[1]))
    for i in range(A.shape[0]):
        for k in range(A.shape[1]):
            a = A[i, k]
            for j in range(B.shape[1]):
                out[i, j] += a * B[k, j]
    return out


@njit(cache=True)
def matvec(A: np.ndarray, x: np.ndarray) -> np.ndarray:
    """A x (m), a new array (loops: no BLAS).

    Args:
        A: A matrix (m x k).
        x: A vector (k)."""
    out = np.zeros(A.shape[0])
    for i in range(A.shape[0]):
        for k in range(A.shape[1]):
            out[i] += A[i, k] * x[k]
    return out


@njit(cache=True)
def dot(a: np.ndarray, b: np.ndarray) -> float:
    """The scalar product a . b (a loop).

    Args:
        a: A vector (m).
        b: A vector (m)."""
    out = 0.0
    for i in range(a.shape[0]):
        out += a[i] * b[i]
    return out


@njit(cache=True)
def mass_matrix_and_derivatives(q: np.ndarray, coefficients: np.ndarray,
                                ranges: np.ndarray) -> np.ndarray:
    """[H, dH/dq_1, ..., dH/dq_n] (1 + n, N, N): H = C psi(q), dH/dq_k = C dpsi/dq_k.

    Args:
        q: The joint angles (n) [rad].
        coefficients: C (N^2, 1 + 2 R), N = n + 3: row i N + j holds H_ij's coefficients
            (velocities vx, vy, omega0, qdot).
        ranges: (R, n), 1 where joint k is in range r, s_r = ranges[r] . q, R = n(n+1)/2."""
    n = q.shape[0]
    R = ranges.shape[0]
    N = n + 3
    s = matvec(ranges, q)
    c, si = np.cos(s), np.sin(s)
    out = np.empty((1 + n, N * N))
    for e in range(N * N):
        value = coefficients[e, 0]
        for r in range(R):
            value += coefficients[e, 1 + r] * c[r] + coefficients[e, 1 + R + r] * si[r]
        out[0, e] = value
        for k in range(n):
            d = 0.0
            for r in range(R):
                if ranges[r, k] != 0.0:
                    d += coefficients[e, 1 + R + r] * c[r] - coefficients[e, 1 + r] * si[r]
            out[1 + k, e] = d
    return out.reshape(1 + n, N, N)


@njit(cache=True)
def inverse3(A: np.ndarray) -> np.ndarray:
    """The inverse A^-1 (3 x 3) of a 3 x 3 matrix (adjugate over determinant).

    Args:
        A: An invertible 3 x 3 matrix."""
    out = np.empty((3, 3))
    out[0, 0] = A[1, 1] * A[2, 2] - A[1, 2] * A[2, 1]
    out[0, 1] = A[0, 2] * A[2, 1] - A[0, 1] * A[2, 2]
    out[0, 2] = A[0, 1] * A[1, 2] - A[0, 2] * A[1, 1]
    out[1, 0] = A[1, 2] * A[2, 0] - A[1, 0] * A[2, 2]
    out[1, 1] = A[0, 0] * A[2, 2] - A[0, 2] * A[2, 0]
    out[1, 2] = A[0, 2] * A[1, 0] - A[0, 0] * A[1, 2]
    out[2, 0] = A[1, 0] * A[2, 1] - A[1, 1] * A[2, 0]
    out[2, 1] = A[0, 1] * A[2, 0] - A[0, 0] * A[2, 1]
    out[2, 2] = A[0, 0] * A[1, 1] - A[0, 1] * A[1, 0]
    det = A[0, 0] * out[0, 0] + A[0, 1] * out[1, 0] + A[0, 2] * out[2, 0]
    return out / det


@njit(cache=True)
def reduced_dynamics(q: np.ndarray, qdot: np.ndarray, coefficients: np.ndarray,
                     ranges: np.ndarray
                     ) -> Tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(M (n, n), C' (n, n), D (n), dD (n, n)) at (q, qdot), as ReducedOrderModel.Evaluate:

        M = W^T H W, dM/dq_k = W^T dH/dq_k W, W = [-A; I], A = H_bb^-1 H_bm,
        C'_ij = (Mdot_ij + G_ji - G_ij) / 2, G_ij = sum_k dM_jk/dq_i qdot_k,
        D = 1 - A[2] (alpha_dot = D qdot), dD[k] = -d(A[2])/dq_k.

    Args:
        q: The joint angles (n) [rad].
        qdot: The joint rates (n) [rad/s].
        coefficients: H's trigonometric coefficients (N^2, 1 + 2 R), N = n + 3.
        ranges: The joint-angle ranges (R, n) (mass_matrix_and_derivatives)."""
    n = q.shape[0]
    N = n + 3
    H = mass_matrix_and_derivatives(q, coefficients, ranges)
    Hbb_inv = inverse3(np.ascontiguousarray(H[0, :3, :3]))
    A = matmul(Hbb_inv, np.ascontiguousarray(H[0, :3, 3:]))
    W = np.zeros((N, n))
    for i in range(n):
        W[0, i], W[1, i], W[2, i] = -A[0, i], -A[1, i], -A[2, i]
        W[3 + i, i] = 1.0
    M = np.empty((n, n))
    dM = np.empty((n, n, n))
    dD = np.empty((n, n))
    HW = np.empty((N, n))
    for k in range(1 + n):
        # HW = H_k W, then W^T HW, as matmul sums them (in place).
        for i in range(N):
            for j in range(n):
                HW[i, j] = 0.0
            for m in range(N):
                h = H[k, i, m]
                for j in range(n):
                    HW[i, j] += h * W[m, j]
        for i in range(n):
            for j in range(n):
                value = 0.0
                for m in range(N):
                    value += W[m, i] * HW[m, j]
                if k == 0:
                    M[i, j] = value
                else:
                    dM[k - 1, i, j] = value
        if k > 0:
            for j in range(n):
                dD[k - 1, j] = -(Hbb_inv[2, 0] * HW[0, j] + Hbb_inv[2, 1] * HW[1, j]
                                 + Hbb_inv[2, 2] * HW[2, j])
    # Loops rather than array expressions: each of those compiles into a kernel of
    # its own and multiplies the one-time compile time.
    C = np.empty((n, n))
    D = np.empty(n)
    for i in range(n):
        D[i] = 1.0 - A[2, i]
        for j in range(n):
            Mdot_ij, G_ij, G_ji = 0.0, 0.0, 0.0
            for k in range(n):
                Mdot_ij += qdot[k] * dM[k, i, j]
                G_ij += dM[i, j, k] * qdot[k]
                G_ji += dM[j, i, k] * qdot[k]
            C[i, j] = 0.5 * (Mdot_ij + G_ji - G_ij)
    return M, C, D, dD


@njit(cache=True)
def joint_momentum(theta0: float, base_velocity: np.ndarray, q: np.ndarray,
                   qdot: np.ndarray, coefficients: np.ndarray, ranges: np.ndarray
                   ) -> np.ndarray:
    """p (n) = H(q)[3:] T v of a planar arm, T turning the base's velocity into its frame.

    Args:
        theta0: The base angle [rad].
        base_velocity: The base velocity (vx, vy [m/s], omega0 [rad/s]) in the world (3).
        q: The joint angles (n) [rad].
        qdot: The joint rates (n) [rad/s].
        coefficients: H's trigonometric coefficients (N^2, 1 + 2 R), N = n + 3.
        ranges: The joint-angle ranges (R, n) (mass_matrix_and_derivatives)."""
    n, R = q.shape[0], ranges.shape[0]
    p = np.empty(n)
    _joint_momentum_into(theta0, base_velocity[0], base_velocity[1], base_velocity[2],
                         q, qdot, coefficients, ranges, np.empty(R), np.empty(R), p)
    return p


@njit(cache=True)
def _joint_momentum_into(theta0, vx, vy, omega0, q, qdot, coefficients, ranges, c, si,
                         p):
    """joint_momentum into p (c, si: work arrays (R)): H's joint rows only, no dH."""
    n = q.shape[0]
    R = ranges.shape[0]
    N = n + 3
    for r in range(R):
        s = 0.0
        for k in range(n):
            s += ranges[r, k] * q[k]
        c[r], si[r] = np.cos(s), np.sin(s)
    cos0, sin0 = np.cos(theta0), np.sin(theta0)
    v0 = cos0 * vx + sin0 * vy
    v1 = -sin0 * vx + cos0 * vy
    for i in range(n):
        p[i] = 0.0
        for j in range(N):
            e = (3 + i) * N + j
            value = coefficients[e, 0]
            for r in range(R):
                value += coefficients[e, 1 + r] * c[r] + coefficients[e, 1 + R + r] * si[r]
            v = v0 if j == 0 else v1 if j == 1 else omega0 if j == 2 else qdot[j - 3]
            p[i] += value * v
