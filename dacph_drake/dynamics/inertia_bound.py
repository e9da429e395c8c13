"""inf_q lambda_min(M(q)) (the gain rule's, eq. 48) and sup_q lambda_max(M(q)) (the
Lyapunov envelope's), searched where a grid over [-pi, pi)^n costs too much: multi-start
descent with an Armijo line search on the torus, d lambda_min / d q_k = v^T (dM/dq_k) v
(v its unit eigenvector); the bound is the smallest minimum found times
(1 - safety_margin) (lambda_max: the largest times (1 + safety_margin))."""
import hashlib
import time
from dataclasses import dataclass
from typing import Tuple

import numpy as np

from dacph_drake.dynamics import ReducedModel


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
        seconds: The wall time of the search [s]."""
    lambda_min: float
    smallest_found: float
    argmin: np.ndarray
    starts: int
    starts_at_minimum: int
    safety_margin: float
    seconds: float


_CACHE = {}


def search_inertia_bound(model: ReducedModel, starts: int = 24,
                         safety_margin: float = 0.05, seed: int = 0,
                         iterations: int = 200) -> InertiaBound:
    """inf_q lambda_min(M), searched (cached per robot), and how it was found.

    Args:
        model: The arm's reduced model.
        starts: The number of descents, from random joint angles.
        safety_margin: The bound is the smallest minimum found times (1 - safety_margin).
        seed: The seed of the starts.
        iterations: The most steps of each descent."""
    key = _Key(model, starts, safety_margin, seed, iterations)
    if key not in _CACHE:
        _CACHE[key] = _Search(model, starts, safety_margin, seed, iterations)
    return _CACHE[key]


def search_mass_matrix_bounds(model: ReducedModel, starts: int = 24,
                              safety_margin: float = 0.05, seed: int = 0,
                              iterations: int = 200) -> Tuple[float, float]:
    """(inf_q lambda_min(M), sup_q lambda_max(M)) [kg m^2], searched and cached.

    Args:
        model: The arm's reduced model.
        starts: The number of descents per bound, from random joint angles.
        safety_margin: The relative margin by which each bound is widened.
        seed: The seed of the starts.
        iterations: The most steps of each descent."""
    smallest = search_inertia_bound(model, starts, safety_margin, seed, iterations)
    key = ("largest", *_Key(model, starts, safety_margin, seed, iterations))
    if key not in _CACHE:
        found, _, _ = _Extremes(model, -1.0, starts, seed, iterations)
        _CACHE[key] = (1.0 + safety_margin) * -found
    return smallest.lambda_min, _CACHE[key]


def _Key(model: ReducedModel, *settings) -> tuple:
    """The cache key: the robot (its M at fixed probe configurations) and the settings."""
    probe = np.random.default_rng(12345).uniform(-np.pi, np.pi, (3, model.num_joints))
    return (hashlib.sha256(np.concatenate([model.MassMatrix(q).ravel() for q in probe]
                                          ).tobytes()).hexdigest(), *settings)


def _ExtremeEigen(model: ReducedModel, q, sign: float):
    """sign * lambda(M(q)) and its gradient (sign = 1: lambda_min; -1: lambda_max)."""
    M, dM = model.MassMatrixAndDerivatives(q)
    values, vectors = np.linalg.eigh(M)
    extreme = 0 if sign > 0 else -1
    v = vectors[:, extreme]
    return sign * values[extreme], sign * np.einsum("i,kij,j->k", v, dM, v)


def _Descend(model: ReducedModel, q, iterations: int, sign: float = 1.0):
    value, gradient = _ExtremeEigen(model, q, sign)
    step = 1.0
    for _ in range(iterations):
        norm = np.linalg.norm(gradient)
        if norm < 1e-12:
            break
        while step > 1e-12:                       # Armijo backtracking
            trial = np.angle(np.exp(1j * (q - step * gradient)))
            trial_value, trial_gradient = _ExtremeEigen(model, trial, sign)
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


def _Extremes(model: ReducedModel, sign: float, starts: int, seed: int,
              iterations: int):
    """The least local minimum of sign * lambda, where, and how many starts within 0.1 %."""
    rng = np.random.default_rng(seed)
    minima = [_Descend(model, rng.uniform(-np.pi, np.pi, model.num_joints), iterations,
                       sign) for _ in range(starts)]
    values = np.array([value for value, _ in minima])
    best = int(np.argmin(values))
    found = float(values[best])
    return found, minima[best][1], int(np.sum(values <= found + 1e-3 * abs(found)))


def _Search(model, starts, safety_margin, seed, iterations) -> InertiaBound:
    begin = time.perf_counter()
    smallest, argmin, at_minimum = _Extremes(model, 1.0, starts, seed, iterations)
    return InertiaBound(
        lambda_min=(1.0 - safety_margin) * smallest, smallest_found=smallest,
        argmin=argmin, starts=starts, starts_at_minimum=at_minimum,
        safety_margin=safety_margin, seconds=time.perf_counter() - begin)
