"""The input ``reduced_model`` = [vec(M), vec(C')] of the LHS controller's last
sample, for the systems that need the port's momentum p = M qdot as the LHS
controller (and through it the port observer) sees it."""
from typing import Sequence

import numpy as np
from pydrake.systems.framework import Context, LeafSystem


class ReducedModelInput:
    """Declares input ``reduced_model`` on ``system`` and reads p = M qdot from it.

    The input has 2 n^2 entries per trial of ``models``, stacked.
    Momenta(context, q, qdot) is each trial's p = M qdot with M from it, or the
    trial's ``models[trial]``.Momentum(q, qdot) (the controller's nominal model)
    where it is not connected (a system tested alone). Reading M from the LHS keeps
    p the same function of the state in the learner's samples (the observer's p)
    and in the evaluation of B_hat(x), D_hat(x), also when the LHS's model is
    identified online (InertialIdentifier).

    Args:
        system: The system that declares the input.
        n: The number of joints.
        models: One model per trial of a batch (their Momentum(q, qdot)).
    """

    def __init__(self, system: LeafSystem, n: int, models: Sequence):
        self._n, self._models = n, list(models)
        self.port = system.DeclareVectorInputPort("reduced_model",
                                                  2 * n * n * len(self._models))

    def Momenta(self, context: Context, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
        """Every trial's p = M qdot.

        Args:
            context: The system's context.
            q: The trials' joint angles [rad] (trials x n).
            qdot: The trials' joint rates [rad/s] (trials x n).

        Returns:
            p (trials x n)."""
        if not self.port.HasValue(context):
            return np.array([model.Momentum(q_i, qdot_i) for model, q_i, qdot_i
                             in zip(self._models, q, qdot)])
        n = self._n
        M = self.port.Eval(context).reshape(-1, 2, n, n)[:, 0]
        return np.matmul(M, qdot[:, :, None])[:, :, 0]
