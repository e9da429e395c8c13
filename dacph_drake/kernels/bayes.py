"""The local Bayesian learner's regression (learning.local_bayes), compiled: one joint's
row of the port relation on its window of band-passed samples,

    y_k = a_k^T theta + psi_k^T eta + r_k,     theta ~ N(theta_0, diag(s^2)),

solved in the prior's standardized coordinates (theta = theta_0 + s o phi) for
conditioning. sigma^2 is inflated by the residual's correlation time and the fit's
degrees of freedom, so a short window is not mistaken for a well determined one."""
import numpy as np
from numba import njit


@njit(cache=True)
def spd_inverse(A: np.ndarray, out: np.ndarray) -> bool:
    """Writes A^-1 into ``out`` by Cholesky; False when A is not positive definite.

    Args:
        A: The matrix (m x m); only its lower triangle is read.
        out: Where the inverse goes (m x m)."""
    m = A.shape[0]
    L = np.zeros((m, m))
    for j in range(m):
        value = A[j, j]
        for k in range(j):
            value -= L[j, k] * L[j, k]
        if not value > 0.0:
            return False
        L[j, j] = np.sqrt(value)
        for i in range(j + 1, m):
            value = A[i, j]
            for k in range(j):
                value -= L[i, k] * L[j, k]
            L[i, j] = value / L[j, j]
    inverse = np.zeros((m, m))           # L^-1, lower triangular
    for j in range(m):
        inverse[j, j] = 1.0 / L[j, j]
        for i in range(j + 1, m):
            value = 0.0
            for k in range(j, i):
                value -= L[i, k] * inverse[k, j]
            inverse[i, j] = value / L[i, i]
    for i in range(m):                   # A^-1 = L^-T L^-1
        for j in range(i + 1):
            value = 0.0
            for k in range(i, m):
                value += inverse[k, i] * inverse[k, j]
            out[i, j] = value
            out[j, i] = value
    return True


@njit(cache=True)
def _matvec(M: np.ndarray, v: np.ndarray) -> np.ndarray:
    """M v (numba's matrix product needs SciPy's BLAS)."""
    out = np.zeros(M.shape[0])
    for i in range(M.shape[0]):
        value = 0.0
        for j in range(M.shape[1]):
            value += M[i, j] * v[j]
        out[i] = value
    return out


@njit(cache=True)
def _newest_relative(r: np.ndarray, y: np.ndarray, old: int) -> float:
    """RMS of the residual over RMS of y on the samples from ``old`` on."""
    new_rms, new_y = 0.0, 0.0
    for k in range(old, r.shape[0]):
        new_rms += r[k] ** 2
        new_y += y[k] ** 2
    return np.sqrt(new_rms / new_y) if new_y > 0.0 else np.nan


