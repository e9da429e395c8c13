"""The sensors' sample and measurement (systems.sensors), compiled. Per trial the state
row holds [n_q (n), n_r (n), n_g (axes), bias (axes), the attitude estimate (4: a
quaternion (w, x, y, z); 1: a planar angle), q_m(k-1) (n), the differentiated rate (n),
samples since the last star-tracker fix]; ``truth`` and the measurement stack
[base_pose, q, base_velocity, qdot], each signal's trials in trial order.

``layout`` (integers): [n, trials, base positions, base velocities, axes, spatial (1/0),
differentiated (1/0), estimated (1/0), fix_every]; ``constants``: [encoder step (0:
unquantized), the rate filter's alpha, encoder_noise, rate_noise, gyro_noise,
gyro_bias_walk sqrt(h), h]."""
import numpy as np
from numba import njit

N, TRIALS, BASE_Q, BASE_V, AXES, SPATIAL, DIFFERENTIATED, ESTIMATED, FIX_EVERY = range(9)
STEP, ALPHA, ENCODER_NOISE, RATE_NOISE, GYRO_NOISE, WALK, PERIOD = range(7)


@njit(cache=True)
def _columns(layout):
    """The state row's offsets: n_q, n_r, n_g, bias, attitude, previous, rate, since fix."""
    n, axes = layout[N], layout[AXES]
    attitude = 4 if layout[SPATIAL] else 1
    offsets = np.empty(8, np.int64)
    offsets[0] = 0
    sizes = (n, n, axes, axes, attitude, n, n)
    for k in range(7):
        offsets[k + 1] = offsets[k] + sizes[k]
    return offsets


@njit(cache=True)
def _rows(flat_state, layout):
    """The state's rows (trials x width), a view of the flat state."""
    width = _columns(layout)[7] + 1
    return flat_state[:layout[TRIALS] * width].reshape((layout[TRIALS], width))


@njit(cache=True)
def _encoder(value, step):
    """An encoder's reading quantized to its counts (step 0: unquantized)."""
    return step * np.round(value / step) if step > 0.0 else value


@njit(cache=True)
def _turned(quaternion, rotation_vector):
    """exp([rotation_vector]) applied to a (w, x, y, z) quaternion, normalized."""
    angle = np.sqrt(np.sum(rotation_vector**2))
    w1 = np.cos(0.5 * angle)
    v1 = (np.sin(0.5 * angle) / angle * rotation_vector if angle > 0.0
          else np.zeros(3))
    w2, v2 = quaternion[0], quaternion[1:]
    out = np.empty(4)
    out[0] = w1 * w2 - np.sum(v1 * v2)
    out[1:] = w1 * v2 + w2 * v1 + np.cross(v1, v2)
    return out / np.sqrt(np.sum(out**2))


@njit(cache=True)
def star_fix(pose_attitude: np.ndarray, noise: np.ndarray, spatial: bool) -> np.ndarray:
    """A star-tracker fix of the attitude with per-axis noise [rad].

    Args:
        pose_attitude: The truth's attitude (a quaternion, or a planar angle (1)).
        noise: The fix's noise per axis.
        spatial: Whether the base is free (a quaternion)."""
    if spatial:
        return _turned(pose_attitude, noise)
    return pose_attitude + noise


@njit(cache=True)
def sensor_measure(flat_state: np.ndarray, truth: np.ndarray, layout: np.ndarray,
                   constants: np.ndarray, out: np.ndarray) -> None:
    """The measurement of ``truth`` with the sensors' state into ``out``
    (systems.sensors' equations).

    Args:
        flat_state: The sensors' state rows, one after the other (anything after them
            is not read).
        truth: The true [base_pose, q, base_velocity, qdot].
        layout: The module's integers.
        constants: The module's constants.
        out: Written: the measured [base_pose, q, base_velocity, qdot]."""
    n, trials, nb_q, nb_v, axes = (layout[N], layout[TRIALS], layout[BASE_Q],
                                   layout[BASE_V], layout[AXES])
    o = _columns(layout)
    state = _rows(flat_state, layout)
    pose0, q0 = 0, trials * nb_q
    velocity0 = q0 + trials * n
    qdot0 = velocity0 + trials * nb_v
    out[:] = truth
    rate_column = 0 if layout[SPATIAL] else 2
    attitude_column = 0 if layout[SPATIAL] else 2
    for i in range(trials):
        for j in range(n):
            out[q0 + i * n + j] = _encoder(truth[q0 + i * n + j] + state[i, o[0] + j],
                                           constants[STEP])
            if layout[DIFFERENTIATED]:
                out[qdot0 + i * n + j] = state[i, o[6] + j]
            else:
                out[qdot0 + i * n + j] = truth[qdot0 + i * n + j] + state[i, o[1] + j]
        for a in range(axes):
            out[velocity0 + i * nb_v + rate_column + a] += (state[i, o[3] + a]
                                                            + state[i, o[2] + a])
        if layout[ESTIMATED]:
            for a in range(o[5] - o[4]):
                out[pose0 + i * nb_q + attitude_column + a] = state[i, o[4] + a]


