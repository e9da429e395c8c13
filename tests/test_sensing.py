"""Sensors, delays and lags between the ground truth and the controllers
(scenario.Sensing, systems.sensors, controllers.closed_loop.AddSensors/AddActuation) and
the RHS loop's certificate that knows them (analysis.rhs_loop.delayed_loop_matrix)."""
import dataclasses

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import ConstantVectorSource, LogVectorOutput

from dacph_drake.analysis.rhs_loop import (check_rhs_loop, delayed_loop_matrix,
                                           largest_tolerated_delay)
from dacph_drake.assembly.scenario_files import load_scenario
from dacph_drake.controllers.dac import build_dac_diagram
from dacph_drake.gain_rule import (STABILITY_MARGIN, best_damped_gain, certified_radius,
                                   lag_pole, loop_matrix, separates_by_decay,
                                   stays_stable_if_wrong)
from dacph_drake.kernels.certificate import (box_certificate, certified_gains, lag_weight,
                                             mode_radius, roots_within)
from dacph_drake.loop.simulate import simulate
from dacph_drake.scenario import Phases, Sensing
from dacph_drake.scenario.built_in import spacecraft_sensing
from dacph_drake.scenario.errors import ConfigError
from dacph_drake.systems.inertial_identifier import InertialIdentifier
from dacph_drake.systems.sensors import SEED_OFFSET, Sensors

H = 2.5e-4


def _tiny(name: str, sensing: Sensing):
    scenario = load_scenario(name)
    scenario.phases = Phases(warmup=0.2, linear=0.3, nonlinear=0.3, disturbance=0.3)
    scenario.sensing = sensing
    return scenario


def test_sensing_is_off_by_default_and_adds_no_system():
    loop = build_dac_diagram(_tiny("short", Sensing()))
    assert not {"sensors", "rhs_delay", "actuator_lag", "lhs_delay"} & set(loop.systems)
    on = build_dac_diagram(_tiny("short", Sensing(enabled=True, rhs_delay=2, lhs_delay=1,
                                                  actuator_lag=0.005)))
    assert {"sensors", "rhs_delay", "actuator_lag", "lhs_delay"} <= set(on.systems)


def test_the_integrator_knows_the_modelled_delay_and_not_the_unmodelled_one():
    """sensing.rhs_delay + latency is the delay the RHS integrator's certificate uses;
    unmodelled_delay lengthens only the delay line the command goes through."""
    loop = build_dac_diagram(_tiny("short", Sensing(enabled=True, rhs_delay=1, latency=1,
                                                    unmodelled_delay=2,
                                                    actuator_lag=0.002)))
    integrator = loop.systems["rhs_integrator"]
    assert (integrator._delay, integrator._pole) == (2, lag_pole(H, 0.002))
    # DelayLine: 1 + 2 samples of delay are 2 steps of Drake's DiscreteTimeDelay,
    # which holds 2 + 1 copies of the command (n = 2).
    context = loop.systems["rhs_delay"].CreateDefaultContext()
    assert context.get_discrete_state_vector().size() == (2 + 1) * 2


def test_the_best_damped_gain_is_a_quarter_without_delay_and_smaller_with_it():
    """best_damped_gain: 1/4 and radius 1/2 for z^2 - z + g; with a delay and a lag the
    gain is smaller and no gain on a fine grid gives a smaller radius."""
    gain, radius = best_damped_gain(H)
    assert gain == pytest.approx(0.25, abs=1e-6) and radius == pytest.approx(0.5, abs=1e-3)
    for delay, lag in ((1, 0.0), (1, 1e-3), (2, 5e-3)):
        gain, radius = best_damped_gain(H, delay, lag)
        assert gain < 0.25
        grid = [mode_radius(complex(g), delay, lag_pole(H, lag))
                for g in np.linspace(1e-3, 1.0, 2000)]
        assert radius <= min(grid) + 1e-9


def test_the_certified_radius_is_the_margin_per_sample_without_delay_or_lag():
    """Without a delay or a lag the certificate's radius is 1 - STABILITY_MARGIN exactly
    (every run without sensing keeps its certificate), a tenth of the best margin 1/2."""
    for h in (H, 2 * H, 1e-3):
        assert certified_radius(h) == 1.0 - STABILITY_MARGIN
    for delay, lag in ((1, 0.0), (1, 1e-3), (2, 5e-3)):
        best = best_damped_gain(H, delay, lag)[1]
        assert 1.0 - certified_radius(H, delay, lag) == pytest.approx(
            0.1 * (1.0 - best), rel=1e-12)


