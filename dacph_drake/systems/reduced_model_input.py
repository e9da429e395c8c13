"""The input ``reduced_model`` = [vec(M), vec(C')] of the LHS controller's last
sample, for the systems that need the port's momentum p = M qdot as the LHS
controller (and through it the port observer) sees it."""
import numpy as np
from pydrake.systems.framework import LeafSystem


class ReducedModelInput:
    """Declares input ``reduced_model`` (2 n^2) on ``system``; Momentum(context, q,
    qdot) is p = M qdot with M from it, or ``model``.Momentum(q, qdot) (the
    controller's nominal model) where it is not connected (a system tested alone).
    Reading M from the LHS keeps p the same function of the state in the learner's
    samples (the observer's p) and in the evaluation of B_hat(x), D_hat(x), also
    when the LHS's model is identified online (InertialIdentifier)."""

    def __init__(self, system: LeafSystem, n: int, model):
        self._n, self._model = n, model
        self.port = system.DeclareVectorInputPort("reduced_model", 2 * n * n)

    def Momentum(self, context, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
        if not self.port.HasValue(context):
            return self._model.Momentum(q, qdot)
        n = self._n
        return self.port.Eval(context)[:n * n].reshape(n, n) @ qdot
