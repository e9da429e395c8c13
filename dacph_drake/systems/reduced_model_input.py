"""The input ``reduced_model`` = [vec(M), vec(C')] of the LHS controller's last
sample, for the systems that need the port's momentum p = M qdot as the LHS
controller (and through it the port observer) sees it."""
from typing import Sequence

import numpy as np
from pydrake.systems.framework import LeafSystem


class ReducedModelInput:
    """Declares input ``reduced_model`` (2 n^2 per trial of ``models``: one model
    per trial of a batch, stacked) on ``system``; Momentum(context, trial, q, qdot)
    is that trial's p = M qdot with M from it, or the trial's
    ``models[trial]``.Momentum(q, qdot) (the controller's nominal model) where it
    is not connected (a system tested alone). Reading M from the LHS keeps p the
    same function of the state in the learner's samples (the observer's p) and in
    the evaluation of B_hat(x), D_hat(x), also when the LHS's model is identified
    online (InertialIdentifier)."""

    def __init__(self, system: LeafSystem, n: int, models: Sequence):
        self._n, self._models = n, list(models)
        self.port = system.DeclareVectorInputPort("reduced_model",
                                                  2 * n * n * len(self._models))

    def Momentum(self, context, trial: int, q: np.ndarray, qdot: np.ndarray
                 ) -> np.ndarray:
        if not self.port.HasValue(context):
            return self._models[trial].Momentum(q, qdot)
        n = self._n
        start = 2 * n * n * trial
        return self.port.Eval(context)[start:start + n * n].reshape(n, n) @ qdot