def test_a_lag_slower_than_the_margin_per_sample_is_certified_at_the_best_gain():
    """A 5 ms lag at 4 kHz has its own pole at 0.951, beyond 1 - STABILITY_MARGIN: no
    gain meets a margin of 0.05 per sample (the best radius is 0.976), and the
    certificate asks a tenth of the best margin instead. At the best-damped gain the
    loop is certified; slower than it by 20 and the radius passes the bound and
    the certificate fails, naming it."""
    delay, lag = 2, 5e-3
    assert lag_pole(H, lag) > 1.0 - STABILITY_MARGIN
    gain, best = best_damped_gain(H, delay, lag)
    assert best > 1.0 - STABILITY_MARGIN
    B = np.array([[1.0, 0.1], [0.05, 0.9]])
    modes = np.linalg.eigvals(B).real
    K = gain / H / modes.max() * np.ones(2)
    check = check_rhs_loop(B, K, H, lambda_lhs=1.0, Td=1.0, delay=delay, lag=lag)
    assert check.ok, check.reason
    assert check.spectral_radius <= certified_radius(H, delay, lag) < 1.0
    slow = check_rhs_loop(B, K / 20, H, lambda_lhs=1.0, Td=1.0, delay=delay, lag=lag)
    assert slow.spectral_radius < 1.0 and not slow.ok
    assert "spectral radius" in slow.reason


def test_a_jump_on_evidence_is_judged_on_the_loop_with_its_delay_and_lag():
    """stays_stable_if_wrong with the command a sample late and a 5 ms lag at 4 kHz
    judges the lagged loop at its certified radius: at the best-damped gain the loop
    without them (radius 0.990, beyond 0.95) would refuse a jump the lagged loop takes
    (0.986 <= 0.9976), and at 40 times it would take one that leaves the lagged loop
    unstable (1.003)."""
    delay, lag = 1, 5e-3
    radius = certified_radius(H, delay, lag)
    B = np.array([[1.0, 0.1], [0.05, 0.9]])
    best = best_damped_gain(H, delay, lag)[0] / H / np.linalg.eigvals(B).real.max()
    K = np.full(2, best)
    assert not stays_stable_if_wrong(B, K, H, 1.0 - STABILITY_MARGIN)
    assert stays_stable_if_wrong(B, K, H, radius, delay, lag)
    assert stays_stable_if_wrong(B, 40 * K, H, 1.0 - STABILITY_MARGIN)
    assert not stays_stable_if_wrong(B, 40 * K, H, radius, delay, lag)
    assert np.max(np.abs(np.linalg.eigvals(
        delayed_loop_matrix(B, 40 * K, H, delay, lag)))) > 1.0


def test_with_a_lag_the_separation_is_the_loops_decay_rate():
    """Eq. 45's sigma_RHS = k lambda is the loop's rate without a lag; with the 6-DOF
    satellite's 5 ms lag, 2 samples late at 2 kHz (lambda_LHS = 40 1/s, Td = 2) the
    best-damped c = 42 1/s decays at 91 1/s and meets the separation's 80 1/s, though
    its k lambda does not, while c = 150 1/s has k lambda beyond 80 and decays slower
    (71 1/s): the check asks the decay (gain_rule.separates_by_decay), and without a
    delay or lag it asks sigma_RHS as before."""
    h, lambda_lhs, Td = 5e-4, 40.0, 2.0
    assert separates_by_decay(2, 5e-3) and not separates_by_decay(0, 0.0)
    cap = best_damped_gain(h, 2, 5e-3)[0] / h
    best = check_rhs_loop(np.eye(2), np.full(2, cap), h, lambda_lhs, Td, 2, 5e-3)
    assert best.sigma_rhs < Td * lambda_lhs <= best.decay_rate and best.ok
    fast = check_rhs_loop(np.eye(2), np.full(2, 150.0), h, lambda_lhs, Td, 2, 5e-3)
    assert fast.sigma_rhs > Td * lambda_lhs > fast.decay_rate and not fast.ok
    assert "decay rate" in fast.reason
    slow = check_rhs_loop(np.eye(2), np.full(2, 79.0), 2.5e-4, lambda_lhs, Td)
    assert slow.decay_rate > Td * lambda_lhs > slow.sigma_rhs and not slow.ok


