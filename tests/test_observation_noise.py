"""The measurement noise on the learner's band-passed observed torque
(learning.observation_noise) against the observer's and the regression filter's own
kernels, and the RHS integrator's chi, which reads a noisy torque error low-passed."""
import numpy as np
import pytest

from dacph_drake.kernels.loop import integrator_sample, observer_samples
from dacph_drake.learning.identification import BandPassCascade
from dacph_drake.learning.local_bayes import LocalBayesChannels
from dacph_drake.learning.observation_noise import ObservationNoise, observation_noise
from dacph_drake.scenario import Sensing

H, SAMPLE, ANTI_ALIAS = 2.5e-4, 0.01, 6.0
M = np.array([[0.02, 0.008], [0.008, 0.012]])


def _band_passed_torque(rng, rate_noise: float, observer_noise: float, trials: int,
                        samples: int) -> np.ndarray:
    """The band-passed tau_obs channel of ``trials`` independent observers of a still
    arm (C' = 0) whose rates read white noise, through observer_samples, the learner's
    sampling and its channels' band-pass (the systems' kernels)."""
    n = len(M)
    model = np.tile(np.concatenate([M.ravel(), np.zeros(n * n)]), trials)
    constants = np.concatenate([[H, 1 - np.exp(-2 * np.pi * ANTI_ALIAS * H)], np.zeros(n)])
    channels = LocalBayesChannels(n)
    cascade = BandPassCascade(2.0, 6.0, 4, 8, SAMPLE)
    state = np.zeros((cascade.num_sections, channels.size * trials))
    memory, q, u = np.zeros(6 * n * trials), np.zeros(n * trials), np.zeros(n * trials)
    decimation = int(round(SAMPLE / H))
    out = []
    for k in range(samples * decimation):
        _, memory = observer_samples(
            trials, q, rate_noise * rng.standard_normal(n * trials), memory, model, u,
            observer_noise * rng.standard_normal(n * trials), constants)
        if k % decimation == 0:
            sample = memory.reshape(trials, 6 * n)[:, n:]
            state, y = cascade.Step(state, channels.Of(k * H, sample).reshape(-1))
            out.append(y.reshape(trials, -1)[:, -n:])
    return np.concatenate(np.array(out)[200:], axis=0)     # past the filter's start


@pytest.mark.parametrize("rate_noise, observer_noise", [(1e-4, 0.0), (0.0, 1e-3)])
def test_the_predicted_noise_is_the_observer_chains(rng, rate_noise, observer_noise):
    """Tachometer noise (differenced by the observer) and the observer's own noise, each
    through the real kernels: the band-passed tau_obs's sd per row is the prediction's
    within 5 % (about 2500 independent samples: the estimate's sd is 1.4 %)."""
    cascade = BandPassCascade(2.0, 6.0, 4, 8, SAMPLE)
    predicted = observation_noise(Sensing(enabled=True, rate_noise=rate_noise), H,
                                  SAMPLE, ANTI_ALIAS, cascade, observer_noise).RowSd(M)
    measured = _band_passed_torque(rng, rate_noise, observer_noise, trials=8,
                                   samples=4200).std(axis=0)
    assert measured == pytest.approx(predicted, rel=0.05)


def test_differentiated_encoders_are_noisier_than_tachometers_by_their_chain():
    """Differenced 17-bit encoders (a count per 4 kHz sample is 0.19 rad/s) put far more
    noise in the band than 1e-4 rad/s tachometers; no sensing, no noise."""
    cascade = BandPassCascade(2.0, 6.0, 4, 8, SAMPLE)
    noise = lambda sensing: observation_noise(sensing, H, SAMPLE, ANTI_ALIAS,  # noqa: E731
                                              cascade, 0.0)
    tachometer = noise(Sensing(enabled=True, rate_noise=1e-4)).rate
    encoders = noise(Sensing(enabled=True, rate_source="differentiated",
                             encoder_counts=2**17)).rate
    assert encoders > 50 * tachometer > 0
    assert noise(Sensing(rate_noise=1e-4)) == ObservationNoise()       # not enabled


def _integrator_errors(noisy: bool, noise: np.ndarray, c: float) -> np.ndarray:
    """The e_tau state integrator_sample keeps for a zero request against tau_obs =
    ``noise`` (samples x n), with the rate c [1/s] and no gains."""
    n = noise.shape[1]
    fast = np.zeros(3 * n + 2)
    gains = np.zeros(n * n + 2 * n + 4)
    gains[n * n + 2 * n] = c
    constants = np.array([H, np.exp(-H / 2.0), 1e-3, float(noisy)])
    errors = np.empty_like(noise)
    for k, tau in enumerate(noise):
        fast = integrator_sample(fast, gains, np.zeros(n), tau, np.zeros(n),
                                 constants)[:3 * n + 2]
        errors[k] = fast[n:2 * n]
    return errors


def test_a_noisy_torque_reaches_chi_low_passed_at_the_loops_rate(rng):
    """White noise on tau_obs: without noisy_torque e_tau is the noise itself (as
    always); with it, its first-order low-pass at c, whose sd is sqrt(a / (2 - a)) of
    the noise's, a = 1 - e^(-c h) (within 5 %)."""
    noise = 0.1 * rng.standard_normal((20000, 2))
    c = 169.0
    assert np.array_equal(_integrator_errors(False, noise, c), -noise)
    filtered = _integrator_errors(True, noise, c)[2000:]
    a = 1 - np.exp(-c * H)
    assert filtered.std(axis=0) == pytest.approx(0.1 * np.sqrt(a / (2 - a)), rel=0.05)


def test_ten_times_the_spacecraft_noise_with_two_samples_of_delay_runs():
    """Trial 26 of sweeps/sensing_short.yaml (10x the spacecraft's noise, 2 samples of
    RHS delay, 1 ms lag) ran away within 0.15 s while chi followed the observer's
    noise: chi rose to ||e_tau|| of the noise (0.1-0.4 N m), the LHS's robust gain
    chi / phi with it. Now its first second runs, and chi stays below 0.1 N m."""
    from dacph_drake.loop.simulate import simulate
    from dacph_drake.log_layout import RhsLog
    from dacph_drake.montecarlo.definition import load_sweep, sample_trial
    scenario = sample_trial(load_sweep("sweeps/sensing_short.yaml"), 26).scenario
    assert scenario.sensing.rate_noise == pytest.approx(1e-3)
    assert scenario.sensing.rhs_delay == 2
    run = simulate(scenario, "dac", duration=1.0)
    assert run.status == "ok", run.reason
    chi = run.logs["rhs_log"][:, RhsLog(2).chi]
    assert np.max(chi[run.logs["time"] > 0.2]) < 0.1

