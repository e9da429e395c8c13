"""The measurement noise on the learner's band-passed observed torque (docs/equations.md
E32-E33), from the sensors' datasheet (scenario.Sensing) and the observer's own noise.

The port observer differentiates the measured joint rates, tau_obs = M (qdot_m(k) -
qdot_m(k-1)) / h + ..., so white rate noise e of sd sigma at h reaches tau_obs as M
(e(k) - e(k-1)) / h, whose power grows with frequency as (2 pi f)^2 sigma^2 h: no filter
removes it inside the learner's band, where it sits beside the excitation. Row i of the
band-passed tau_obs carries noise of sd

    nu_i = sqrt((g ||M_i||)^2 + g_o^2)     [N m],

g the chain's gain on a unit M (the difference, the observer's anti-alias low-pass at h,
the sampling every periods.learner_sample and the band-pass), g_o the same chain's gain on
the observer's own noise (rhs.observer_noise, no difference). The terms (C' + b) qdot_mid
and D qdot, through which the rate noise also enters undifferentiated, are left out: in
the band they are (C' + b) / (2 pi f M) of the first, a few per cent on the arms here.
A loop whose tau_obs carries any of it (measured_rate_noise or rhs.observer_noise above
0) runs the RHS integrator's chi on a low-passed error (systems.rhs_integrator,
``noisy_torque``); docs/results/sensing.md compares nu with the port's in-band torque."""
from dataclasses import dataclass

import numpy as np

from dacph_drake.dynamics.sensor_noise import measured_rate_noise
from dacph_drake.learning.identification import BandPassCascade
from dacph_drake.scenario import Sensing

# Impulse responses are kept until they decay to this fraction of their peak.
_DECAYED = 1e-12


@dataclass(frozen=True)
class ObservationNoise:
    """The sd of the band-passed tau_obs's noise: nu_i = sqrt((rate ||M_i||)^2 + direct^2).

    Attributes:
        rate: g, the sd on a row of unit norm of M [N m per kg m^2].
        direct: g_o, the sd from the observer's own noise [N m]."""
    rate: float = 0.0
    direct: float = 0.0

    def RowSd(self, M: np.ndarray) -> np.ndarray:
        """nu_i of every row [N m] (n).

        Args:
            M: The reduced mass matrix (n x n)."""
        return np.sqrt((self.rate * np.linalg.norm(M, axis=1)) ** 2 + self.direct ** 2)


def _low_pass_response(gain: float, length: int) -> np.ndarray:
    """The first-order low-pass y_k = y_(k-1) + gain (x_k - y_(k-1))'s impulse response."""
    return gain * (1.0 - gain) ** np.arange(length)


def _decay_length(gain: float) -> int:
    """Samples until a first-order low-pass of this gain decays to _DECAYED."""
    return int(np.ceil(np.log(_DECAYED) / np.log1p(-gain))) + 1 if gain < 1 else 1


def _autocorrelation(response: np.ndarray) -> np.ndarray:
    """sum_k g_k g_(k+l) for l >= 0 (FFT)."""
    size = 1 << int(np.ceil(np.log2(2 * len(response))))
    spectrum = np.fft.rfft(response, size)
    return np.fft.irfft(spectrum * np.conj(spectrum), size)[:len(response)]


def band_noise_gain(response: np.ndarray, decimation: int,
                    cascade: BandPassCascade) -> float:
    """The sd of white unit noise through ``response`` at h, taken every ``decimation``-th
    sample and band-passed by ``cascade``: sqrt(sum_l R_v(l) R_f(l)), R_v the sampled
    noise's autocorrelation (R_x at multiples of the decimation), R_f the band-pass's.

    Args:
        response: The impulse response from the white noise to the sampled signal at h.
        decimation: periods.learner_sample / h (an integer).
        cascade: The learner's band-pass at periods.learner_sample."""
    sampled = _autocorrelation(response)[::decimation]
    length = max(_decay_length(float(np.min(cascade.gains))) * cascade.num_sections, 2)
    impulse = np.zeros((length, 1))
    impulse[0] = 1.0
    band = _autocorrelation(cascade.Filter(impulse)[:, 0])
    lags = min(len(sampled), len(band))
    variance = sampled[0] * band[0] + 2.0 * np.dot(sampled[1:lags], band[1:lags])
    return float(np.sqrt(max(variance, 0.0)))


def observation_noise(sensing: Sensing, rhs_period: float, sample_period: float,
                      anti_alias_cutoff: float, cascade: BandPassCascade,
                      observer_noise: float) -> ObservationNoise:
    """The ObservationNoise of a loop whose sensors are ``sensing`` (scenario.Sensing).

    The measured rate's noise: measured_rate_noise, white for the tachometers, or
    differenced at h and low-passed at rate_cutoff for the differentiated encoders.

    Args:
        sensing: The sensors (not enabled: no rate noise).
        rhs_period: The observer's period h [s].
        sample_period: The learner's sampling period [s], a multiple of h.
        anti_alias_cutoff: The observer's low-pass on its regression channels [Hz]
            (0: none).
        cascade: The learner's band-pass.
        observer_noise: rhs.observer_noise [N m]."""
    h = rhs_period
    decimation = max(int(round(sample_period / h)), 1)
    anti_alias = (1.0 - np.exp(-2 * np.pi * anti_alias_cutoff * h)
                  if anti_alias_cutoff > 0 else 1.0)
    length = max(_decay_length(anti_alias), 2) + decimation
    sd, rate_filter = measured_rate_noise(sensing, h), np.zeros(length)
    rate_filter[0] = 1.0
    if sensing.enabled and sensing.rate_source != "tachometer":
        cutoff = 1.0 - np.exp(-2 * np.pi * sensing.rate_cutoff * h)
        length += _decay_length(cutoff)
        rate_filter = np.convolve(np.r_[1.0, -1.0],
                                  _low_pass_response(cutoff, length))[:length]
    low_pass = _low_pass_response(anti_alias, length)
    differenced = np.convolve(np.convolve(rate_filter[:length], [1.0, -1.0]) / h,
                              low_pass)[:length]
    return ObservationNoise(
        rate=sd * band_noise_gain(differenced, decimation, cascade) if sd > 0 else 0.0,
        direct=(observer_noise * band_noise_gain(low_pass, decimation, cascade)
                if observer_noise > 0 else 0.0))