def test_a_certificate_with_a_lag_certifies_by_the_loops_decay():
    """certified_gains with the satellite's lag: by k lambda no rate up to the
    best-damped one meets 80 1/s (not certified); by the decay the rate at which the
    set's slowest mode is best damped is, and the box's radius is within exp(-h 80)
    and the certified radius."""
    h, delay, lag, rate = 5e-4, 2, 5e-3, 80.0
    pole, cap = lag_pole(h, lag), best_damped_gain(h, delay, lag)[0] / h
    lower = np.array([[0.97, -0.01], [-0.01, 0.97]])
    upper = np.array([[1.03, 0.01], [0.01, 1.03]])
    results = {}
    for by_decay in (False, True):
        out, K = np.empty((1, 4)), np.empty((1, 2))
        certified_gains(lower[None], upper[None], np.ones((1, 2)), np.zeros((1, 2)),
                        np.array([176.0]), np.zeros(1), np.array([rate]), h, cap,
                        certified_radius(h, delay, lag), out, K, delay, pole, by_decay)
        results[by_decay] = out[0].copy(), K[0].copy()
    assert results[False][0][1] == 0.0
    out, K = results[True]
    assert out[1] == 1.0 and cap <= out[0] <= cap / 0.96 * (1 + 1e-12)
    radius = box_certificate(lower, upper, K, h, delay, pole)[1]
    assert radius <= min(np.exp(-h * rate), certified_radius(h, delay, lag))


def test_the_certified_margin_is_a_rate_where_the_lag_is_slow():
    """With a lag of many samples the margin the certificate asks is a decay rate,
    -ln(radius) / h, nearly the same at 4 and 8 kHz (the margin per sample is not)."""
    rates = [-np.log(certified_radius(h, 0, 5e-3)) / h for h in (H, H / 2)]
    assert rates[1] == pytest.approx(rates[0], rel=0.05)


@pytest.mark.parametrize("name", ["short", "satellite_3dof"])
def test_noiseless_sensors_without_delays_change_no_log(name):
    """The sensors wired in with no noise, quantization, latency or lag: every log of
    the run is the one without them, bit for bit (their outputs equal their inputs)."""
    off = simulate(_tiny(name, Sensing()), "dac").logs
    on = simulate(_tiny(name, Sensing(enabled=True)), "dac").logs
    for log in off:
        assert np.array_equal(off[log], on[log], equal_nan=True), log


def _sensors(settings: Sensing, pose, q, velocity, qdot, seeds=(3,), duration=1.0):
    """Simulates a Sensors alone on constant true signals; returns its logged outputs."""
    builder = DiagramBuilder()
    sensors = builder.AddSystem(Sensors(settings=settings, num_joints=len(q) // len(seeds),
                                        base_positions=len(pose) // len(seeds),
                                        period=H, seeds=list(seeds)))
    for name, value in zip(("base_pose", "q", "base_velocity", "qdot"),
                           (pose, q, velocity, qdot)):
        source = builder.AddSystem(ConstantVectorSource(np.asarray(value, float)))
        builder.Connect(source.get_output_port(), sensors.GetInputPort(name))
    logs = {name: LogVectorOutput(sensors.GetOutputPort(name), builder, H)
            for name in ("base_pose", "q", "base_velocity", "qdot")}
    diagram = builder.Build()
    simulator = Simulator(diagram)
    simulator.AdvanceTo(duration)
    context = simulator.get_context()
    return {name: log.FindLog(context).data().T for name, log in logs.items()}


def test_encoders_quantize_to_their_counts():
    counts = 2**17
    q = [0.3 + 1e-6, -1.234567]
    out = _sensors(Sensing(enabled=True, encoder_counts=counts), [0, 0, 0.1], q,
                   [0, 0, 0], [0, 0], duration=0.01)["q"]
    step = 2 * np.pi / counts
    assert np.allclose(out / step, np.round(out / step), atol=1e-9)
    assert np.all(np.abs(out - q) <= step / 2 + 1e-15)