@njit(cache=True)
def sensor_sample(flat_state: np.ndarray, truth: np.ndarray, normals: np.ndarray,
                  cursor: int, layout: np.ndarray, constants: np.ndarray,
                  star_noise: float) -> int:
    """One sample of the sensors' state (in place): the sample's noise, the gyro bias'
    walk, the encoders' differentiated rate, and the attitude estimate propagated by
    the gyro, or fixed by the star tracker when the fix is due. Each trial's standard
    normals are read from its row of ``normals`` at ``cursor``: the sample's noise (2 n
    + axes), then the walk's (axes, if it walks), then the fix's (axes, if due).

    Args:
        flat_state: The sensors' state rows, one after the other (anything after them
            is not read).
        truth: The true [base_pose, q, base_velocity, qdot].
        normals: Each trial's standard normals (trials x at least cursor +
            sample_normals(layout, constants)).
        cursor: The first unread column of ``normals``.
        layout: The module's integers.
        constants: The module's constants.
        star_noise: The star tracker's noise per axis [rad].

    Returns:
        The first column left unread."""
    n, trials, nb_q, nb_v, axes = (layout[N], layout[TRIALS], layout[BASE_Q],
                                   layout[BASE_V], layout[AXES])
    o = _columns(layout)
    state = _rows(flat_state, layout)
    spatial = layout[SPATIAL] == 1
    h = constants[PERIOD]
    q0 = trials * nb_q
    velocity0 = q0 + trials * n
    rate_column = 0 if spatial else 2
    attitude_column = 0 if spatial else 2
    attitude_size = o[5] - o[4]
    walk = cursor + 2 * n + axes
    fix = walk + (axes if constants[WALK] > 0.0 else 0)
    due = layout[ESTIMATED] == 1 and state[0, o[7]] + 1 >= layout[FIX_EVERY]
    for i in range(trials):
        draws = normals[i]
        for j in range(n):
            state[i, o[0] + j] = constants[ENCODER_NOISE] * draws[cursor + j]
            state[i, o[1] + j] = constants[RATE_NOISE] * draws[cursor + n + j]
        for a in range(axes):
            state[i, o[2] + a] = constants[GYRO_NOISE] * draws[cursor + 2 * n + a]
            if constants[WALK] > 0.0:
                state[i, o[3] + a] += constants[WALK] * draws[walk + a]
        for j in range(n):
            measured = _encoder(truth[q0 + i * n + j] + state[i, o[0] + j],
                                constants[STEP])
            state[i, o[6] + j] += constants[ALPHA] * (
                (measured - state[i, o[5] + j]) / h - state[i, o[6] + j])
            state[i, o[5] + j] = measured
        if layout[ESTIMATED]:
            state[i, o[7]] += 1
            pose = truth[i * nb_q + attitude_column:i * nb_q + attitude_column
                         + attitude_size]
            if due:
                state[i, o[4]:o[5]] = star_fix(pose, star_noise * draws[fix:fix + axes],
                                               spatial)
                state[i, o[7]] = 0
            else:
                omega = np.empty(axes)
                for a in range(axes):
                    omega[a] = (truth[velocity0 + i * nb_v + rate_column + a]
                                + state[i, o[3] + a] + state[i, o[2] + a])
                if spatial:
                    state[i, o[4]:o[5]] = _turned(state[i, o[4]:o[5]].copy(), omega * h)
                else:
                    state[i, o[4]] += omega[0] * h
    return fix + (axes if due else 0)
