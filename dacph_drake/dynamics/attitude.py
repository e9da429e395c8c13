"""The end-effector attitude task of a spatial arm: attitude error on SO(3), the 3 x n task
Jacobian (the GJM's angular rows) and the damped pseudo-inverse law

    nu = D^+ (omega_d - Lambda e) + (I - D^+ D) xi,    D^+ = D^T (D D^T + mu^2 I)^-1,

mu keeping nu bounded near singular configurations."""
from typing import Tuple

import numpy as np
from pydrake.common.eigen_geometry import AngleAxis
from pydrake.math import RotationMatrix

from dacph_drake.scenario import AttitudeReference


def attitude_error(R_WE: RotationMatrix, R_WD: RotationMatrix) -> np.ndarray:
    """The attitude error e = 2 sgn(eta) epsilon, (eta, epsilon) the quaternion of
    R_WE R_WD^T: |e| = 2 sin(theta / 2), e the rotation vector theta k to first order, the
    shorter way round; with omega_E = omega_d - Lambda e, e decays as exp(-Lambda t).

    Args:
        R_WE: The end effector's orientation in the world.
        R_WD: The desired orientation in the world.

    Returns:
        e (3), in the world frame."""
    error = (R_WE @ R_WD.inverse()).ToQuaternion()
    epsilon = np.array([error.x(), error.y(), error.z()])
    return 2.0 * (1.0 if error.w() >= 0.0 else -1.0) * epsilon


def damped_pseudo_inverse(D: np.ndarray, damping: float) -> np.ndarray:
    """The damped pseudo-inverse D^+ = D^T (D D^T + damping^2 I)^-1.

    Args:
        D: The task Jacobian (m x n).
        damping: The damping mu (0: the Moore-Penrose pseudo-inverse of a full-rank D).

    Returns:
        D^+ (n x m)."""
    m = D.shape[0]
    return D.T @ np.linalg.inv(D @ D.T + damping**2 * np.eye(m))


def reference_rates(D: np.ndarray, omega_d: np.ndarray, e: np.ndarray,
                    Lambda: float, xi: np.ndarray, damping: float) -> np.ndarray:
    """The reference joint rates nu = D^+ (omega_d - Lambda e) + (I - D^+ D) xi.

    Args:
        D: The task Jacobian (3 x n), the GJM's angular rows.
        omega_d: The desired angular velocity (3) [rad/s].
        e: The attitude error (3) (attitude_error).
        Lambda: The attitude error's gain [1/s].
        xi: The secondary motion (n) [rad/s], e.g. the potential field's descent.
        damping: The pseudo-inverse's damping mu (damped_pseudo_inverse).

    Returns:
        nu (n) [rad/s]."""
    D_plus = damped_pseudo_inverse(D, damping)
    return D_plus @ (omega_d - Lambda * e) + (np.eye(D.shape[1]) - D_plus @ D) @ xi


def reference_start(reference: AttitudeReference, R_WE0: RotationMatrix) -> RotationMatrix:
    """R_d(0): the attitude at q0 turned by initial_error about initial_error_axis.

    Args:
        reference: The scenario.AttitudeReference.
        R_WE0: The end effector's attitude at q0."""
    axis = np.asarray(reference.initial_error_axis, float)
    return RotationMatrix(AngleAxis(reference.initial_error,
                                    axis / np.linalg.norm(axis))) @ R_WE0


def reference_at(reference: AttitudeReference, R_d0: RotationMatrix, t: float
                 ) -> Tuple[RotationMatrix, np.ndarray]:
    """(R_d(t), omega_d(t) in the world [rad/s]) of scenario.AttitudeReference.

    Args:
        reference: The scenario.AttitudeReference.
        R_d0: R_d(0) (reference_start).
        t: The time [s]."""
    axis = np.asarray(reference.axis, float) / np.linalg.norm(reference.axis)
    w = 2 * np.pi / reference.period
    phi = reference.amplitude * np.sin(w * t)
    phi_dot = reference.amplitude * w * np.cos(w * t)
    return R_d0 @ RotationMatrix(AngleAxis(phi, axis)), R_d0.matrix() @ axis * phi_dot