def test_the_sensors_noise_is_each_trials_stream_in_order_across_blocks():
    """The sensors draw each trial's standard normals NORMALS_BLOCK at a time and read
    them in the order one draw each would: at the start the star tracker's fix (axes),
    then per sample the encoders', the rates' and the gyro's noise (2 n + axes) and the
    bias walk's (axes). The rate noise read back from the tachometers' measurement is
    that stream's, past a block's end (1200 samples of 6 normals > 4096)."""
    noise, seeds, n = 1e-3, (3, 11), 2
    qdot = np.array([0.2, -0.4, 0.1, 0.3])
    out = _sensors(Sensing(enabled=True, rate_noise=noise, gyro_noise=1e-4,
                           gyro_bias_walk=1e-5), np.tile([0, 0, 0.1], 2),
                   np.tile([0.3, 1.0], 2), np.zeros(6), qdot, seeds=seeds,
                   duration=1200 * H)["qdot"]
    read = (out - qdot).reshape(len(out), 2, n) / noise
    per_sample = 2 * n + 1 + 1
    for i, seed in enumerate(seeds):
        stream = np.random.default_rng(seed + SEED_OFFSET).standard_normal(
            1 + per_sample * 1300)
        drawn = np.array([stream[1 + per_sample * k + n:1 + per_sample * k + 2 * n]
                          for k in range(1300)])
        moved = [shift for shift in range(-2, 3)
                 if np.allclose(read[4:, i], drawn[4 + shift:4 + shift + len(read) - 4],
                                rtol=0, atol=1e-9)]
        assert len(moved) == 1, seed
        assert len(read) - 4 + 4 + moved[0] > 4096 // per_sample


def test_gyro_noise_and_bias_walk_have_their_sizes():
    """The planar base's measured rate: omega + b + n_g, n_g of sd gyro_noise per sample;
    b starts at gyro_bias and walks with variance gyro_bias_walk^2 t."""
    noise, bias, walk, duration = 1e-3, 2e-4, 5e-3, 4.0
    seeds = tuple(range(40))
    trials = len(seeds)
    out = _sensors(Sensing(enabled=True, gyro_noise=noise, gyro_bias=bias,
                           gyro_bias_walk=walk),
                   np.tile([0, 0, 0.1], trials), np.tile([0.3, 1.0], trials),
                   np.tile([0, 0, 0.05], trials), np.zeros(2 * trials), seeds=seeds,
                   duration=duration)["base_velocity"].reshape(-1, trials, 3)
    error = out[1:, :, 2] - 0.05
    increments = np.diff(error, axis=0)          # white noise differences: var 2 sd^2
    assert np.std(increments) == pytest.approx(np.sqrt(2) * noise, rel=0.05)
    final_bias = np.mean(error[-400:], axis=0)   # the bias at the end, per trial
    assert np.mean(final_bias) == pytest.approx(bias, abs=4 * walk * np.sqrt(duration)
                                                / np.sqrt(trials))
    assert np.std(final_bias) == pytest.approx(walk * np.sqrt(duration), rel=0.35)



@pytest.mark.parametrize("rate_source", ["tachometer", "differentiated"])
def test_state_noise_is_the_sd_of_each_reading(rate_source):
    """dynamics.sensor_noise.state_noise, what the identifier's draws read (the encoders',
    the measured joint rates' and the gyro's sd), is the Sensors' own within 5 %: the
    tachometers' rate_noise, or the encoders' white noise differenced and low-passed."""
    from dacph_drake.dynamics.sensor_noise import state_noise
    settings = Sensing(enabled=True, encoder_noise=2e-6, rate_source=rate_source,
                       rate_noise=1e-4, rate_cutoff=200.0, gyro_noise=3e-4)
    seeds = tuple(range(10))
    trials = len(seeds)
    out = _sensors(settings, np.tile([0, 0, 0.1], trials), np.tile([0.3, 1.0], trials),
                   np.tile([0, 0, 0.05], trials), np.zeros(2 * trials), seeds=seeds,
                   duration=0.5)
    noise = state_noise(settings, H)
    settled = slice(100, None)
    angles = out["q"][settled] - np.tile([0.3, 1.0], trials)
    assert np.std(angles) == pytest.approx(noise.joint_angle, rel=0.05)
    assert np.std(out["qdot"][settled]) == pytest.approx(noise.joint_rate, rel=0.05)
    rates = out["base_velocity"][settled].reshape(-1, trials, 3)[:, :, 2]
    assert np.std(rates) == pytest.approx(noise.base_rate, rel=0.05)
    assert state_noise(Sensing(rate_noise=1e-4), H) == state_noise(Sensing(), H)


