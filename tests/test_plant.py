"""The ground truth: momentum and energy bookkeeping of the free-floating plant."""
import numpy as np

from dacph_drake.free_flight import run_free_flight


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
