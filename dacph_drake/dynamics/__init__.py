"""The reduced models of free-floating arms at zero momentum, their inertial parameters and
bounds, and the port's true RHS model; ReducedModel is what the loop's systems need."""
from typing import Protocol, Tuple

import numpy as np


class ReducedModel(Protocol):
    """The controller's reduced model (ReducedOrderModel for planar arms, FloatingBaseModel
    for described ones); M(q) qdot = p is the port's momentum.

    Attributes:
        num_joints: The number of the arm's joints n.
        joint_damping: The joint damping b (n) [N m s/rad], in the LHS model (planar: 0)."""
    num_joints: int
    joint_damping: np.ndarray

    def Momentum(self, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
        """The port's momentum p = M(q) qdot (n).

        Args:
            q: The joint angles (n) [rad].
            qdot: The joint rates (n) [rad/s]."""

    def MassMatrix(self, q: np.ndarray) -> np.ndarray:
        """The reduced mass matrix M(q) (n x n).

        Args:
            q: The joint angles (n) [rad]."""

    def MassMatrixAndDerivatives(self, q: np.ndarray
                                 ) -> Tuple[np.ndarray, np.ndarray]:
        """(M, dM), dM[k] = dM/dq_k (n x n x n).

        Args:
            q: The joint angles (n) [rad]."""