def test_the_gyro_carries_the_attitude_between_star_tracker_fixes():
    """A spatial base turning at a constant world rate: with exact sensors the estimate
    propagated by the gyro is the truth's attitude at the last fix turned by omega t
    (the truth held constant here, the estimate turns away from it by |omega| t since
    the fix); at each fix it is reset to the truth."""
    omega = np.array([0.0, 0.0, 0.2])
    rate = 10.0
    out = _sensors(Sensing(enabled=True, star_tracker_rate=rate, star_tracker_noise=1e-9),
                   [1, 0, 0, 0, 0, 0, 0], [0.1], np.concatenate([omega, [0, 0, 0]]),
                   [0.0], duration=0.35)["base_pose"]
    angle = 2 * np.arctan2(np.linalg.norm(out[:, 1:4], axis=1), out[:, 0])
    t = np.arange(len(angle)) * H
    since_fix = (t + 1e-9) % (1 / rate)
    drifted = since_fix > 2 * H                  # away from the fix
    assert np.allclose(angle[drifted], 0.2 * since_fix[drifted], atol=1e-9)
    assert np.all(angle[~drifted] < 2e-4)


def test_the_delayed_loop_matrix_is_the_recursion_it_models():
    """delayed_loop_matrix iterated equals the loop's recursion run step by step (the
    integrator, a delay line of d commands, the sampled first-order lag, tau_obs one
    sample late: the lag's output averaged over the sample, as the port observer's
    momentum difference measures it), and with no delay or lag it is
    gain_rule.loop_matrix."""
    rng = np.random.default_rng(0)
    B = np.eye(3) + 0.1 * rng.standard_normal((3, 3))
    K, d, lag = np.array([500.0, 700.0, 900.0]), 3, 0.002
    assert np.array_equal(delayed_loop_matrix(B, K, H), loop_matrix(B, K, H))
    A = delayed_loop_matrix(B, K, H, d, lag)
    a = np.exp(-H / lag)
    b = (1 - a) / np.log(1 / a)
    u_I, line, s, tau = rng.standard_normal(3), [rng.standard_normal(3) for _ in range(d)], \
        rng.standard_normal(3), rng.standard_normal(3)
    x = np.concatenate([u_I, *line, s, tau])
    for _ in range(25):
        applied = line[-1]
        s_next = a * s + (1 - a) * applied
        u_I, line, s, tau = (u_I - H * K * tau, [u_I] + line[:-1], s_next,
                             B @ ((1 - b) * applied + b * s))
        x = A @ x
        assert np.allclose(x, np.concatenate([u_I, *line, s, tau]))


def test_the_lag_weight_is_the_lags_output_averaged_over_a_sample():
    """Under a held command u from s(0), s(t) = u + (s(0) - u) e^(-t / lag); its mean over
    [0, h] is (1 - b) u + b s(0), b = lag_weight(a) (a fine trapezoid quadrature)."""
    for lag in (2e-4, 1e-3, 5e-3):
        a = lag_pole(H, lag)
        t = np.linspace(0.0, H, 20001)
        response = 1.0 + (0.3 - 1.0) * np.exp(-t / lag)
        mean = np.sum(0.5 * (response[1:] + response[:-1]) * np.diff(t)) / H
        b = lag_weight(a)
        assert abs(mean - ((1 - b) * 1.0 + b * 0.3)) < 1e-9


def test_the_mode_polynomial_has_the_loop_matrix_eigenvalues_as_roots():
    """The certificate's per-mode test (kernels.certificate.roots_within) agrees with
    the delayed loop matrix's spectral radius on random loops with delays and lags."""
    rng = np.random.default_rng(3)
    for _ in range(60):
        B = np.eye(3) + 0.2 * rng.standard_normal((3, 3))
        K = rng.uniform(100.0, 1500.0, 3)
        d, lag = int(rng.integers(0, 5)), float(rng.choice([0.0, 1e-3, 4e-3]))
        radius = np.max(np.abs(np.linalg.eigvals(delayed_loop_matrix(B, K, H, d, lag))))
        modes = np.linalg.eigvals(H * np.diag(K) @ B).astype(complex)
        for bound in (radius - 1e-6, radius + 1e-6):
            assert all(roots_within(mu, d, lag_pole(H, lag), bound) for mu in modes) \
                == (bound > radius)


