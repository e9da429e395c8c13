"""The reduced-order port-Hamiltonian model is the plant (SPEC section 2)."""
import numpy as np
import pytest
from pydrake.systems.framework import DiagramBuilder, LeafSystem

from dacph_drake.dynamics.plant import (AddFreeFloatingArm, END_EFFECTOR, MakeArmPlant,
                               link_name)
from dacph_drake.dynamics.reduced_model import ReducedOrderModel, mass_matrix_bounds
from dacph_drake.scenario.planar_arm import RobotParams
from dacph_drake.scenario.simulator import MakeSimulator
from dacph_drake.scenario.simulator import FixedStepConfig


@pytest.fixture
def model(robot):
    return ReducedOrderModel(MakeArmPlant(robot))


def _zero_momentum_state(model, rng, theta0=None):
    n = model.num_joints
    q_full = np.concatenate([rng.uniform(-1, 1, 2),
                             [rng.uniform(-np.pi, np.pi) if theta0 is None else theta0],
                             rng.uniform(-np.pi, np.pi, n)])
    qdot = rng.uniform(-1, 1, n)
    return q_full, qdot, model.BaseVelocity(q_full, qdot)


def test_joint_accelerations_and_rates_match_the_plant(model, rng):
    plant = model.plant
    context = plant.CreateDefaultContext()
    for _ in range(20):
        q_full, qdot, v_base = _zero_momentum_state(model, rng)
        tau = rng.uniform(-0.1, 0.1, model.num_joints)
        plant.SetPositions(context, q_full)
        plant.SetVelocities(context, np.concatenate([v_base, qdot]))
        plant.get_actuation_input_port().FixValue(context, tau)
        accelerations = plant.EvalTimeDerivatives(context).get_generalized_velocity()
        reduced = model.Evaluate(q_full[3:], qdot)
        qddot = np.linalg.solve(reduced.M, tau - reduced.C @ qdot)
        np.testing.assert_allclose(accelerations.CopyToVector()[3:], qddot,
                                   rtol=0, atol=1e-9)
        # Task Jacobian: the end effector's angular rate is D(q) qdot.
        ee = plant.GetFrameByName(END_EFFECTOR)
        omega = ee.CalcSpatialVelocityInWorld(context).rotational()[2]
        assert omega == pytest.approx(reduced.D @ qdot, abs=1e-12)
        np.testing.assert_allclose(model.EndEffectorJacobian(q_full)[2], reduced.D,
                                   atol=1e-12)
        # Every link's GJM maps qdot to that link's true velocity (centre of mass).
        for k, J_bar in enumerate(model.LinkJacobians(q_full)):
            body = plant.GetBodyByName(link_name(k))
            V = body.EvalSpatialVelocityInWorld(context).Shift(
                body.EvalPoseInWorld(context).rotation() @ body.default_com())
            np.testing.assert_allclose(J_bar @ qdot, V.get_coeffs(), atol=1e-12)
        # alpha from the full state equals the end-effector frame's angle.
        R = ee.CalcPoseInWorld(context).rotation().matrix()
        alpha = model.EndEffectorAngle(q_full)
        assert np.angle(np.exp(1j * (alpha - np.arctan2(R[1, 0], R[0, 0])))) == \
            pytest.approx(0.0, abs=1e-12)


def test_reduced_quantities_do_not_depend_on_base_pose(model, rng):
    q_full, qdot, _ = _zero_momentum_state(model, rng, theta0=0.0)
    reduced = model.Evaluate(q_full[3:], qdot)
    for theta0 in (0.7, -2.0):
        q_full[2] = theta0
        np.testing.assert_allclose(model.EndEffectorJacobian(q_full)[2], reduced.D,
                                   atol=1e-12)
        omega0 = model.BaseVelocity(q_full, qdot)[2]
        assert omega0 == pytest.approx(reduced.base_velocity_map[2] @ qdot, abs=1e-12)


def test_structure_skew_symmetry_and_definiteness(model, rng):
    for _ in range(20):
        q = rng.uniform(-np.pi, np.pi, model.num_joints)
        qdot = rng.uniform(-2, 2, model.num_joints)
        r = model.Evaluate(q, qdot)
        S = r.Mdot - 2 * r.C
        np.testing.assert_allclose(S, -S.T, atol=1e-14)
        np.testing.assert_allclose(r.M, r.M.T, atol=1e-15)
        assert np.linalg.eigvalsh(r.M)[0] > 0
        # dH/dq = -(Mdot - C') M^-1 p with p = M qdot (the paper's identity).
        np.testing.assert_allclose(r.dH_dq, -(r.Mdot - r.C) @ qdot, atol=1e-14)


def test_analytic_derivatives_match_finite_differences(model, rng):
    h = 1e-6
    for _ in range(10):
        q = rng.uniform(-np.pi, np.pi, model.num_joints)
        qdot = rng.uniform(-2, 2, model.num_joints)
        r = model.Evaluate(q, qdot)
        p = r.M @ qdot
        for k in range(model.num_joints):
            e = np.zeros(model.num_joints)
            e[k] = h
            plus, minus = model.Evaluate(q + e, qdot), model.Evaluate(q - e, qdot)
            np.testing.assert_allclose(r.dM[k], (plus.M - minus.M) / (2 * h), atol=1e-9)
            np.testing.assert_allclose(r.dD[k], (plus.D - minus.D) / (2 * h), atol=1e-8)
            dH_fd = (model.Hamiltonian(q + e, p) - model.Hamiltonian(q - e, p)) / (2 * h)
            assert r.dH_dq[k] == pytest.approx(dH_fd, abs=1e-8)
        np.testing.assert_allclose(r.Mdot, sum(r.dM[k] * qdot[k]
                                               for k in range(model.num_joints)))


