"""The spacecraft's sensors between the ground truth and the controllers
(scenario.Sensing): joint encoders, joint-rate tachometers or differentiated encoders,
the base's gyro and star tracker, and a latency."""
from typing import Sequence

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import LeafSystem, ValueProducer

from dacph_drake.scenario import Sensing

SEED_OFFSET = 7919      # the sensors' noise streams apart from the observer's (seed)


def _quaternion_product(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a b of (w, x, y, z) quaternions, row by row (k x 4)."""
    w1, v1, w2, v2 = a[:, :1], a[:, 1:], b[:, :1], b[:, 1:]
    return np.hstack([w1 * w2 - np.sum(v1 * v2, axis=1, keepdims=True),
                      w1 * v2 + w2 * v1 + np.cross(v1, v2)])


def _rotation_quaternion(rotation_vector: np.ndarray) -> np.ndarray:
    """The unit quaternions (k x 4) of rotation vectors (k x 3) [rad]."""
    angle = np.linalg.norm(rotation_vector, axis=1, keepdims=True)
    half = 0.5 * angle
    axis = np.divide(rotation_vector, angle, out=np.zeros_like(rotation_vector),
                     where=angle > 0)
    return np.hstack([np.cos(half), np.sin(half) * axis])


class Sensors(LeafSystem):
    """Measured ``base_pose``, ``q``, ``base_velocity`` and ``qdot`` of a batch's trials
    from the true ones (inputs of the same names, plant.STATE_SIGNALS), every ``period``:

        q_m     = delta round((q + n_q) / delta),    delta = 2 pi / encoder_counts
        qdot_m  = qdot + n_r (tachometer), or the low-passed difference
                  (q_m(k) - q_m(k-1)) / h at rate_cutoff (differentiated)
        omega_m = omega + b + n_g,   b(k+1) = b(k) + gyro_bias_walk sqrt(h) N(0, 1)
        R_m     = exp([n_s]) R at each star-tracker fix, exp([omega_m] h) R_m between

    omega and R in the world frame (a planar base: the angle theta0 and its rate); the
    base's position and linear velocity pass exact (no navigation sensor is modelled).
    Each noise is Gaussian, drawn per trial from its own seeded stream and held for the
    sample. Outputs are the measurements ``latency`` samples late; with no noise, no
    quantization, no latency and an exact attitude they equal the inputs at once.

    Args:
        settings: The sensing section.
        num_joints: n.
        base_positions: The base joint's positions (3: planar; 7: free, quaternion first).
        period: The sensors' sample period h [s] (periods.rhs).
        seeds: Each trial's seed."""

    def __init__(self, *, settings: Sensing, num_joints: int, base_positions: int,
                 period: float, seeds: Sequence[int]):
        super().__init__()
        n, trials, s = num_joints, len(seeds), settings
        self._n, self._trials, self._h, self._s = n, trials, period, s
        self._spatial = base_positions == 7
        self._axes = 3 if self._spatial else 1
        # The attitude's columns in base_pose and the angular rates' in base_velocity.
        self._attitude_columns = slice(0, 4) if self._spatial else slice(2, 3)
        self._rate_columns = slice(0, 3) if self._spatial else slice(2, 3)
        self._rngs = [np.random.default_rng(seed + SEED_OFFSET) for seed in seeds]
        self._step = 2 * np.pi / s.encoder_counts if s.encoder_counts else 0.0
        self._alpha = 1.0 - np.exp(-2 * np.pi * s.rate_cutoff * period)
        self._fix_every = (max(1, int(round(1.0 / (s.star_tracker_rate * period))))
                           if s.star_tracker_rate > 0 else 1)
        self._estimated = s.star_tracker_rate > 0 or s.star_tracker_noise > 0
        self._differentiated = s.rate_source == "differentiated"
        nb_q, nb_v = base_positions, 6 if self._spatial else 3
        self._sizes = (nb_q, n, nb_v, n)
        # State per trial: [noise n_q (n), n_r (n), n_g (axes), bias (axes), attitude
        # estimate (4 or 1), q_m(k-1) (n), filtered rate (n), samples since the fix].
        a, attitude = self._axes, 4 if self._spatial else 1
        offsets = np.cumsum([0, n, n, a, a, attitude, n, n, 1])
        (self._nq, self._nr, self._ng, self._bias, self._attitude, self._previous,
         self._rate) = [slice(lo, hi) for lo, hi in zip(offsets[:-1], offsets[1:])][:7]
        self._since_fix = offsets[-2]
        self._width = offsets[-1]
        self._noise_width = 2 * n + a
        self._draws, self._walk_draws = np.empty((trials, 2 * n + a)), np.empty((trials, a))
        self._state = self.DeclareDiscreteState(self._width * trials)
        # The measurements of the last ``latency`` samples, oldest first.
        self._measured = sum(self._sizes) * trials
        self._queue = (self.DeclareDiscreteState(self._measured * s.latency)
                       if s.latency > 0 else None)
        # 0 until the initialization event has run: the outputs are then the truth's
        # (what other systems' initialization reads).
        self._ready = self.DeclareDiscreteState(1)
        self._inputs = [self.DeclareVectorInputPort(name, size * trials)
                        for name, size in zip(("base_pose", "q", "base_velocity", "qdot"),
                                              self._sizes)]
        # The stacked measurement, computed once per context for the four outputs.
        self._measurement = self.DeclareCacheEntry(
            "measurement", ValueProducer(
                allocate=lambda: AbstractValue.Make(np.zeros(self._measured)),
                calc=lambda context, value: value.set_value(self._CalcMeasured(context))),
            {self.all_input_ports_ticket(), self.all_state_ticket()})
        starts = np.cumsum([0, *[size * trials for size in self._sizes]])
        for name, lo, hi in zip(("base_pose", "q", "base_velocity", "qdot"),
                                starts[:-1], starts[1:]):
            self.DeclareVectorOutputPort(
                name, hi - lo, lambda context, output, lo=lo, hi=hi: output.SetFromVector(
                    self._measurement.Eval(context)[lo:hi]),
                prerequisites_of_calc={self._measurement.ticket()})
        self.DeclareInitializationDiscreteUpdateEvent(self._Initialize)
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._UpdateSample)

    def _Trials(self, vector: np.ndarray, size: int) -> np.ndarray:
        return vector.reshape(self._trials, size)

    def _Measure(self, state: np.ndarray, truth: Sequence[np.ndarray]) -> np.ndarray:
        """The stacked measurements [base_pose, q, base_velocity, qdot] at the truth."""
        pose, q, velocity, qdot = (self._Trials(x, size).copy()
                                   for x, size in zip(truth, self._sizes))
        q = self._Encoders(q, state[:, self._nq])
        if self._differentiated:
            qdot = state[:, self._rate].copy()
        else:
            qdot = qdot + state[:, self._nr]
        velocity[:, self._rate_columns] += state[:, self._bias] + state[:, self._ng]
        if self._estimated:
            pose[:, self._attitude_columns] = state[:, self._attitude]
        return np.concatenate([x.reshape(-1) for x in (pose, q, velocity, qdot)])

    def _Encoders(self, q: np.ndarray, noise: np.ndarray) -> np.ndarray:
        """The encoders' readings of q with their noise, quantized to their counts."""
        q = q + noise
        return self._step * np.round(q / self._step) if self._step else q

    def _CalcMeasured(self, context) -> np.ndarray:
        if context.get_discrete_state(self._ready).get_value()[0] == 0:
            return np.concatenate([port.Eval(context) for port in self._inputs])
        if self._queue is not None:
            return context.get_discrete_state(self._queue).get_value()[:self._measured]
        state = self._Trials(context.get_discrete_state(self._state).get_value(),
                             self._width)
        return self._Measure(state, [port.Eval(context) for port in self._inputs])

    def _Fix(self, pose: np.ndarray, noise: np.ndarray) -> np.ndarray:
        """A star-tracker fix of each trial's attitude with per-axis noise."""
        if not self._spatial:
            return pose[:, self._attitude_columns] + noise
        fixed = _quaternion_product(_rotation_quaternion(noise),
                                    pose[:, self._attitude_columns])
        return fixed / np.linalg.norm(fixed, axis=1, keepdims=True)

    def _Initialize(self, context, discrete_state):
        s = self._s
        pose, q, _, _ = (self._Trials(port.Eval(context), size)
                         for port, size in zip(self._inputs, self._sizes))
        state = np.zeros((self._trials, self._width))
        state[:, self._bias] = s.gyro_bias
        state[:, self._attitude] = self._Fix(pose, self._StarNoise())
        state[:, self._previous] = self._Encoders(q, 0.0)
        discrete_state.get_mutable_vector(self._state).SetFromVector(state.reshape(-1))
        discrete_state.get_mutable_vector(self._ready).SetFromVector([1.0])
        if self._queue is not None:
            first = self._Measure(state, [port.Eval(context) for port in self._inputs])
            discrete_state.get_mutable_vector(self._queue).SetFromVector(
                np.tile(first, self._s.latency))

    def _StarNoise(self) -> np.ndarray:
        return self._s.star_tracker_noise * np.stack(
            [rng.standard_normal(self._axes) for rng in self._rngs])

    def _UpdateSample(self, context, discrete_state):
        s, h = self._s, self._h
        truth = [port.Eval(context) for port in self._inputs]
        pose, q, velocity, _ = (self._Trials(x, size) for x, size in zip(truth, self._sizes))
        state = self._Trials(context.get_discrete_state(self._state).get_value(),
                             self._width).copy()
        draws = self._draws
        for rng, row in zip(self._rngs, draws):
            rng.standard_normal(out=row)
        n, a = self._n, self._axes
        state[:, self._nq] = s.encoder_noise * draws[:, :n]
        state[:, self._nr] = s.rate_noise * draws[:, n:2 * n]
        state[:, self._ng] = s.gyro_noise * draws[:, 2 * n:2 * n + a]
        if s.gyro_bias_walk > 0:
            walk = self._walk_draws
            for rng, row in zip(self._rngs, walk):
                rng.standard_normal(out=row)
            state[:, self._bias] += s.gyro_bias_walk * np.sqrt(h) * walk
        measured_q = self._Encoders(q, state[:, self._nq])
        state[:, self._rate] += self._alpha * (
            (measured_q - state[:, self._previous]) / h - state[:, self._rate])
        state[:, self._previous] = measured_q
        if self._estimated:
            state[:, self._since_fix] += 1
            fix = state[:, self._since_fix] >= self._fix_every
            omega = (velocity[:, self._rate_columns] + state[:, self._bias]
                     + state[:, self._ng])
            if self._spatial:
                turned = _quaternion_product(_rotation_quaternion(omega * h),
                                             state[:, self._attitude])
                turned /= np.linalg.norm(turned, axis=1, keepdims=True)
            else:
                turned = state[:, self._attitude] + omega * h
            if fix[0]:          # every trial fixes at the same samples
                turned = self._Fix(pose, self._StarNoise())
                state[:, self._since_fix] = 0
            state[:, self._attitude] = turned
        discrete_state.get_mutable_vector(self._state).SetFromVector(state.reshape(-1))
        if self._queue is not None:
            queue = context.get_discrete_state(self._queue).get_value()
            discrete_state.get_mutable_vector(self._queue).SetFromVector(np.concatenate(
                [queue[self._measured:], self._Measure(state, truth)]))