def test_a_certificate_that_knows_the_delay_keeps_the_delayed_loop_within_bound():
    """On a set of B, the rate certified without the delay and lag leaves the delayed,
    lagged loop beyond the radius bound; certified with them (certified_gains' delay
    and pole) the box certificate with them holds: what the integrator adopts."""
    n, h, rate = 2, H, 100.0
    lower = np.array([[0.8, -0.05], [-0.05, 0.8]])
    upper = np.array([[1.3, 0.05], [0.05, 1.3]])
    delay, pole = 2, lag_pole(h, 1e-3)
    gains = {}
    for known in (False, True):
        out, K = np.empty((1, 4)), np.empty((1, n))
        certified_gains(lower[None], upper[None], np.ones((1, n)), np.zeros((1, n)),
                        np.array([0.25 / h]), np.array([rate]), np.array([rate]), h,
                        0.25 / h, 0.95, out, K, delay if known else 0,
                        pole if known else 0.0)
        assert out[0, 1] == 1.0
        gains[known] = K[0].copy()
    assert box_certificate(lower, upper, gains[False], h, delay, pole)[1] > 0.95
    slowest, radius = box_certificate(lower, upper, gains[True], h, delay, pole)
    assert radius <= 0.95 and slowest >= rate * (1 - 1e-9)
    assert np.all(gains[True] < gains[False])


def test_the_tolerated_delay_counts_up_from_the_runs_own():
    """A loop tuned for a delay of 2 samples may be worse without the delay (a delay
    speeds the slow root): the tolerated delay scans from the run's delay up."""
    B, K = np.eye(2), np.full(2, 0.05 / H)
    at_zero = np.max(np.abs(np.linalg.eigvals(delayed_loop_matrix(B, K, H))))
    at_two = np.max(np.abs(np.linalg.eigvals(delayed_loop_matrix(B, K, H, 2))))
    assert at_two < at_zero
    radius = 0.5 * (at_zero + at_two)
    assert largest_tolerated_delay(B, K, H, radius=radius) == -1
    tolerated = largest_tolerated_delay(B, K, H, radius=radius, start=2)
    assert tolerated >= 2
    assert np.max(np.abs(np.linalg.eigvals(
        delayed_loop_matrix(B, K, H, tolerated + 1)))) >= radius


def test_the_tolerated_delay_is_where_the_radius_crosses():
    B = np.array([[1.0, 0.1], [0.05, 0.9]])
    K = np.array([800.0, 900.0])
    for lag in (0.0, 0.002):
        stable = largest_tolerated_delay(B, K, H, lag, radius=1.0)
        radius = [np.max(np.abs(np.linalg.eigvals(delayed_loop_matrix(B, K, H, d, lag))))
                  for d in (stable, stable + 1)]
        assert radius[0] < 1.0 <= radius[1]
        assert largest_tolerated_delay(B, K, H, lag) <= stable


@pytest.mark.parametrize("setting, value, message", [
    ("rate_source", "kalman", r"sensing.rate_source = 'kalman'; allowed: tachometer, "
                              r"differentiated"),
    ("star_tracker_rate", 1e5, r"sensing.star_tracker_rate"),
    ("gyro_noise", -1.0, r"sensing.gyro_noise = -1.0"),
    ("rhs_delay", -1, r"sensing.rhs_delay = -1"),
    ("lhs_delay", 2000, r"sensing.lhs_delay = 2000"),
    ("latency", -2, r"sensing.latency = -2"),
    ("encoder_counts", -1, r"sensing.encoder_counts = -1"),
    ("encoder_noise", -1e-3, r"sensing.encoder_noise"),
    ("rate_noise", -1e-3, r"sensing.rate_noise"),
    ("rate_cutoff", 0.0, r"sensing.rate_cutoff = 0.0"),
    ("gyro_bias", float("nan"), r"sensing.gyro_bias"),
    ("gyro_bias_walk", -1.0, r"sensing.gyro_bias_walk"),
    ("star_tracker_noise", -1.0, r"sensing.star_tracker_noise"),
    ("actuator_lag", -0.005, r"sensing.actuator_lag"),
    ("unmodelled_delay", -1, r"sensing.unmodelled_delay = -1"),
])
def test_a_bad_sensing_setting_is_named(setting, value, message):
    from dacph_drake.assembly.registry import validate_scenario
    scenario = _tiny("short", Sensing(enabled=True))
    setattr(scenario.sensing, setting, value)
    with pytest.raises(ConfigError, match=message):
        validate_scenario(scenario)


