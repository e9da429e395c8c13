"""The reduced models of free-floating arms at zero momentum (the planar closed form,
any plant's by AutoDiff), their inertial parameters and bounds, and the port's true
RHS model; ReducedModel is what the systems of the loop need of any of them."""
from typing import Protocol

import numpy as np


class ReducedModel(Protocol):
    """The controller's reduced model of a free-floating arm at zero momentum
    (reduced_model.ReducedOrderModel for planar arms, floating_model.FloatingBaseModel
    for described ones): M(q) qdot = p is the port's momentum."""
    num_joints: int

    def Momentum(self, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
        """p = M(q) qdot."""

    def MassMatrix(self, q: np.ndarray) -> np.ndarray:
        """M(q), the reduced mass matrix (n x n)."""
