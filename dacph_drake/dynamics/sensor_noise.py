"""The noise on each reading of the measured state (scenario.Sensing; systems.sensors):
what the identifier's momentum samples carry, and the white rate noise the port observer
differentiates (learning.observation_noise)."""
from dataclasses import dataclass

import numpy as np

from dacph_drake.scenario import Sensing


def measured_rate_noise(sensing: Sensing, rhs_period: float) -> float:
    """The sd of the white noise behind the measured joint rates: the tachometers'
    rate_noise [rad/s]; or, differentiated, the encoders' (encoder_noise and a uniform
    quantization of one count, step^2 / 12) over h [rad/s], before their difference and
    low-pass; 0 when the sensors are not enabled.

    Args:
        sensing: The sensors.
        rhs_period: The sensors' and the observer's period h [s]."""
    if not sensing.enabled:
        return 0.0
    if sensing.rate_source == "tachometer":
        return sensing.rate_noise
    return float(_angle_noise(sensing) / rhs_period)


def base_rate_columns(base_velocities: int) -> slice:
    """The gyro's axes in a base velocity of this size: the planar base's [x, y, theta]
    rates (3) or Drake's floating body's [w, v] (6) (kernels.sensors reads the same).

    Args:
        base_velocities: The base velocity's size."""
    return slice(0, 3) if base_velocities == 6 else slice(2, 3)


def _angle_noise(sensing: Sensing) -> float:
    """The encoders' sd [rad]: encoder_noise and one count's uniform quantization."""
    step = 2 * np.pi / sensing.encoder_counts if sensing.encoder_counts else 0.0
    return float(np.sqrt(sensing.encoder_noise ** 2 + step ** 2 / 12.0))


@dataclass(frozen=True)
class StateNoise:
    """The sd of the noise on one reading of the measured state, each reading's noise
    independent of the last but for the gyro's bias (the sensors hold a sample's noise
    for periods.rhs; a reader every periods.learner_sample sees independent draws).

    Attributes:
        joint_angle: The encoders' [rad].
        joint_rate: The measured joint rates' [rad/s].
        base_rate: The gyro's white noise per axis [rad/s].
        gyro_bias: The gyro's initial bias' magnitude per axis [rad/s].
        gyro_bias_walk: The bias' random walk [rad/s/sqrt(s)]."""
    joint_angle: float = 0.0
    joint_rate: float = 0.0
    base_rate: float = 0.0
    gyro_bias: float = 0.0
    gyro_bias_walk: float = 0.0

    def Any(self) -> bool:
        """Whether a reading carries any noise."""
        return any(value > 0 for value in (self.joint_angle, self.joint_rate,
                                           self.base_rate, self.gyro_bias,
                                           self.gyro_bias_walk))


def state_noise(sensing: Sensing, rhs_period: float) -> StateNoise:
    """The StateNoise of ``sensing`` (all zero when it is not enabled). Differentiated
    rates are white noise e of sd measured_rate_noise differenced and low-passed (gain a =
    1 - exp(-2 pi rate_cutoff h)): impulse response a, -a^2 (1 - a)^(k-1), so their sd is
    measured_rate_noise sqrt(a^2 + a^3 / (2 - a)). The base's attitude noise (star
    tracker) is left out: it turns the zero momentum, a second-order change.

    Args:
        sensing: The sensors.
        rhs_period: The sensors' period h [s]."""
    if not sensing.enabled:
        return StateNoise()
    rate = measured_rate_noise(sensing, rhs_period)
    if sensing.rate_source != "tachometer":
        a = 1.0 - np.exp(-2 * np.pi * sensing.rate_cutoff * rhs_period)
        rate *= float(np.sqrt(a ** 2 + a ** 3 / (2.0 - a)))
    return StateNoise(joint_angle=_angle_noise(sensing), joint_rate=rate,
                      base_rate=sensing.gyro_noise, gyro_bias=abs(sensing.gyro_bias),
                      gyro_bias_walk=sensing.gyro_bias_walk)
