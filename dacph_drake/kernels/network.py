"""The RHS network (network module, E34-E35) evaluated for every trial of a batch in one
compiled call, from each trial's exported parameters in torch's parameters() order:
body_B, body_D, head_B, head_D, each layer's weight (row-major) then its bias."""
from typing import Tuple

import numpy as np
from numba import njit


@njit(cache=True)
def _dense(weights, offset, rows, columns, x, out, activate):
    """out = tanh(W x + b) (W x + b unless ``activate``); returns the offset after W, b."""
    for r in range(rows):
        value = 0.0
        for c in range(columns):
            value += weights[offset + r * columns + c] * x[c]
        value += weights[offset + rows * columns + r]
        out[r] = np.tanh(value) if activate else value
    return offset + rows * columns + rows


@njit(cache=True)
def _body(weights, offset, hidden, x, work):
    """The tanh MLP's last hidden layer into work[-1]; returns the offset after it."""
    width, source = x.shape[0], x
    for layer in range(hidden.shape[0]):
        offset = _dense(weights, offset, hidden[layer], width, source, work[layer],
                        True)
        width, source = hidden[layer], work[layer]
    return offset


@njit(cache=True)
def evaluate_networks(hidden: np.ndarray, momentum_scale: float, weights: np.ndarray,
                      q: np.ndarray, p: np.ndarray, coupling: np.ndarray
                      ) -> Tuple[np.ndarray, np.ndarray]:
    """Every trial's (B_hat (trials, n, n), D_hat (trials, n)) at weights[i], (q[i], p[i]).

    Args:
        hidden: The MLPs' hidden layer widths (layers,), int64 (both MLPs alike).
        momentum_scale: p_scale, the momentum's scale in the networks' input.
        weights: Each trial's exported parameter vector (trials, size).
        q: Each trial's joint angles (trials, n) [rad].
        p: Each trial's momentum (trials, n).
        coupling: Each trial's coupling scale F (trials, n, n)."""
    trials, n = q.shape[0], q.shape[1]
    layers, widest = hidden.shape[0], 0
    for h in hidden:
        widest = max(widest, h)
    B, D = np.empty((trials, n, n)), np.empty((trials, n))
    x = np.empty(2 * n)
    work_B, work_D = np.empty((layers, widest)), np.empty((layers, widest))
    head_B, head_D = np.empty(n * n), np.empty(n)
    last = hidden[layers - 1]
    for i in range(trials):
        for j in range(n):
            x[j], x[n + j] = q[i, j], p[i, j] / momentum_scale
        offset = _body(weights[i], 0, hidden, x, work_B)
        offset = _body(weights[i], offset, hidden, x, work_D)
        offset = _dense(weights[i], offset, n * n, last, work_B[layers - 1], head_B,
                        False)
        _dense(weights[i], offset, n, last, work_D[layers - 1], head_D, False)
        for r in range(n):
            for c in range(n):
                B[i, r, c] = head_B[r * n + c] * coupling[i, r, c]
            z = head_D[r]               # softplus(z) = log(1 + e^z), stably
            D[i, r] = max(z, 0.0) + np.log1p(np.exp(-abs(z)))
    return B, D
