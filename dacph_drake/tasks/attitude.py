"""The end-effector attitude task of a spatial arm (the LHS's task in 3D; planar arms
track the scalar alpha): attitude error on SO(3), the 3 x n task Jacobian from the
GJM's angular rows, and the damped pseudo-inverse law for the reference joint rates

    nu = D^+ (omega_d - Lambda e) + (I - D^+ D) xi,    D^+ = D^T (D D^T + mu^2 I)^-1,

mu the damping that keeps nu bounded near singular configurations (mu = 0: the
Moore-Penrose pseudo-inverse of a full-rank D)."""
import numpy as np
from pydrake.math import RotationMatrix


def attitude_error(R_WE: RotationMatrix, R_WD: RotationMatrix) -> np.ndarray:
    """e = 2 sgn(eta) epsilon, (eta, epsilon) the quaternion of the world-frame error
    rotation R_WE R_WD^T: |e| = 2 sin(theta / 2) for an error of angle theta about
    the axis epsilon / |epsilon|, so e equals the rotation vector theta k to first
    order; the sign picks the shorter way round (either quaternion of the double
    cover gives the same e). With omega_E = omega_d - Lambda e, e decays as
    exp(-Lambda t) to first order."""
    error = (R_WE @ R_WD.inverse()).ToQuaternion()
    epsilon = np.array([error.x(), error.y(), error.z()])
    return 2.0 * (1.0 if error.w() >= 0.0 else -1.0) * epsilon


def damped_pseudo_inverse(D: np.ndarray, damping: float) -> np.ndarray:
    """D^+ = D^T (D D^T + damping^2 I)^-1 (n x m for an m x n task Jacobian D)."""
    m = D.shape[0]
    return D.T @ np.linalg.inv(D @ D.T + damping**2 * np.eye(m))


def reference_rates(D: np.ndarray, omega_d: np.ndarray, e: np.ndarray,
                    Lambda: float, xi: np.ndarray, damping: float) -> np.ndarray:
    """nu = D^+ (omega_d - Lambda e) + (I - D^+ D) xi: the task rate in the range of
    D^+, the secondary motion xi (for example the potential field's descent) in its
    null space."""
    D_plus = damped_pseudo_inverse(D, damping)
    return D_plus @ (omega_d - Lambda * e) + (np.eye(D.shape[1]) - D_plus @ D) @ xi
