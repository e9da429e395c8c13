"""Input ``reduced_model`` = [vec(M), vec(C')] of the LHS controller's last sample."""
from typing import Sequence

import numpy as np
from pydrake.systems.framework import Context, LeafSystem


class ReducedModelInput:
    """Declares input ``reduced_model`` on ``system`` and reads p = M qdot from it, so p is
    the same function of the state for the learner and for B_hat(x), D_hat(x).

    Args:
        system: The system that declares the input.
        n: The number of joints.
        models: Each trial's nominal model, whose Momentum(q, qdot) serves unconnected."""

    def __init__(self, system: LeafSystem, n: int, models: Sequence):
        self._n, self._models = n, list(models)
        self.port = system.DeclareVectorInputPort("reduced_model",
                                                  2 * n * n * len(self._models))

    def Momenta(self, context: Context, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
        """Every trial's p = M qdot (trials x n; M from the input, else its model's).

        Args:
            context: The system's context.
            q: The trials' joint angles [rad] (trials x n).
            qdot: The trials' joint rates [rad/s] (trials x n)."""
        if not self.port.HasValue(context):
            return np.array([model.Momentum(q_i, qdot_i) for model, q_i, qdot_i
                             in zip(self._models, q, qdot)])
        n = self._n
        M = self.port.Eval(context).reshape(-1, 2, n, n)[:, 0]
        return np.matmul(M, qdot[:, :, None])[:, :, 0]
