"""The spacecraft's sensors between the ground truth and the controllers
(scenario.Sensing): joint encoders, joint-rate tachometers or differentiated encoders,
the base's gyro and star tracker, and a latency."""
from typing import Sequence

import numpy as np
from pydrake.systems.framework import Diagram, DiagramBuilder, LeafSystem
from pydrake.systems.primitives import Demultiplexer, Multiplexer

from dacph_drake.dynamics.plant import STATE_SIGNALS
from dacph_drake.kernels import sensors as kernel
from dacph_drake.scenario import Sensing

SEED_OFFSET = 7919      # the sensors' noise streams apart from the observer's (seed)
NORMALS_BLOCK = 4096    # standard normals drawn at once per trial (_SensorSamples._Ahead)


class _SensorSamples(LeafSystem):
    """The sensors' samples and measurement (Sensors' equations; kernels.sensors) on
    the stacked truth: input ``truth``, output ``measurement``, each [base_pose, q,
    base_velocity, qdot] with each signal's trials stacked."""

    def __init__(self, *, settings: Sensing, num_joints: int, base_positions: int,
                 period: float, seeds: Sequence[int]):
        super().__init__()
        n, trials, s = num_joints, len(seeds), settings
        spatial = base_positions == 7
        self._s, self._trials, self._spatial = s, trials, spatial
        self._axes = axes = 3 if spatial else 1
        self._sizes = (base_positions, n, 6 if spatial else 3, n)
        self._rngs = [np.random.default_rng(seed + SEED_OFFSET) for seed in seeds]
        fix_every = (max(1, int(round(1.0 / (s.star_tracker_rate * period))))
                     if s.star_tracker_rate > 0 else 1)
        self._layout = np.array([
            n, trials, base_positions, self._sizes[2], axes, spatial,
            s.rate_source == "differentiated",
            s.star_tracker_rate > 0 or s.star_tracker_noise > 0, fix_every], np.int64)
        self._constants = np.array([
            2 * np.pi / s.encoder_counts if s.encoder_counts else 0.0,
            1.0 - np.exp(-2 * np.pi * s.rate_cutoff * period), s.encoder_noise,
            s.rate_noise, s.gyro_noise, s.gyro_bias_walk * np.sqrt(period), period])
        self._width = 4 * n + 2 * axes + (4 if spatial else 1) + 1
        self._attitude = slice(2 * n + 2 * axes, 2 * n + 2 * axes + (4 if spatial else 1))
        # Each trial's stream drawn ahead in blocks (_Ahead), the next unread, and
        # the most a sample reads (its noise, the bias walk's and a fix's).
        self._normals, self._cursor = np.empty((trials, 0)), 0
        self._most = 2 * n + 3 * axes
        # The trials' rows, then 0 until the initialization event has run: the output
        # is then the truth (what other systems' initialization reads).
        self._state = self.DeclareDiscreteState(self._width * trials + 1)
        self._size = sum(self._sizes) * trials
        # The measurements of the last ``latency`` samples, oldest first.
        self._queue = (self.DeclareDiscreteState(self._size * s.latency)
                       if s.latency > 0 else None)
        self._truth = self.DeclareVectorInputPort("truth", self._size)
        self._measured = np.empty(self._size)
        self.DeclareVectorOutputPort(
            "measurement", self._size, self._CalcMeasurement,
            prerequisites_of_calc={self._truth.ticket(), self.all_state_ticket()})
        self.DeclareInitializationDiscreteUpdateEvent(self._Initialize)
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._UpdateSample)

    def _CalcMeasurement(self, context, output):
        state = context.get_discrete_state(self._state).get_value()
        if state[-1] == 0:
            output.SetFromVector(self._truth.Eval(context))
        elif self._queue is not None:
            output.SetFromVector(
                context.get_discrete_state(self._queue).get_value()[:self._size])
        else:
            kernel.sensor_measure(state, self._truth.Eval(context), self._layout,
                                  self._constants, output.get_mutable_value())

    def _Ahead(self) -> np.ndarray:
        """Each trial's standard normals (a row each), at least a sample's most unread
        from ``self._cursor``: drawn NORMALS_BLOCK at a time, the numbers one draw each
        would give."""
        if self._cursor + self._most > self._normals.shape[1]:
            self._normals = np.concatenate(
                [self._normals[:, self._cursor:],
                 np.stack([rng.standard_normal(NORMALS_BLOCK) for rng in self._rngs])],
                axis=1)
            self._cursor = 0
        return self._normals

    def _AttitudeColumns(self, truth: np.ndarray) -> np.ndarray:
        """Each trial's true attitude (trials x 4 or 1)."""
        pose = truth[:self._sizes[0] * self._trials].reshape(self._trials, -1)
        return pose[:, 0:4] if self._spatial else pose[:, 2:3]

    def _Initialize(self, context, discrete_state):
        truth = self._truth.Eval(context)
        rows = np.zeros((self._trials, self._width))
        n = self._sizes[1]
        rows[:, 2 * n + self._axes:2 * n + 2 * self._axes] = self._s.gyro_bias
        normals, first = self._Ahead(), self._cursor
        star = self._s.star_tracker_noise * normals[:, first:first + self._axes]
        self._cursor += self._axes
        rows[:, self._attitude] = [
            kernel.star_fix(attitude, noise, self._spatial)
            for attitude, noise in zip(self._AttitudeColumns(truth), star)]
        q = truth[self._sizes[0] * self._trials:][:n * self._trials].reshape(
            self._trials, n)
        step = self._constants[kernel.STEP]
        rows[:, self._attitude.stop:self._attitude.stop + n] = (
            step * np.round(q / step) if step else q)
        discrete_state.get_mutable_vector(self._state).SetFromVector(
            np.append(rows.reshape(-1), 1.0))
        if self._queue is not None:
            kernel.sensor_measure(rows.reshape(-1), truth, self._layout, self._constants,
                                  self._measured)
            discrete_state.get_mutable_vector(self._queue).SetFromVector(
                np.tile(self._measured, self._s.latency))

    def _UpdateSample(self, context, discrete_state):
        truth = self._truth.Eval(context)
        # The update's state, pre-loaded with the current one: changed in place.
        state = discrete_state.get_mutable_value(self._state)
        self._cursor = kernel.sensor_sample(state, truth, self._Ahead(), self._cursor,
                                            self._layout, self._constants,
                                            self._s.star_tracker_noise)
        if self._queue is not None:
            kernel.sensor_measure(state, truth, self._layout, self._constants,
                                  self._measured)
            queue = context.get_discrete_state(self._queue).get_value()
            discrete_state.get_mutable_vector(self._queue).SetFromVector(
                np.concatenate([queue[self._size:], self._measured]))


