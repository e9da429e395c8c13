"""inf_q lambda_min(M(q)), the inertia bound of the RHS gain rule (eq. 48), for arms
with many joints: a grid over [-pi, pi)^n costs 73^n mass matrices (a 32 s build
already for n = 3), so the bound is searched instead.

Multi-start descent on lambda_min(M(q)): where the smallest eigenvalue is simple, its
gradient is d lambda_min / d q_k = v^T (dM/dq_k) v (v its unit eigenvector; dM/dq from
FloatingBaseModel's AutoDiff); each start descends with an Armijo line search on the
torus of joint angles. A local search can miss the global minimum, so the bound
returned is the smallest minimum found times (1 - safety_margin), and the result
says how many starts came within 0.1 % of it (the more, the likelier it is the
global one; the landscape is flat near it, so descents stop at slightly different
values)."""
import hashlib
import time
from dataclasses import dataclass

import numpy as np

from dacph_drake.dynamics.floating_model import FloatingBaseModel


@dataclass
class InertiaBound:
    """The result of search_inertia_bound.

    Attributes:
        lambda_min: The bound used: (1 - safety_margin) * smallest_found [kg m^2].
        smallest_found: The minimum over the starts' local minima [kg m^2].
        argmin: The joint angles where it was found [rad].
        starts: The number of starts.
        starts_at_minimum: The starts whose local minimum is within 0.1 % of it.
        safety_margin: The relative margin taken off smallest_found.
        seconds: The wall time of the search [s].
    """
    lambda_min: float
    smallest_found: float
    argmin: np.ndarray
    starts: int
    starts_at_minimum: int
    safety_margin: float
    seconds: float


_CACHE = {}


def search_inertia_bound(model: FloatingBaseModel, starts: int = 24,
                         safety_margin: float = 0.05, seed: int = 0,
                         iterations: int = 200) -> InertiaBound:
    """The gain rule's inf_q lambda_min(M) of a model's arm (see the module docstring).

    Cached per robot (its mass matrix at fixed probe configurations identifies it)
    and settings within a process.

    Args:
        model: The arm's reduced model.
        starts: The number of descents, from random joint angles.
        safety_margin: The bound is the smallest minimum found times
            (1 - safety_margin).
        seed: The seed of the starts.
        iterations: The most steps of each descent.

    Returns:
        The bound and how it was found."""
    probe = np.random.default_rng(12345).uniform(-np.pi, np.pi, (3, model.num_joints))
    key = (hashlib.sha256(np.concatenate([model.MassMatrix(q).ravel() for q in probe]
                                         ).tobytes()).hexdigest(),
           starts, safety_margin, seed, iterations)
    if key not in _CACHE:
        _CACHE[key] = _Search(model, starts, safety_margin, seed, iterations)
    return _CACHE[key]


def _SmallestEigen(model: FloatingBaseModel, q):
    M, dM = model.MassMatrixAndDerivatives(q)
    values, vectors = np.linalg.eigh(M)
    v = vectors[:, 0]
    return values[0], np.einsum("i,kij,j->k", v, dM, v)


def _Descend(model: FloatingBaseModel, q, iterations: int):
    value, gradient = _SmallestEigen(model, q)
    step = 1.0
    for _ in range(iterations):
        norm = np.linalg.norm(gradient)
        if norm < 1e-12:
            break
        while step > 1e-12:                       # Armijo backtracking
            trial = np.angle(np.exp(1j * (q - step * gradient)))
            trial_value, trial_gradient = _SmallestEigen(model, trial)
            if trial_value <= value - 1e-4 * step * norm**2:
                break
            step *= 0.5
        else:
            break
        if value - trial_value < 1e-14 * max(1.0, abs(value)):
            q, value = trial, trial_value
            break
        q, value, gradient = trial, trial_value, trial_gradient
        step *= 2.0
    return value, q


def _Search(model, starts, safety_margin, seed, iterations) -> InertiaBound:
    begin = time.perf_counter()
    rng = np.random.default_rng(seed)
    minima = [_Descend(model, rng.uniform(-np.pi, np.pi, model.num_joints), iterations)
              for _ in range(starts)]
    values = np.array([value for value, _ in minima])
    best = int(np.argmin(values))
    smallest = float(values[best])
    return InertiaBound(
        lambda_min=(1.0 - safety_margin) * smallest, smallest_found=smallest,
        argmin=minima[best][1], starts=starts,
        starts_at_minimum=int(np.sum(values <= smallest * (1 + 1e-3))),
        safety_margin=safety_margin, seconds=time.perf_counter() - begin)
