"""The built-in scenarios by name (scenarios/*.yaml) and a described arm's own sections."""
import numpy as np

from dacph_drake.scenario import (DescribedArm, Disturbance, EndEffectorAttitude,
                                  Learner, Periods, Phases, Rhs, Scenario, Sensing,
                                  Uncertainty)


def paper_scenario() -> Scenario:
    """The paper's 1500 s scenario, its LHS model exact (bayes.model_error 0)."""
    scenario = Scenario()
    scenario.learner.bayes.model_error = 0.0
    return scenario


def short_scenario() -> Scenario:
    """The paper's phases compressed to 2 + 8 + 8 + 8 s; scenarios/short.yaml."""
    return Scenario(phases=Phases(warmup=2.0, linear=8.0, nonlinear=8.0, disturbance=8.0))


def described_arm_periods() -> Periods:
    """A described arm's periods (K_d = damping_rate M asks periods.rhs <= 1.25 ms)."""
    return Periods(rhs=5e-4, lhs=1e-3, learner=0.1, learner_sample=1e-2, log=1e-2)


def described_arm_rhs() -> Rhs:
    """chi forgets over 0.25 s: the first request's peak would hold it for seconds."""
    return Rhs(chi_window=0.25)


def described_arm_learner() -> Learner:
    """The learner for joints whose inertias lie decades apart (docs: Settings)."""
    return Learner(momentum_scale=0.5, prior_weight=0.1, band_sections=[8, 8],
                   coupling="inertia", prior_scale="per_input", prior_fallback=True)


def six_dof_uncertainty(scale: float = 1.0) -> Uncertainty:
    """satellite_6dof's true RHS: the paper's form sized to each joint.

    Args:
        scale: linear_scale and nonlinear_scale.

    Returns:
        The section."""
    pair = np.array([[-0.1, 0.0], [0.05, 0.15]])
    coupling = np.zeros((6, 6))
    coupling[:2, :2] = [[0.0, -0.1], [0.4, 0.0]]
    return Uncertainty(
        B0=[1.0] * 6, D0=[0.2, 0.2, 0.1, 0.01, 0.01, 0.005],
        D_offset=[0.04, 0.05, 0.02, 0.002, 0.003, 0.001],
        D_linear=[0.05, 0.15, 0.1, 0.1, 0.1, 0.1],
        D_quadratic=[-0.01, 0.1, 0.1, 1.0, -1.0, 1.0],
        B_linear=np.kron(np.eye(3), pair).tolist(),
        B_quadratic=[0.02, -0.5, 0.5, 5.0, -5.0, 5.0],
        B_q1_squared=coupling.tolist(), linear_scale=scale, nonlinear_scale=scale)


def six_dof_disturbance(scale: float = 1.0) -> Disturbance:
    """satellite_6dof's d(t).

    Args:
        scale: Disturbance.scale.

    Returns:
        The section."""
    return Disturbance(
        scale=scale, lf_offset=[0.03, -0.02, 0.02, -0.002, 0.002, -0.001],
        lf_amplitude=[0.02, 0.02, 0.01, 0.002, 0.002, 0.001],
        lf_frequency=[0.05, 0.07, 0.06, 0.08, 0.09, 0.1],
        hf_direction=[1.0, -1.0, 0.5, -0.1, 0.1, -0.05])


SATELLITE_PHASES = dict(warmup=2.0, linear=4.0, nonlinear=4.0, disturbance=4.0)


def spacecraft_sensing(actuator_lag: float = 0.001, latency: int = 0) -> Sensing:
    """The sensors and delays of a small spacecraft arm (docs/results/sensing.md gives
    each value's source): 17-bit joint encoders, tachometers of 1e-4 rad/s noise, a gyro
    of 0.01 deg/s noise with a 1 deg/h bias walking 1e-5 rad/s/sqrt(s), a star tracker of
    10 arcsec at 10 Hz, one sample of computation delay on the LHS and on the RHS.

    Args:
        actuator_lag: The actuators' time constant [s].
        latency: The sensors' latency [samples of periods.rhs]."""
    degree = np.pi / 180
    return Sensing(enabled=True, encoder_counts=2**17, rate_source="tachometer",
                   rate_noise=1e-4, gyro_noise=0.01 * degree, gyro_bias=degree / 3600,
                   gyro_bias_walk=1e-5, star_tracker_noise=10 * degree / 3600,
                   star_tracker_rate=10.0, latency=latency, lhs_delay=1,
                   rhs_delay=1, actuator_lag=actuator_lag)


def satellite_6dof_scenario() -> Scenario:
    """The 6-DOF satellite arm (scenarios/satellite_6dof.yaml)."""
    return Scenario(
        robot=DescribedArm("satellite_6dof"), task=EndEffectorAttitude(),
        q0=[0.3, -0.8, 1.6, 0.2, 0.6, -0.3], phases=Phases(**SATELLITE_PHASES),
        rhs=described_arm_rhs(), periods=described_arm_periods(),
        uncertainty=six_dof_uncertainty(), disturbance=six_dof_disturbance(),
        learner=described_arm_learner())


def satellite_3dof_scenario() -> Scenario:
    """The 3-DOF variant (scenarios/satellite_3dof.yaml)."""
    return Scenario(
        robot=DescribedArm("satellite_3dof"), task=EndEffectorAttitude(),
        q0=[0.3, -0.8, 1.6], phases=Phases(**SATELLITE_PHASES),
        rhs=described_arm_rhs(), periods=described_arm_periods(),
        uncertainty=Uncertainty(
            B0=[1.0] * 3, D0=[0.2, 0.2, 0.01], D_offset=[0.04, 0.05, 0.002],
            D_linear=[0.15, 0.05, 0.1], D_quadratic=[0.1, -0.01, 1.0],
            B_linear=[[-0.1, 0.0, 0.0], [0.05, 0.15, 0.0], [0.0, 0.0, 0.1]],
            B_quadratic=[0.5, 0.02, 5.0],
            B_q1_squared=[[0.0, -0.1, 0.0], [0.4, 0.0, 0.0], [0.0, 0.0, 0.0]]),
        disturbance=Disturbance(lf_offset=[0.03, -0.02, 0.002],
                                lf_amplitude=[0.02, 0.02, 0.002],
                                lf_frequency=[0.05, 0.07, 0.09],
                                hf_direction=[1.0, -1.0, 0.1]),
        learner=described_arm_learner())


def with_spacecraft_sensing(scenario: Scenario) -> Scenario:
    """``scenario`` measured through spacecraft_sensing() (the base of sensing sweeps).

    Args:
        scenario: The scenario (changed and returned)."""
    scenario.sensing = spacecraft_sensing()
    return scenario


BUILT_IN_SCENARIOS = {"paper": paper_scenario, "short": short_scenario,
                      "satellite_6dof": satellite_6dof_scenario,
                      "satellite_3dof": satellite_3dof_scenario}
