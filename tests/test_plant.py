"""The ground truth: momentum and energy bookkeeping of the free-floating plant."""
from dacph_drake.app.free_flight import run_free_flight


def test_free_flight_conserves_momentum_and_energy(robot, rng):
    n = robot.num_links
    result = run_free_flight(robot, duration=20.0,
                             amplitudes=rng.uniform(0.004, 0.008, n),
                             frequencies=rng.uniform(3, 6, n),
                             q0=rng.uniform(-0.5, 0.5, n))
    assert result.min_clearance > 0.0       # no contact: the torques are the only work
    assert result.kinetic_energy > 1e-5     # the arm really moved
    assert result.max_momentum < 1e-9
    assert abs(result.kinetic_energy - result.work) < 1e-6 * result.kinetic_energy


def test_the_closed_loops_integrator_keeps_the_bookkeeping(robot, rng):
    """The closed loops integrate with Scenario().simulator (RK2 at 0.25 ms,
    chosen for speed, docs/results/performance.md): momentum stays at round-off like
    RK3's, and the energy balance closes to 5.8e-6 over 20 s (RK3: 2.3e-7), which
    this bounds at 2e-5."""
    from dacph_drake.scenario import Scenario
    n = robot.num_links
    scenario = Scenario()
    result = run_free_flight(robot, duration=20.0,
                             amplitudes=rng.uniform(0.004, 0.008, n),
                             frequencies=rng.uniform(3, 6, n),
                             q0=rng.uniform(-0.5, 0.5, n),
                             integration_scheme=scenario.simulator.integration_scheme,
                             step=scenario.simulator.max_step_size)
    assert scenario.simulator.integration_scheme == "runge_kutta2"
    assert result.kinetic_energy > 1e-5
    assert result.max_momentum < 1e-9
    assert abs(result.kinetic_energy - result.work) < 2e-5 * result.kinetic_energy