@njit(cache=True)
def _correlation_time(r: np.ndarray, lags: int) -> float:
    """Bartlett's correlation time 1 + 2 sum_l (1 - l / (L + 1)) max(rho_l, 0), >= 1."""
    count = r.shape[0]
    lags = min(lags, count // 4)
    mean = 0.0
    for k in range(count):
        mean += r[k]
    mean /= max(count, 1)
    c0 = 0.0
    for k in range(count):
        c0 += (r[k] - mean) ** 2
    if not c0 > 0.0:
        return 1.0
    tau = 1.0
    for lag in range(1, lags + 1):
        c = 0.0
        for k in range(lag, count):
            c += (r[k] - mean) * (r[k - lag] - mean)
        tau += 2.0 * (1.0 - lag / (lags + 1.0)) * max(c / c0, 0.0)
    return tau


@njit(cache=True)
def fit_row(A: np.ndarray, y: np.ndarray, w: np.ndarray, prior_mean: np.ndarray,
            prior_sd: np.ndarray, lags: int, min_tau: float, floor: float, newest: int,
            nuisance: float, min_dof: float, mean: np.ndarray, variance: np.ndarray,
            statistics: np.ndarray, detectable: float = 0.0) -> bool:
    """One row's posterior on its window; whether the window determines it:
    (sum w - nuisance - tr hat) / tau >= min_dof (if not, the prior's mean and variance).

    Args:
        A: The regressors (K samples x P columns), the nuisance projected out.
        y: The band-passed port torque (K), the nuisance projected out.
        w: The forgetting weights (K), the newest sample's 1.
        prior_mean: theta_0 (P).
        prior_sd: s (P), each > 0.
        lags: The longest lag of the correlation-time estimate [samples].
        min_tau: The least correlation time: 1 / (2 f h) for a band f [Hz] sampled at h [s].
        floor: The observer's relative accuracy: each coefficient's variance gains
            (floor RMS_w(r) / RMS_w(A_c))^2.
        newest: How many of the last samples are new since the last fit.
        nuisance: The weighted dof the projected nuisance spent (project_out).
        min_dof: The residual dof (in independent samples) a determined fit needs.
        mean: The posterior mean (P), written.
        variance: The posterior variances (P), written.
        statistics: Written: [sigma^2, residual dof, effective parameters, change statistic,
            newest relative residual, tau].
        detectable: The relative residual below which the change test misses a change: each
            coefficient's variance gains (detectable RMS_w(y) / RMS_w(A_c))^2."""
    K, P = A.shape
    scaled = A * prior_sd.reshape(1, P)
    offset = y - _matvec(A, prior_mean)
    G = np.zeros((P, P))
    b = np.zeros(P)
    for k in range(K):
        for i in range(P):
            wa = w[k] * scaled[k, i]
            b[i] += wa * offset[k]
            for j in range(i + 1):
                G[i, j] += wa * scaled[k, j]
    for i in range(P):
        for j in range(i):
            G[j, i] = G[i, j]
    weight = np.sum(w)
    sigma2 = max(1e-4 * np.sum(w * y * y) / weight, 1e-300)
    C = np.empty((P, P))
    precision = np.empty((P, P))
    phi = np.zeros(P)
    r = offset.copy()
    determined = True
    tau = 1.0
    p_eff = 0.0
    for _ in range(4):
        precision[:, :] = G / sigma2
        for c in range(P):
            precision[c, c] += 1.0
        if not spd_inverse(precision, C):
            determined = False
            break
        phi = _matvec(C, b / sigma2)
        r = offset - _matvec(scaled, phi)
        tau = max(_correlation_time(r, lags), min_tau)
        p_eff = 0.0
        for i in range(P):
            for j in range(P):
                p_eff += G[i, j] * C[j, i]
        p_eff /= sigma2
        residual_weight = weight - nuisance - p_eff
        if residual_weight < min_dof * tau:
            determined = False
            residual_weight = min_dof * tau
        sigma2 = max(np.sum(w * r * r) / residual_weight * tau, 1e-300)
    if determined:
        precision[:, :] = G / sigma2
        for c in range(P):
            precision[c, c] += 1.0
        determined = spd_inverse(precision, C)
    if not determined:
        mean[:] = prior_mean
        variance[:] = prior_sd ** 2
        statistics[:] = np.nan
        statistics[4] = _newest_relative(r, y, K - newest)
        return False
    phi = _matvec(C, b / sigma2)
    r = offset - _matvec(scaled, phi)
    residual = np.sqrt(np.sum(w * r * r) / weight)
    signal = np.sqrt(np.sum(w * y * y) / weight)
    for c in range(P):
        mean[c] = prior_mean[c] + prior_sd[c] * phi[c]
        column = np.sqrt(np.sum(w * A[:, c] ** 2) / weight)
        variance[c] = prior_sd[c] ** 2 * C[c, c]
        if column > 0.0:
            variance[c] += (floor * residual / column) ** 2
            variance[c] += (detectable * signal / column) ** 2
    old = K - newest
    # The newest samples predicted by the fit to the others (their rows removed
    # from the normal equations), each against its predictive variance: the
    # noise's, the coefficients' and the floor's.
    for k in range(old, K):
        for i in range(P):
            wa = w[k] * scaled[k, i]
            b[i] -= wa * offset[k]
            for j in range(P):
                G[i, j] -= wa * scaled[k, j]
    # The noise of the others alone (a change in the newest samples inflates the
    # window's sigma^2, which would hide it), iterated with their fit as above.
    weight_old = np.sum(w[:old]) if old > 0 else 0.0
    sigma2_old = max(1e-4 * np.sum(w[:old] * y[:old] ** 2) / max(weight_old, 1e-300),
                     1e-300)
    for _ in range(4):
        precision[:, :] = G / sigma2_old
        for c in range(P):
            precision[c, c] += 1.0
        if not (newest > 0 and old > 0 and spd_inverse(precision, C)):
            break
        phi = _matvec(C, b / sigma2_old)
        r_old = offset[:old] - _matvec(scaled[:old], phi)
        sigma2_old = max(np.sum(w[:old] * r_old * r_old)
                         / max(weight_old - nuisance - p_eff, min_dof * tau) * tau,
                         1e-300)
    precision[:, :] = G / sigma2_old
    for c in range(P):
        precision[c, c] += 1.0
    z2, predicted = 0.0, 0
    if newest > 0 and old > 0 and spd_inverse(precision, C):
        phi = _matvec(C, b / sigma2_old)
        old_residual = np.sqrt(sigma2_old / tau)
        for k in range(old, K):
            error = offset[k]
            spread = 0.0
            for i in range(P):
                error -= scaled[k, i] * phi[i]
                for j in range(P):
                    spread += scaled[k, i] * C[i, j] * scaled[k, j]
            z2 += error ** 2 / (sigma2_old / tau + spread + (floor * old_residual) ** 2)
            predicted += 1
    statistics[0] = sigma2
    statistics[1] = (weight - nuisance - p_eff) / tau
    statistics[2] = p_eff + nuisance
    statistics[3] = np.sqrt(z2 / predicted) if predicted else np.nan
    statistics[4] = _newest_relative(r, y, old)
    statistics[5] = tau
    return True


@njit(cache=True)
def project_out(basis: np.ndarray, w: np.ndarray, A: np.ndarray, y: np.ndarray) -> float:
    """Projects the span of ``basis`` (the band-pass's free response) out of A's columns and
    y, W-orthogonally (modified Gram-Schmidt, skipping directions below 1e-9); returns the
    weighted dof spent, sum_s sum_k w_k^2 q_sk^2.

    Args:
        basis: The nuisance columns (K x S).
        w: The weights (K).
        A: The regressors (K x P), projected in place.
        y: The target (K), projected in place."""
    K, S = basis.shape
    Q = basis.copy()
    kept = 0
    for s in range(S):
        v = Q[:, s].copy()
        original = np.sqrt(np.sum(w * v * v))
        for j in range(kept):
            v -= np.sum(w * v * Q[:, j]) * Q[:, j]
        norm = np.sqrt(np.sum(w * v * v))
        if not original > 0.0 or norm < 1e-9 * original:
            continue
        Q[:, kept] = v / norm
        kept += 1
    spent = 0.0
    for j in range(kept):
        q = Q[:, j]
        for c in range(A.shape[1]):
            A[:, c] -= np.sum(w * A[:, c] * q) * q
        y -= np.sum(w * y * q) * q
        spent += np.sum(w * w * q * q)
    return spent


@njit(cache=True)
def row_design(rows: np.ndarray, i: int, n: int, t_now: float, p_now: float
               ) -> np.ndarray:
    """Row i's regressors A (K x 3 (n + 1)) of theta_ij(x) = theta_ij + drift_ij (t - t_now)
    + slope_ij (p_i - p_now) / p_scale, per entry [const, drift, slope]: B_ij: [U0_j, Ut_j -
    t_now U0_j, Up_ij - p_now U0_j]; D_i: -[V0_i, Vt_i - t_now V0_i, Vp_i - p_now V0_i].

    Args:
        rows: The window's samples (K x (2n + channels)): [q, p / p_scale, channels].
        i: The row (joint).
        n: The number of joints.
        t_now: The model's reference time [s].
        p_now: The model's reference momentum of joint i, over p_scale."""
    K = rows.shape[0]
    c0 = 2 * n                              # the channels' first column
    A = np.empty((K, 3 * (n + 1)))
    for k in range(K):
        for j in range(n):
            u0 = rows[k, c0 + j]
            A[k, 3 * j] = u0
            A[k, 3 * j + 1] = rows[k, c0 + n + j] - t_now * u0
            A[k, 3 * j + 2] = rows[k, c0 + 2 * n + i * n + j] - p_now * u0
        v0 = rows[k, c0 + 2 * n + n * n + i]
        A[k, 3 * n] = -v0
        A[k, 3 * n + 1] = -(rows[k, c0 + 3 * n + n * n + i] - t_now * v0)
        A[k, 3 * n + 2] = -(rows[k, c0 + 4 * n + n * n + i] - p_now * v0)
    return A


@njit(cache=True)
def fit_rows(times: np.ndarray, rows: np.ndarray, starts: np.ndarray, n: int,
             prior_mean: np.ndarray, prior_sd: np.ndarray, free_response: np.ndarray,
             forgetting: float, lags: int, min_tau: float, floor: float,
             detectable: float, newest_period: float, minimum: int, min_dof: float,
             mean: np.ndarray,
             variance: np.ndarray,
             statistics: np.ndarray, determined: np.ndarray) -> None:
    """Every row's fit of one trial (fit_row on row_design, the nuisance projected).

    Args:
        times: The buffered samples' times, oldest first (K) [s].
        rows: The buffered samples (K x (2n + channels)), as row_design reads them.
        starts: Each row's window start [s] (its last restart).
        n: The number of joints.
        prior_mean: Each row's theta_0 (n x 3 (n + 1)).
        prior_sd: Each row's s (n x 3 (n + 1)).
        free_response: The filter's response to each unit state from the start (>= K x S).
        forgetting: The forgetting time [s].
        lags: fit_row's lags.
        min_tau: fit_row's min_tau.
        floor: fit_row's floor.
        detectable: fit_row's detectable.
        newest_period: The newest samples' span, for the change test [s].
        minimum: The fewest samples a row's window must hold.
        min_dof: fit_row's min_dof.
        mean: Each row's posterior mean (n x 3 (n + 1)), written.
        variance: Each row's posterior variances (n x 3 (n + 1)), written.
        statistics: Each row's fit_row statistics (n x 6), written.
        determined: Whether each row's window determined its fit (n), written."""
    K = times.shape[0]
    t_now = times[K - 1]
    for i in range(n):
        first = 0
        while first < K and times[first] < starts[i] - 1e-9:
            first += 1
        count = K - first
        if count < minimum:
            mean[i] = prior_mean[i]
            variance[i] = prior_sd[i] ** 2
            statistics[i] = np.nan
            determined[i] = False
            continue
        window = rows[first:]
        w = np.exp((times[first:] - t_now) / forgetting)
        A = row_design(window, i, n, t_now, window[count - 1, n + i])
        y = window[:, 2 * n + 5 * n + n * n + i].copy()
        spent = project_out(free_response[:count], w, A, y)
        newest = 0
        for k in range(first, K):
            if times[k] > t_now - newest_period + 1e-9:
                newest += 1
        determined[i] = fit_row(A, y, w, prior_mean[i], prior_sd[i], lags, min_tau,
                                floor, newest, spent, min_dof, mean[i],
                                variance[i], statistics[i], detectable)