def test_a_delay_line_of_k_samples_delays_a_discrete_signal_by_k_samples():
    """DelayLine(h, k) between a system updated every h and one reading it at the same
    instants: the reader sees the value k samples later than it would directly."""
    from pydrake.systems.framework import LeafSystem
    from dacph_drake.controllers.closed_loop import DelayLine

    class Counter(LeafSystem):
        def __init__(self, reads: bool):
            super().__init__()
            self._u = self.DeclareVectorInputPort("u", 1) if reads else None
            state = self.DeclareDiscreteState(1)
            self.DeclareStateOutputPort("y", state)
            self.DeclarePeriodicDiscreteUpdateEvent(H, 0.0, self._Update)

        def _Update(self, context, discrete_state):
            value = (self._u.Eval(context) if self._u is not None
                     else context.get_discrete_state(0).get_value() + 1)
            discrete_state.get_mutable_vector(0).SetFromVector(value)

    for k in (1, 3):
        builder = DiagramBuilder()
        counter = builder.AddSystem(Counter(False))
        direct, delayed = builder.AddSystem(Counter(True)), builder.AddSystem(Counter(True))
        line = builder.AddSystem(DelayLine(H, k, 1))
        builder.Connect(counter.get_output_port(), direct.get_input_port())
        builder.Connect(counter.get_output_port(), line.get_input_port())
        builder.Connect(line.get_output_port(), delayed.get_input_port())
        logs = [LogVectorOutput(s.get_output_port(), builder, H) for s in (direct, delayed)]
        simulator = Simulator(builder.Build())
        simulator.AdvanceTo(12 * H)
        direct_log, delayed_log = (log.FindLog(simulator.get_context()).data().ravel()
                                   for log in logs)
        assert np.array_equal(delayed_log[k:], direct_log[:-k])


def test_an_unknown_sensing_key_in_a_file_is_refused(tmp_path):
    (tmp_path / "s.yaml").write_text("sensing: {enabeld: true}\n")
    with pytest.raises(ConfigError, match="enabeld"):
        load_scenario(tmp_path / "s.yaml")


def test_a_run_saved_before_sensing_keeps_its_fingerprint():
    """The sensing section off, as introduced, leaves a scenario's fingerprinted text
    as it was before the section existed; turned on, it changes the fingerprint."""
    from pydrake.common.yaml import yaml_dump_typed
    from dacph_drake.assembly.scenario_files import saved_forms
    scenario = load_scenario("short")
    text = saved_forms(scenario)[0]
    assert "sensing:" in yaml_dump_typed(scenario) and "sensing:" not in text
    scenario.sensing.enabled = True
    assert "sensing:" in saved_forms(scenario)[0]


def test_a_sensing_run_saved_before_unmodelled_delay_reads_it_at_zero(tmp_path):
    """A saved run with the sensors on, written before sensing.unmodelled_delay existed
    (its file has no such line), loads with the delay 0, the behaviour before it, and
    keeps its fingerprinted text; a nonzero delay is in that text."""
    from pydrake.common.yaml import yaml_dump_typed
    from dacph_drake.assembly.scenario_files import saved_forms
    scenario = load_scenario("short")
    scenario.sensing = spacecraft_sensing()
    text = yaml_dump_typed(scenario)
    assert "  unmodelled_delay: 0\n" in text
    (tmp_path / "saved.yaml").write_text(text.replace("  unmodelled_delay: 0\n", ""))
    loaded = load_scenario(tmp_path / "saved.yaml")
    assert loaded.sensing.unmodelled_delay == 0
    assert saved_forms(loaded)[0] == saved_forms(scenario)[0]
    assert "unmodelled_delay" not in saved_forms(scenario)[0]
    scenario.sensing.unmodelled_delay = 2
    assert "unmodelled_delay: 2" in saved_forms(scenario)[0]


def test_the_learning_report_names_the_rate_noise_where_most_quantities_stay_at_the_prior():
    """With tachometer noise above RATE_NOISE_LIMIT and most quantities at the prior the
    report names the noise and its size on the observer's acceleration; not below the
    limit, not with most quantities learned, not with sensing off."""
    from dacph_drake.loop.metrics import RATE_NOISE_LIMIT, _rate_noise_note
    scenario = _tiny("short", Sensing(enabled=True, rate_noise=1e-4))
    note = _rate_noise_note(scenario, 0.97)
    assert "97 %" in note and "0.0001 rad/s per sample" in note
    assert f"{np.sqrt(2) * 1e-4 / H:.3g} rad/s^2" in note
    assert _rate_noise_note(scenario, 0.5) == ""
    scenario.sensing.rate_noise = 0.5 * RATE_NOISE_LIMIT
    assert _rate_noise_note(scenario, 0.97) == ""
    assert _rate_noise_note(_tiny("short", Sensing(rate_noise=1e-4)), 0.97) == ""


