"""The null-space potential field: analytic gradient and Hessian against finite
differences, and the projection that leaves alpha_dot alone."""
import numpy as np

from dacph_drake.dynamics.plant import MakeArmPlant
from dacph_drake.dynamics.base_repulsion import BaseRepulsionPotential
from dacph_drake.dynamics.reduced_model import ReducedOrderModel
from dacph_drake.scenario.planar_arm import RobotParams
from dacph_drake.scenario import Potential


def _active_configurations(potential, rng, count):
    out = []
    while len(out) < count:
        q = rng.uniform(-np.pi, np.pi, potential._n)
        if potential.MinClearance(q) > 0.005 and np.all(np.abs(q[1:]) < np.pi - 0.01) \
                and potential.Evaluate(q, np.zeros_like(q))[0] > 0:
            out.append(q)
    return out


def test_gradient_and_hessian_match_finite_differences(robot, rng):
    potential = BaseRepulsionPotential(robot, Potential())
    h = 1e-7
    for q in _active_configurations(potential, rng, 40):
        qdot = rng.uniform(-1, 1, q.size)
        U, grad, grad_dot = potential.Evaluate(q, qdot)
        for k in range(q.size):
            e = np.zeros(q.size)
            e[k] = h
            fd = (potential.Evaluate(q + e, qdot)[0] - potential.Evaluate(q - e, qdot)[0]) / (2 * h)
            assert abs(fd - grad[k]) <= 1e-5 * (1e-3 + abs(grad[k]))
        fd = (potential.Evaluate(q + h * qdot, qdot)[1]
              - potential.Evaluate(q - h * qdot, qdot)[1]) / (2 * h)
        np.testing.assert_allclose(grad_dot, fd, rtol=1e-5, atol=1e-6 * np.max(np.abs(fd)))


def test_null_space_projection_keeps_alpha_dot(robot, rng):
    potential = BaseRepulsionPotential(robot, Potential())
    model = ReducedOrderModel(MakeArmPlant(robot))
    for q in _active_configurations(potential, rng, 10):
        xi = -0.1 * potential.Evaluate(q, np.zeros_like(q))[1]
        D = model.Evaluate(q, np.zeros_like(q)).D
        projected = (np.eye(q.size) - np.outer(D / (D @ D), D)) @ xi
        assert abs(D @ projected) < 1e-14 * max(1.0, np.linalg.norm(xi))
        if robot.num_links > 1:
            assert np.linalg.norm(projected) > 0


def test_potential_is_zero_far_from_the_base():
    potential = BaseRepulsionPotential(RobotParams(), Potential())
    U, grad, _ = potential.Evaluate(np.array([0.0, 0.3]), np.zeros(2))
    assert U == 0 and np.all(grad == 0)
    assert potential.MinClearance(np.array([0.0, 0.3])) > Potential().base_margin