def test_mass_matrix_bounds_reported():
    lo, hi = mass_matrix_bounds(ReducedOrderModel(MakeArmPlant(RobotParams())))
    print(f"paper robot: inf lambda_min(M) = {lo:.6f}, sup lambda_max(M) = {hi:.6f} kg m^2")
    assert 0.0050 < lo < 0.0052          # SPEC section 5: about 0.0051 kg m^2
    assert hi > lo


@pytest.mark.parametrize("links", [3, 4, 6])
def test_searched_bounds_of_larger_arms_enclose_the_grid_and_every_sample(links, rng):
    """Arms of more than GRID_JOINTS links get searched bounds (the 73^n grid does
    not fit in memory at n = 6): below the smallest and above the largest eigenvalue
    of M at every sampled configuration, and within the search's 5 % margin of the
    grid's where the grid is affordable (n = 3, 4 at 25 points per joint: the
    search's optimum at least as extreme as the grid's, within 5 %). The
    search's derivative dM/dq is the closed form's, checked against central
    differences."""
    from dacph_drake.scenario.planar_arm import LinkParams
    from dacph_drake.dynamics.reduced_model import GRID_JOINTS, grid_mass_matrix_bounds
    assert links > GRID_JOINTS
    model = ReducedOrderModel(MakeArmPlant(RobotParams(links=[
        LinkParams(mass=1.0 + 0.3 * k, length=0.5 - 0.05 * k, inertia=0.02,
                   com=0.2 - 0.01 * k) for k in range(links)])))
    lo, hi = mass_matrix_bounds(model)
    samples = [np.linalg.eigvalsh(model.MassMatrix(q))
               for q in rng.uniform(-np.pi, np.pi, (2000, links))]
    assert lo < min(e[0] for e in samples) and hi > max(e[-1] for e in samples)
    if links <= 4:
        grid_lo, grid_hi = grid_mass_matrix_bounds(model, 25)
        assert 0.90 * grid_lo <= lo <= 0.95 * grid_lo
        assert 1.05 * grid_hi <= hi <= 1.10 * grid_hi
    q, h = rng.uniform(-np.pi, np.pi, links), 1e-6
    M, dM = model.MassMatrixAndDerivatives(q)
    np.testing.assert_allclose(M, model.MassMatrix(q), atol=1e-14)
    for k in range(links):
        e = h * np.eye(links)[k]
        np.testing.assert_allclose(dM[k], (model.MassMatrix(q + e)
                                           - model.MassMatrix(q - e)) / (2 * h), atol=1e-8)


class JointPathTracker(LeafSystem):
    """Computed torque along the closed joint loop q_d(t) = q0 + r (cos wt - 1, sin wt, ...):
    tau = M (qdd_d + Kp e + Kd edot) + C' qdot, from the reduced model."""

    def __init__(self, model, plant, q0, radius, period):
        super().__init__()
        self._model, self._q0 = model, q0
        self._r, self._w = radius, 2 * np.pi / period
        self._nq = plant.num_positions()
        self._state = self.DeclareVectorInputPort("state", plant.num_multibody_states())
        self.DeclareVectorOutputPort("tau", model.num_joints, self._CalcTorque)

    def Desired(self, t):
        n, r, w = self._model.num_joints, self._r, self._w
        phase = w * t + np.arange(n)                 # distinct phases: a loop, not a line
        q = self._q0 + r * (np.cos(phase) - np.cos(np.arange(n)))
        return q, -r * w * np.sin(phase), -r * w**2 * np.cos(phase)

    def _CalcTorque(self, context, output):
        x = self._state.Eval(context)
        q, qdot = x[3:self._nq], x[self._nq + 3:]
        q_d, qd_d, qdd_d = self.Desired(context.get_time())
        r = self._model.Evaluate(q, qdot)
        a = qdd_d + 400 * (q_d - q) + 40 * (qd_d - qdot)
        output.SetFromVector(r.M @ a + r.C @ qdot)


def test_nonholonomy_closed_joint_loop_rotates_the_base(robot):
    builder = DiagramBuilder()
    plant, _ = AddFreeFloatingArm(builder, robot)
    model = ReducedOrderModel(MakeArmPlant(robot))
    n = robot.num_links
    q0 = np.linspace(0.4, -0.4, n)
    period = 4.0
    tracker = builder.AddSystem(JointPathTracker(model, plant, q0, 0.4, period))
    builder.Connect(plant.get_state_output_port(), tracker.get_input_port())
    builder.Connect(tracker.get_output_port(), plant.get_actuation_input_port())
    simulator = MakeSimulator(builder.Build(), FixedStepConfig("runge_kutta3"))
    plant_context = plant.GetMyContextFromRoot(simulator.get_mutable_context())
    plant.SetPositions(plant_context, np.concatenate([[0, 0, 0], q0]))
    simulator.AdvanceTo(period)
    q_final = plant.GetPositions(plant_context)
    np.testing.assert_allclose(q_final[3:], q0, atol=1e-7)       # the loop closed
    # Integral of the GJM's base row along the path (trapezoid rule: spectrally
    # accurate for a periodic integrand).
    times = np.linspace(0, period, 2001)[:-1]
    rates = []
    for t in times:
        q_d, qd_d, _ = tracker.Desired(t)
        rates.append(model.Evaluate(q_d, qd_d).base_velocity_map[2] @ qd_d)
    predicted = np.mean(rates) * period
    assert abs(predicted) > 1e-3                                   # net rotation
    assert q_final[2] == pytest.approx(predicted, abs=1e-6)