def measures_nothing(settings: Sensing) -> bool:
    """Whether the sensors return the truth at once: no noise, bias, quantization,
    latency, differentiated rate or estimated attitude.

    Args:
        settings: The sensing section."""
    s = settings
    return (s.encoder_counts == 0 and s.rate_source == "tachometer" and s.latency == 0
            and not any((s.encoder_noise, s.rate_noise, s.gyro_noise, s.gyro_bias,
                         s.gyro_bias_walk, s.star_tracker_noise, s.star_tracker_rate)))


class Sensors(Diagram):
    """Measured ``base_pose``, ``q``, ``base_velocity`` and ``qdot`` of a batch's trials
    (outputs) from the true ones (inputs of the same names, plant.STATE_SIGNALS), every
    ``period``:

        q_m     = delta round((q + n_q) / delta),    delta = 2 pi / encoder_counts
        qdot_m  = qdot + n_r (tachometer), or the low-passed difference
                  (q_m(k) - q_m(k-1)) / h at rate_cutoff (differentiated)
        omega_m = omega + b + n_g,   b(k+1) = b(k) + gyro_bias_walk sqrt(h) N(0, 1)
        R_m     = exp([n_s]) R at each star-tracker fix, exp([omega_m] h) R_m between

    omega and R in the world frame (a planar base: the angle theta0 and its rate); the
    base's position and linear velocity pass exact (no navigation sensor is modelled).
    Each noise is Gaussian, drawn per trial from its own seeded stream and held for the
    sample; the measurement is ``latency`` samples late. A Multiplexer stacks the truth
    for one compiled sample-and-measure system, a Demultiplexer splits its measurement
    (one Python call per evaluation); settings that measure nothing (measures_nothing)
    pass the truth through.

    Args:
        settings: The sensing section.
        num_joints: n.
        base_positions: The base joint's positions (3: planar; 7: free, quaternion first).
        period: The sensors' sample period h [s] (periods.rhs).
        seeds: Each trial's seed."""

    def __init__(self, *, settings: Sensing, num_joints: int, base_positions: int,
                 period: float, seeds: Sequence[int]):
        super().__init__()
        builder = DiagramBuilder()
        trials = len(seeds)
        sizes = [size * trials for size in
                 (base_positions, num_joints, 6 if base_positions == 7 else 3, num_joints)]
        truth = builder.AddNamedSystem("truth", Multiplexer(sizes))
        measured = builder.AddNamedSystem("measured", Demultiplexer(sizes))
        if measures_nothing(settings):
            builder.Connect(truth.get_output_port(), measured.get_input_port())
        else:
            samples = builder.AddNamedSystem("samples", _SensorSamples(
                settings=settings, num_joints=num_joints, base_positions=base_positions,
                period=period, seeds=seeds))
            builder.Connect(truth.get_output_port(), samples.get_input_port())
            builder.Connect(samples.get_output_port(), measured.get_input_port())
        for i, name in enumerate(STATE_SIGNALS):
            builder.ExportInput(truth.get_input_port(i), name)
            builder.ExportOutput(measured.get_output_port(i), name)
        builder.BuildInto(self)