def test_the_observed_command_is_the_torque_the_actuators_delivered_over_the_sample():
    """dac._ObservedCommand: what the port observer reads at t_(k+1) (before that
    instant's updates) is the actuators' torque averaged over [t_k, t_(k+1)): a
    command updated every h, delayed by DelayLine and lagged by Drake's
    FirstOrderLowPassFilter (the actuation path), integrated exactly; to 1e-9."""
    from pydrake.systems.framework import LeafSystem
    from pydrake.systems.primitives import FirstOrderLowPassFilter, Integrator
    from dacph_drake.controllers.closed_loop import DelayLine
    from dacph_drake.controllers.dac import _ObservedCommand
    from dacph_drake.scenario import Scenario

    class Command(LeafSystem):
        def __init__(self):
            super().__init__()
            self.rng = np.random.default_rng(5)
            state = self.DeclareDiscreteState(2)
            self.DeclareStateOutputPort("u", state)
            self.DeclarePeriodicDiscreteUpdateEvent(H, 0.0, self.Update)

        def Update(self, context, discrete_state):
            discrete_state.get_mutable_vector().SetFromVector(self.rng.normal(size=2))

    class Probe(LeafSystem):
        def __init__(self):
            super().__init__()
            self.seen = []
            self.integral = self.DeclareVectorInputPort("integral", 2)
            self.observed = self.DeclareVectorInputPort("observed", 2)
            self.DeclarePeriodicDiscreteUpdateEvent(H, 0.0, self.Update)
            self.DeclareDiscreteState(1)

        def Update(self, context, discrete_state):
            self.seen.append((context.get_time(), self.integral.Eval(context).copy(),
                              self.observed.Eval(context).copy()))

    scenario = Scenario()
    scenario.periods.rhs = H
    scenario.sensing = Sensing(enabled=True, rhs_delay=2, latency=1, actuator_lag=0.001)
    builder = DiagramBuilder()
    command = builder.AddSystem(Command())
    line = builder.AddSystem(DelayLine(H, 3, 2))
    lag = builder.AddSystem(FirstOrderLowPassFilter(0.001, 2))
    integral = builder.AddSystem(Integrator(2))
    builder.Connect(command.get_output_port(), line.get_input_port())
    builder.Connect(line.get_output_port(), lag.get_input_port())
    builder.Connect(lag.get_output_port(), integral.get_input_port())
    probe = builder.AddSystem(Probe())
    builder.Connect(integral.get_output_port(), probe.GetInputPort("integral"))
    builder.Connect(_ObservedCommand(builder, scenario, command.get_output_port()),
                    probe.GetInputPort("observed"))
    simulator = Simulator(builder.Build())
    simulator.get_mutable_integrator().set_target_accuracy(1e-12)
    simulator.AdvanceTo(60 * H)
    times, integrals, observed = zip(*probe.seen)
    delivered = np.diff(np.array(integrals), axis=0) / H
    assert np.allclose(delivered[5:], np.array(observed)[6:], atol=1e-9)


def test_through_noise_the_identifier_identifies_only_where_it_is_read(monkeypatch):
    """With noisy sensors the identified parameters are read only by the check of E
    (every periods.learner), so the identifier identifies at the update before each
    check: every log is bit for bit the one of identifying at every update, but the
    logged misfit, which is held between checks."""
    scenario = _tiny("short", dataclasses.replace(spacecraft_sensing(), rhs_delay=0,
                                                  lhs_delay=0, actuator_lag=0.0))
    scenario.inertia.fit_tolerance = 0.0
    checked = simulate(scenario, "dac").logs
    monkeypatch.setattr(InertialIdentifier, "_ChecksNext", lambda self, t: True)
    every = simulate(scenario, "dac").logs
    assert not np.array_equal(every["inertial_parameters"][0],
                              every["inertial_parameters"][-1])
    for log in every:
        if log == "identification_log":
            assert np.array_equal(every[log][:, [0, 2]], checked[log][:, [0, 2]])
            assert not np.array_equal(every[log][:, 1], checked[log][:, 1])
        else:
            assert np.array_equal(every[log], checked[log], equal_nan=True), log
