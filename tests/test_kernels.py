"""The compiled kernels of the fast path against the Python/Drake computations they
replace, to round-off, on the paper's arm and a 3-link arm."""
import numpy as np
import pytest

from dacph_drake.kernels.arm import joint_momentum, reduced_dynamics
from dacph_drake.kernels.loop import (integrator_sample, pack_true_rhs, stack_packs,
                                      true_matrices_of_trials, true_torque)
from dacph_drake.kernels.potential import potential
from dacph_drake.dynamics.plant import ArmCoordinates, MakeArmPlant
from dacph_drake.dynamics.base_repulsion import BaseRepulsionPotential
from dacph_drake.dynamics.reduced_model import ReducedOrderModel
from dacph_drake.scenario.planar_arm import LinkParams, RobotParams
from dacph_drake.scenario import Potential, Scenario
from dacph_drake.systems.disturbance import DisturbanceSource
from dacph_drake.dynamics.uncertainty import TrueRhsModel

ROBOTS = {"2-link": RobotParams(),
          "3-link": RobotParams(links=[LinkParams(), LinkParams(mass=0.7),
                                       LinkParams(mass=0.4, length=0.25, com=0.12, inertia=0.004)])}


@pytest.fixture(scope="module", params=list(ROBOTS))
def robot(request):
    robot = ROBOTS[request.param]
    return robot, ReducedOrderModel(MakeArmPlant(robot))


def _samples(n, count=50, seed=1):
    rng = np.random.default_rng(seed)
    return [(rng.uniform(-np.pi, np.pi, n), rng.normal(size=n)) for _ in range(count)]


def test_reduced_dynamics_kernel_matches_the_model(robot):
    _, model = robot
    for q, qdot in _samples(model.num_joints):
        r = model.Evaluate(q, qdot)
        M, C, D, dD = reduced_dynamics(q, qdot, *model.trigonometric_representation)
        scale = np.max(np.abs(r.M))
        for kernel, reference in ((M, r.M), (C, r.C), (D, r.D), (dD, r.dD)):
            np.testing.assert_allclose(kernel, reference, rtol=0, atol=1e-13 * scale)


def test_joint_momentum_kernel_is_the_plants(robot):
    """p = the joint rows of H(q_full) v from Drake's CalcMassMatrix, at any base
    pose and any velocity (not only at zero momentum)."""
    _, model = robot
    plant = model.plant
    context = plant.CreateDefaultContext()
    rng = np.random.default_rng(2)
    for _ in range(20):
        x = np.concatenate([rng.normal(size=2), rng.uniform(-np.pi, np.pi, 1 + model.num_joints),
                            rng.normal(size=3 + model.num_joints)])
        nq = plant.num_positions()
        plant.SetPositions(context, x[:nq])
        expected = (plant.CalcMassMatrix(context) @ x[nq:])[3:]
        base_pose, q, base_velocity, qdot = ArmCoordinates.FromPlant(plant).Split(x)
        np.testing.assert_allclose(
            joint_momentum(base_pose[2], base_velocity, q, qdot,
                           *model.trigonometric_representation),
            expected, rtol=0, atol=1e-13)


def test_potential_kernel_matches_the_model(robot):
    params, _ = robot
    field = BaseRepulsionPotential(params, Potential())
    n = params.num_links
    checked_active = 0
    for q, qdot in _samples(n, 400):
        U, grad, grad_dot = field.Evaluate(q, qdot)
        U2, grad2, grad_dot2 = potential(q, qdot, *field.kernel_arguments)
        scale = max(1.0, abs(U), np.max(np.abs(grad)), np.max(np.abs(grad_dot)))
        assert abs(U2 - U) <= 1e-13 * scale
        np.testing.assert_allclose(grad2, grad, rtol=0, atol=1e-13 * scale)
        np.testing.assert_allclose(grad_dot2, grad_dot, rtol=0, atol=1e-13 * scale)
        checked_active += U > 0
        P, _, _, _ = field._Points(q, qdot)
        assert abs(field.MinClearance(q) - np.min(field._Clearance(P)[0])) <= 1e-14
    assert checked_active > 20         # the field was active on many samples


def test_true_torque_kernel_matches_the_reference_by_phase():
    scenario = Scenario()
    model = ReducedOrderModel(MakeArmPlant(scenario.robot.truth))
    reference = TrueRhsModel(scenario.uncertainty, scenario.phases)
    source = DisturbanceSource(settings=[scenario.disturbance],
                               starts=[scenario.disturbance_start])
    model_vector = source.GetOutputPort("disturbance_model").Eval(source.CreateDefaultContext())
    packed = pack_true_rhs(*model.trigonometric_representation, reference.kernel_arguments)
    rng = np.random.default_rng(4)
    for t in (1.0, 100.0, 600.0, 1200.0, 1234.5):
        q, qdot = rng.uniform(-2, 2, 2), rng.normal(size=2)
        q_full = np.concatenate([[0.1, -0.2, 0.3], q])
        x = np.concatenate([q_full, model.BaseVelocity(q_full, qdot), qdot])
        u = rng.normal(size=2)
        B, D = reference.Matrices(t, q, model.Momentum(q, qdot))
        expected = B @ u - D * qdot + source.Evaluate(t)
        indices = ArmCoordinates.FromPlant(model.plant).StateIndices()
        np.testing.assert_allclose(true_torque(t, x, indices, u, model_vector, packed),
                                   expected, rtol=0, atol=1e-14)
        # The metrics' [vec(B~), diag(D~)] of a batch: this state as trial 1 of 2.
        packs, offsets = stack_packs([packed, packed])
        both = true_matrices_of_trials(t, np.concatenate([0 * x, x]),
                                       np.array([indices, indices + len(x)]), packs,
                                       offsets, 2)
        np.testing.assert_allclose(both[6:], np.concatenate([B.reshape(-1), D]),
                                   rtol=0, atol=1e-14)


def test_integrator_kernel_is_the_integrator_equation():
    rng = np.random.default_rng(5)
    n, h = 3, 2.5e-4
    B_inverse, D_hat, K = rng.normal(size=(n, n)), rng.uniform(0, 1, n), rng.uniform(500, 900, n)
    gains = np.concatenate([B_inverse.reshape(-1), D_hat, K, [800.0, 700.0, 1.0, 1.0]])
    request, previous, observed, qdot = (rng.normal(size=n) for _ in range(4))
    u_I = rng.normal(size=n)
    fast = np.concatenate([u_I, np.zeros(n + 1), [0.02], previous])
    out = integrator_sample(fast, gains, request, observed, qdot, np.array([h, 0.99, 1e-3]))
    e = previous - observed
    u_I = u_I + h * K * e
    chi = max(np.linalg.norm(e), 0.99 * 0.02, 1e-3)
    np.testing.assert_allclose(out[:3 * n + 2], np.concatenate(
        [u_I, e, [np.linalg.norm(e), chi], request]), rtol=0, atol=1e-15)
    np.testing.assert_allclose(out[3 * n + 2:], B_inverse @ (request + D_hat * qdot) + u_I,
                               rtol=0, atol=1e-14)
