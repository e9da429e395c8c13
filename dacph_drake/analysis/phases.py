"""The run's phases (linear, plus nonlinear, plus disturbance) as masks over its
logged times, and the RMS the metrics take over them."""
from typing import Dict

import numpy as np

from dacph_drake.scenario import Scenario


def rms(x: np.ndarray) -> float:
    """Root mean square over time of a signal, or of a vector signal's norm (nan if empty).

    Args:
        x: The signal: one value per sample (T), or one vector per row (T x k)."""
    x = np.asarray(x, float)
    if x.ndim > 1:
        x = np.linalg.norm(x, axis=1)
    return float(np.sqrt(np.mean(x**2))) if x.size else float("nan")


def relative_error_rms(estimate: np.ndarray, truth: np.ndarray) -> float:
    """time-RMS of ||estimate(t) - truth(t)|| / ||truth(t)|| (Frobenius on rows).

    Args:
        estimate: The estimate, one row per sample (T x k).
        truth: The truth, laid out as ``estimate``."""
    ratio = (np.linalg.norm(estimate - truth, axis=1)
             / np.maximum(np.linalg.norm(truth, axis=1), 1e-300))
    return rms(ratio)


PHASES = ("phase1", "phase2", "phase3")


def phase_windows(scenario: Scenario, t: np.ndarray) -> Dict[str, np.ndarray]:
    """Phase name (PHASES) -> boolean mask over t (the last phase runs to the end).

    Args:
        scenario: The scenario (its phases).
        t: The logged times [s] (T)."""
    p = scenario.phases
    edges = [p.linear_start, p.nonlinear_start, p.disturbance_start, np.inf]
    return {name: (t >= lo) & (t < hi) for name, lo, hi in zip(PHASES, edges, edges[1:])}
