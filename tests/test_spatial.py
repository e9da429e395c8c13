"""Free-floating robots from description files (a free quaternion base, nq != nv) and
the reduced model of any free-floating plant (floating_model.FloatingBaseModel):
the physics tests of the planar model, for the shipped 3-DOF and 6-DOF spatial
robots and, against the planar closed form, for the planar arms."""
import numpy as np
import pytest
from pydrake.math import RollPitchYaw
from pydrake.multibody.tree import JacobianWrtVariable
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import Sine

from dacph_drake.robots.description import (SPATIAL_ROBOTS, AddRobotFromDescription,
                                     MakeRobotPlant, ParsedDescription)
from dacph_drake.scenario.errors import ConfigError
from dacph_drake.dynamics.floating_model import FloatingBaseModel
from dacph_drake.dynamics.plant import MakeArmPlant
from dacph_drake.dynamics.reduced_model import ReducedOrderModel
from dacph_drake.scenario.simulator import MakeSimulator
from dacph_drake.scenario.simulator import FixedStepConfig


@pytest.fixture(scope="module", params=list(SPATIAL_ROBOTS))
def spatial(request):
    return request.param, FloatingBaseModel(MakeRobotPlant(request.param))


def _zero_momentum_state(model, rng, scale=1.0):
    """Random joints, a random base pose, joint rates and the base twist that
    makes the momentum zero."""
    n = model.num_joints
    q = rng.uniform(-np.pi, np.pi, n)
    quaternion = rng.standard_normal(4)
    base = np.concatenate([quaternion / np.linalg.norm(quaternion),
                           rng.uniform(-1, 1, 3)])
    qdot = scale * rng.uniform(-1, 1, n)
    return q, base, qdot, model.BaseVelocity(q, qdot, base)


def test_robots_from_files_have_a_free_quaternion_base(spatial):
    name, model = spatial
    plant, n = model.plant, int(name[10])
    assert model.num_joints == n == plant.num_actuators()
    assert (plant.num_positions(), plant.num_velocities()) == (7 + n, 6 + n)
    assert plant.gravity_field().gravity_vector().tolist() == [0.0, 0.0, 0.0]
    assert list(model.coordinates.base_q) == list(range(7))
    positions = model.coordinates.Positions(np.ones(n))   # the base at the origin
    assert positions[:7].tolist() == [1.0, 0, 0, 0, 0, 0, 0] and np.all(positions[7:] == 1)


def test_bad_descriptions_are_named(tmp_path):
    with pytest.raises(ConfigError, match="no such .urdf or .sdf file; allowed: a file, "
                                          "or one of satellite_3dof, satellite_6dof"):
        MakeRobotPlant("satellite_9dof")
    fixed = tmp_path / "fixed.urdf"
    fixed.write_text('<robot name="r"><link name="a"/></robot>')
    with pytest.raises(ConfigError, match="no revolute joint"):
        MakeRobotPlant(fixed)


def test_momentum_is_conserved_in_free_flight_with_random_torques(spatial, rng):
    """From rest, with sinusoidal joint torques for 4 s (RK5 at 0.25 ms; amplitude
    M_kk(q0) times 1-3 rad/s^2, joint rates reach a few rad/s): the spatial
    momentum about the world origin stays zero to 1e-9."""
    name, model = spatial
    builder = DiagramBuilder()
    plant, _ = AddRobotFromDescription(builder, name)
    n = plant.num_actuators()
    q0 = rng.uniform(-1, 1, n)
    amplitudes = np.diag(model.MassMatrix(q0)) * rng.uniform(1.0, 3.0, n)
    torque = builder.AddSystem(Sine(amplitudes, rng.uniform(0.3, 1.0, n),
                                    rng.uniform(0, np.pi, n), n))
    builder.Connect(torque.get_output_port(0), plant.get_actuation_input_port())
    simulator = MakeSimulator(builder.Build(), FixedStepConfig("runge_kutta5"))
    context = plant.GetMyContextFromRoot(simulator.get_mutable_context())
    plant.SetPositions(context, model.FullPositions(q0))
    worst = 0.0
    for t in np.linspace(0.2, 4.0, 20):
        simulator.AdvanceTo(t)
        h = plant.CalcSpatialMomentumInWorldAboutPoint(context, np.zeros(3))
        worst = max(worst, np.max(np.abs(h.get_coeffs())))
    speed = np.max(np.abs(plant.GetVelocities(context)[model.coordinates.joint_v]))
    assert 0.1 < speed < 20                           # the arm did move
    assert worst < 1e-9


def test_plant_accelerations_follow_the_reduced_dynamics(spatial, rng):
    """At any zero-momentum state, the plant's joint accelerations are
    M^-1 (tau - C' qdot), whatever the base's pose."""
    _, model = spatial
    plant = model.plant
    context = plant.CreateDefaultContext()
    joint_v = model.coordinates.joint_v
    for _ in range(5):
        q, base, qdot, v_base = _zero_momentum_state(model, rng)
        tau = rng.uniform(-1, 1, model.num_joints)
        plant.SetPositions(context, model.FullPositions(q, base))
        plant.SetVelocities(context, np.concatenate([v_base, qdot]))
        plant.get_actuation_input_port().FixValue(context, tau)
        accelerations = plant.EvalTimeDerivatives(context).get_generalized_velocity(
            ).CopyToVector()
        M = model.MassMatrix(q)
        qddot = np.linalg.solve(M, tau - model.Coriolis(q, qdot) @ qdot)
        np.testing.assert_allclose(accelerations[joint_v], qddot, rtol=1e-9,
                                   atol=1e-9 * np.max(np.abs(qddot)))
        h = plant.CalcSpatialMomentumInWorldAboutPoint(context, np.zeros(3))
        assert np.max(np.abs(h.get_coeffs())) < 1e-12


def test_mass_matrix_derivatives_and_skew_symmetry(spatial, rng):
    """dM/dq (AutoDiff through the Schur complement) against central differences;
    Mdot - 2 C' is skew-symmetric; M is symmetric positive definite."""
    _, model = spatial
    n = model.num_joints
    for _ in range(3):
        q, _, qdot, _ = _zero_momentum_state(model, rng)
        M, dM = model.MassMatrixAndDerivatives(q)
        np.testing.assert_allclose(M, model.MassMatrix(q), atol=1e-13)
        assert np.allclose(M, M.T, atol=1e-13) and np.linalg.eigvalsh(M).min() > 0
        h = 1e-6
        for k in range(n):
            step = np.zeros(n)
            step[k] = h
            fd = (model.MassMatrix(q + step) - model.MassMatrix(q - step)) / (2 * h)
            np.testing.assert_allclose(dM[k], fd, atol=1e-8 * max(1.0, np.abs(M).max()))
        Mdot = np.tensordot(qdot, dM, axes=(0, 0))
        N = Mdot - 2 * model.Coriolis(q, qdot)
        np.testing.assert_allclose(N, -N.T, atol=1e-12 * np.abs(Mdot).max() + 1e-15)


def test_the_reduced_model_is_blind_to_the_base_pose(spatial, rng):
    """M(q) is a property of the arm's shape: the base's pose changes H but not its
    Schur complement; the GJM maps qdot to the true end-effector twist."""
    _, model = spatial
    plant = model.plant
    context = plant.CreateDefaultContext()
    end_effector = plant.GetFrameByName("end_effector")
    q, base, qdot, v_base = _zero_momentum_state(model, rng)
    plant.SetPositions(context, model.FullPositions(q, base))
    H = plant.CalcMassMatrix(context)
    b, m = model.coordinates.base_v, model.coordinates.joint_v
    schur = H[np.ix_(m, m)] - H[np.ix_(m, b)] @ np.linalg.solve(H[np.ix_(b, b)],
                                                                H[np.ix_(b, m)])
    np.testing.assert_allclose(schur, model.MassMatrix(q), atol=1e-12)
    plant.SetVelocities(context, np.concatenate([v_base, qdot]))
    J = plant.CalcJacobianSpatialVelocity(context, JacobianWrtVariable.kV,
                                          end_effector, np.zeros(3),
                                          plant.world_frame(), plant.world_frame())
    np.testing.assert_allclose(
        model.GeneralizedJacobian(q, end_effector, base_positions=base) @ qdot,
        J @ plant.GetVelocities(context), atol=1e-12)


def test_a_closed_joint_loop_turns_the_base(rng):
    """Nonholonomy: the 3-DOF arm driven around a closed loop in joint space by
    computed torque (reduced model) comes back to its shape with the base turned;
    the plant's base attitude equals the integral of the GJM's base rows
    (omega_b = -[H_bb^-1 H_bm]_omega qdot) along the same path."""
    model = FloatingBaseModel(MakeRobotPlant("satellite_3dof"))
    n, period = model.num_joints, 4.0
    center, radius = np.array([0.3, 0.6, -1.2]), 0.5

    def path(t):
        phase = 2 * np.pi * t / period
        w = 2 * np.pi / period
        q = center + radius * np.array([np.cos(phase) - 1, np.sin(phase), np.sin(phase)])
        qdot = radius * w * np.array([-np.sin(phase), np.cos(phase), np.cos(phase)])
        qddot = -radius * w * w * np.array([np.cos(phase), np.sin(phase), np.sin(phase)])
        return q, qdot, qddot

    builder = DiagramBuilder()
    plant, _ = AddRobotFromDescription(builder, "satellite_3dof")
    from pydrake.systems.framework import LeafSystem

    class ComputedTorque(LeafSystem):
        def __init__(self):
            super().__init__()
            self._state = self.DeclareVectorInputPort("state", plant.num_multibody_states())
            self.DeclareVectorOutputPort("tau", n, self._CalcTau)

        def _CalcTau(self, context, output):
            x = self._state.Eval(context)
            q = x[model.coordinates.joint_q]
            qdot = x[plant.num_positions() + model.coordinates.joint_v]
            q_d, qdot_d, qddot_d = path(context.get_time())
            command = qddot_d + 400 * (q_d - q) + 40 * (qdot_d - qdot)
            output.SetFromVector(model.MassMatrix(q) @ command
                                 + model.Coriolis(q, qdot) @ qdot)

    tracker = builder.AddSystem(ComputedTorque())
    builder.Connect(plant.get_state_output_port(), tracker.get_input_port())
    builder.Connect(tracker.get_output_port(), plant.get_actuation_input_port())
    simulator = MakeSimulator(builder.Build(), FixedStepConfig("runge_kutta3", 1e-3))
    context = plant.GetMyContextFromRoot(simulator.get_mutable_context())
    q0, qdot0, _ = path(0.0)
    plant.SetPositions(context, model.FullPositions(q0))
    plant.SetVelocities(context, np.concatenate([model.BaseVelocity(q0, qdot0), qdot0]))
    simulator.AdvanceTo(period)
    np.testing.assert_allclose(plant.GetPositions(context)[model.coordinates.joint_q],
                               q0, atol=1e-6)                     # back to its shape
    R_plant = plant.GetFreeBodyPose(context, plant.GetBodyByName("base")).rotation()
    # The same attitude from omega_b along the path (RK4 on the rotation matrix).
    R, steps = np.eye(3), 4000
    dt = period / steps

    def omega(t, R):
        q, qdot, _ = path(t)
        base = np.concatenate([RotationToQuaternion(R), np.zeros(3)])
        return model.BaseVelocity(q, qdot, base)[:3]

    for i in range(steps):
        t = i * dt
        k1 = omega(t, R)
        R1 = Rodrigues(k1 * dt / 2) @ R
        k2 = omega(t + dt / 2, R1)
        R2 = Rodrigues(k2 * dt / 2) @ R
        k3 = omega(t + dt / 2, R2)
        R3 = Rodrigues(k3 * dt) @ R
        k4 = omega(t + dt, R3)
        R = Rodrigues((k1 + 2 * k2 + 2 * k3 + k4) * dt / 6) @ R
    turned = RollPitchYaw(R_plant).vector()
    assert np.max(np.abs(turned)) > 1e-3                   # the base did turn
    np.testing.assert_allclose(R_plant.matrix(), R, atol=1e-6)


def Rodrigues(rotation_vector):
    angle = np.linalg.norm(rotation_vector)
    if angle < 1e-15:
        return np.eye(3)
    k = rotation_vector / angle
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def RotationToQuaternion(R):
    from pydrake.math import RotationMatrix
    quaternion = RotationMatrix(R).ToQuaternion()
    return np.array([quaternion.w(), quaternion.x(), quaternion.y(), quaternion.z()])


@pytest.mark.parametrize("links", [2, 3])
def test_planar_closed_form_equals_the_generic_model(links, rng):
    """For the planar arms, the compiled closed form (ReducedOrderModel) and the
    generic model from the plant agree on M, C' and the base velocity."""
    from conftest import three_link_robot
    from dacph_drake.scenario.planar_arm import RobotParams
    robot = RobotParams() if links == 2 else three_link_robot()
    plant = MakeArmPlant(robot)
    closed_form, generic = ReducedOrderModel(plant), FloatingBaseModel(plant)
    for _ in range(5):
        q, qdot = rng.uniform(-np.pi, np.pi, links), rng.uniform(-1, 1, links)
        reduced = closed_form.Evaluate(q, qdot)
        np.testing.assert_allclose(generic.MassMatrix(q), reduced.M, atol=1e-12)
        np.testing.assert_allclose(generic.Coriolis(q, qdot), reduced.C, atol=1e-10)
        base = np.array([0.1, -0.2, 0.7])
        np.testing.assert_allclose(
            generic.BaseVelocity(q, qdot, base),
            closed_form.BaseVelocity(generic.FullPositions(q, base), qdot), atol=1e-12)


@pytest.mark.parametrize("links", [2, 3])
def test_inertia_bound_search_finds_the_grids_minimum(links):
    """The multi-start search reaches the 73^n grid's inf lambda_min(M) or below
    (the grid only samples), within 0.5 %."""
    from conftest import three_link_robot
    from dacph_drake.dynamics.inertia_bound import search_inertia_bound
    from dacph_drake.dynamics.reduced_model import grid_mass_matrix_bounds
    from dacph_drake.scenario.planar_arm import RobotParams
    plant = MakeArmPlant(RobotParams() if links == 2 else three_link_robot())
    grid, _ = grid_mass_matrix_bounds(ReducedOrderModel(plant))
    bound = search_inertia_bound(FloatingBaseModel(plant))
    assert grid * 0.995 < bound.smallest_found <= grid
    assert bound.lambda_min == pytest.approx(0.95 * bound.smallest_found)


def test_inertia_bound_of_a_spatial_arm_is_below_every_sample(spatial, rng):
    from dacph_drake.dynamics.inertia_bound import search_inertia_bound
    _, model = spatial
    bound = search_inertia_bound(model)
    samples = rng.uniform(-np.pi, np.pi, (500, model.num_joints))
    sampled = min(np.linalg.eigvalsh(model.MassMatrix(q))[0] for q in samples)
    assert bound.smallest_found <= sampled and bound.starts_at_minimum >= 2
    assert np.linalg.eigvalsh(model.MassMatrix(bound.argmin))[0] == pytest.approx(
        bound.smallest_found, rel=1e-12)


def test_attitude_error_is_the_rotation_vector_to_first_order(rng):
    from pydrake.common.eigen_geometry import AngleAxis
    from pydrake.math import RotationMatrix
    from dacph_drake.dynamics.attitude import attitude_error
    R_d = RotationMatrix(RollPitchYaw(rng.uniform(-np.pi, np.pi, 3)))
    assert np.all(attitude_error(R_d, R_d) == 0.0)
    for angle in (1e-3, 0.5, 3.0):
        axis = rng.standard_normal(3)
        axis /= np.linalg.norm(axis)
        R_e = RotationMatrix(AngleAxis(angle, axis)) @ R_d       # world-frame error
        e = attitude_error(R_e, R_d)
        assert np.linalg.norm(e) == pytest.approx(2 * np.sin(angle / 2), rel=1e-12)
        np.testing.assert_allclose(e / np.linalg.norm(e), axis, atol=1e-9)
    assert np.linalg.norm(attitude_error(RotationMatrix(AngleAxis(1e-3, axis)) @ R_d,
                                         R_d) - 1e-3 * axis) < 1e-9


def test_damped_pseudo_inverse_keeps_the_null_space(rng):
    from dacph_drake.dynamics.attitude import damped_pseudo_inverse, reference_rates
    D = rng.standard_normal((3, 6))
    xi = rng.standard_normal(6)
    exact = reference_rates(D, np.zeros(3), np.zeros(3), 1.0, xi, damping=0.0)
    assert np.linalg.norm(D @ exact) < 1e-12                # xi moves nothing the task sees
    task = rng.standard_normal(3)
    np.testing.assert_allclose(D @ damped_pseudo_inverse(D, 0.0) @ task, task, atol=1e-12)
    singular = np.vstack([D[:2], D[:1]])                    # rank 2
    nu = reference_rates(singular, task, np.zeros(3), 1.0, np.zeros(6), damping=0.05)
    assert np.all(np.isfinite(nu)) and np.linalg.norm(nu) < 100 * np.linalg.norm(task)


def test_the_attitude_law_tracks_a_3d_reference_on_the_six_dof_arm():
    """Kinematic closed loop on the free-floating 6-DOF arm: joint rates qdot = nu
    (xi = 0), the base turning as zero momentum demands (the task Jacobian is the
    GJM's angular rows, so it accounts for it): from a 0.3 rad error, e decays as
    exp(-Lambda t) while R_d(t) turns, down to 1e-3 of its start in 4 s."""
    from pydrake.common.eigen_geometry import AngleAxis
    from pydrake.math import RotationMatrix
    from dacph_drake.dynamics.attitude import attitude_error, reference_rates
    model = FloatingBaseModel(MakeRobotPlant("satellite_6dof"))
    plant = model.plant
    context = plant.CreateDefaultContext()
    end_effector = plant.GetFrameByName("end_effector")
    q = np.array([0.3, -0.8, 1.6, 0.2, 0.6, -0.3])
    R_base, Lambda, dt = np.eye(3), 2.0, 1e-3

    def pose(q, R_base):
        quaternion = RotationMatrix(R_base).ToQuaternion()
        base = np.array([quaternion.w(), quaternion.x(), quaternion.y(), quaternion.z(),
                         0.0, 0.0, 0.0])
        plant.SetPositions(context, model.FullPositions(q, base))
        return base, end_effector.CalcPoseInWorld(context).rotation()

    _, R_start = pose(q, R_base)
    R_0 = RotationMatrix(AngleAxis(0.3, [0.6, 0.0, 0.8])) @ R_start   # R_d(0)
    axis = np.array([0.0, 0.6, 0.8])

    def reference(t):               # R_d(t) = R_0 rotated about a body axis by phi(t)
        phi, phi_dot = 0.4 * np.sin(0.8 * t), 0.32 * np.cos(0.8 * t)
        return (R_0 @ RotationMatrix(AngleAxis(phi, axis)),
                R_0.matrix() @ axis * phi_dot)
    errors = []
    for step in range(4000):
        t = step * dt
        base, R_WE = pose(q, R_base)
        R_d, omega_d = reference(t)
        e = attitude_error(R_WE, R_d)
        errors.append(np.linalg.norm(e))
        D = model.GeneralizedJacobian(q, end_effector, base_positions=base)[:3]
        qdot = reference_rates(D, omega_d, e, Lambda, np.zeros(6), damping=1e-3)
        omega_base = model.BaseVelocity(q, qdot, base)[:3]
        q = q + dt * qdot
        R_base = Rodrigues(omega_base * dt) @ R_base
    errors = np.array(errors)
    assert errors[0] == pytest.approx(2 * np.sin(0.15), rel=1e-9)
    expected = errors[0] * np.exp(-Lambda * dt * np.arange(len(errors)))
    assert np.all(errors <= 1.05 * expected + 2e-4)          # first-order decay
    assert errors[-1] < 1e-3 * errors[0]


def test_clearance_potential_gradient_matches_the_motion(rng):
    """grad U (from the witness points' GJMs) against the central difference of U
    along a zero-momentum motion: joints q +- h v, the base moved and turned by
    +- h times the twist zero momentum gives it."""
    from pydrake.common.eigen_geometry import AngleAxis, Quaternion
    from pydrake.math import RotationMatrix
    from dacph_drake.robots.clearance_potential import BaseClearancePotential
    model = FloatingBaseModel(MakeRobotPlant("satellite_6dof"))
    potential = BaseClearancePotential(parsed=ParsedDescription("satellite_6dof"), model=model,
                                       gain=1.0, margin=0.1)
    q = np.array([0.3, -0.8, 2.1, 0.2, 0.6, -0.3])        # 4.4 cm from the base
    base = np.array([1.0, 0, 0, 0, 0.1, -0.2, 0.3])
    clearance = potential.Evaluate(q, base)
    assert 0 < clearance.min_distance < 0.1 and clearance.U > 0

    def moved(sign, v, h=1e-6):
        twist = model.BaseVelocity(q, v, base)
        turn = RotationMatrix(AngleAxis(h * np.linalg.norm(twist[:3]),
                                        twist[:3] / np.linalg.norm(twist[:3])))
        R = (turn if sign > 0 else turn.inverse()) @ RotationMatrix(Quaternion(base[:4]))
        quaternion = R.ToQuaternion()
        pose = np.concatenate([[quaternion.w(), quaternion.x(), quaternion.y(),
                                quaternion.z()], base[4:] + sign * h * twist[3:]])
        return potential.Evaluate(q + sign * h * v, pose).U

    for _ in range(3):
        v = rng.standard_normal(model.num_joints)
        along = (moved(+1, v) - moved(-1, v)) / 2e-6
        assert clearance.gradient @ v == pytest.approx(along, rel=1e-5, abs=1e-9)


def test_planar_arms_through_the_description_path(robot, rng):
    """RobotParams generates its URDF (description.planar_arm_urdf): the plant parsed
    from it is the one dynamics/plant.py builds (same layout, mass matrix, end-effector pose),
    and its generic reduced model equals the planar closed form."""
    from dacph_drake.dynamics.plant import END_EFFECTOR, ArmCoordinates
    parsed, built = MakeRobotPlant(robot), MakeArmPlant(robot)
    for a, b in zip(vars(ArmCoordinates.FromPlant(parsed)).values(),
                    vars(ArmCoordinates.FromPlant(built)).values()):
        assert np.array_equal(a, b)
    contexts = [parsed.CreateDefaultContext(), built.CreateDefaultContext()]
    for _ in range(5):
        x = rng.uniform(-np.pi, np.pi, built.num_positions())
        poses, masses = [], []
        for plant, context in zip((parsed, built), contexts):
            plant.SetPositions(context, x)
            masses.append(plant.CalcMassMatrix(context))
            poses.append(plant.GetFrameByName(END_EFFECTOR).CalcPoseInWorld(
                context).GetAsMatrix4())
        np.testing.assert_allclose(masses[0], masses[1], atol=1e-14)
        np.testing.assert_allclose(poses[0], poses[1], atol=1e-14)
    q = rng.uniform(-np.pi, np.pi, robot.num_links)
    np.testing.assert_allclose(FloatingBaseModel(parsed).MassMatrix(q),
                               ReducedOrderModel(built).Evaluate(q, 0 * q).M, atol=1e-12)


def test_the_homogeneous_region_of_attraction_is_the_full_programs(rng):
    """The spatial LHS's region of attraction from the homogeneous reduction (an SOS
    bound of the Coriolis cubic on the sphere) certifies the level the full
    sums-of-squares program in s certifies on satellite_3dof (within 0.1 %), and on
    the 6-DOF arm the bound is the cubic's maximum (within 0.1 % of projected
    gradient ascent from 2000 random starts, never below it); on the 6-DOF arm's
    certified boundary (rho times 0.999) the frozen dynamics' dV/dt is negative at
    20 000 random points."""
    from dacph_drake.analysis.region_of_attraction import (
        _Region, attitude_region_of_attraction)
    q3 = np.array([0.3, -0.8, 1.6])
    model = FloatingBaseModel(MakeRobotPlant("satellite_3dof"))
    reduced = attitude_region_of_attraction(model, q3, 20.0)
    M = model.MassMatrix(q3)
    full = _Region(q3, M, [model.Coriolis(q3, np.eye(3)[k]) for k in range(3)],
                   20.0 * M, 0.0, np.zeros(3))
    assert reduced.rho == pytest.approx(full.rho, rel=1e-3)
    q6 = np.array([0.3, -0.8, 1.6, 0.2, 0.6, -0.3])
    model = FloatingBaseModel(MakeRobotPlant("satellite_6dof"))
    region = attitude_region_of_attraction(model, q6, 20.0)
    M = model.MassMatrix(q6)
    Gamma = np.array([model.Coriolis(q6, np.eye(6)[k]) for k in range(6)])
    eigenvalues, eigenvectors = np.linalg.eigh(M)
    L = eigenvectors @ np.diag(eigenvalues**-0.5) @ eigenvectors.T

    def cubic(w):
        s = L @ w
        return s @ np.einsum("k,kij,j->i", s, Gamma, s)
    best = -np.inf
    for w in rng.normal(size=(2000, 6)):
        w /= np.linalg.norm(w)
        for _ in range(100):                    # projected gradient ascent
            step = 1e-4 * np.eye(6)
            gradient = np.array([cubic(w + e) - cubic(w - e) for e in step]) / 2e-4
            w = w + 0.02 * (gradient - (gradient @ w) * w)
            w /= np.linalg.norm(w)
        best = max(best, cubic(w))
    gamma = 20.0 / np.sqrt(2 * region.rho)
    assert best <= gamma <= best * 1.001
    s = (L @ rng.normal(size=(6, 20000))).T
    s *= np.sqrt(2 * 0.999 * region.rho / np.einsum("ni,ij,nj->n", s, M, s))[:, None]
    Vdot = [-x @ np.einsum("k,kij,j->i", x, Gamma, x) - 20.0 * x @ M @ x for x in s]
    assert max(Vdot) < 0


def test_the_moving_configuration_region_holds_far_beyond_the_frozen_one():
    """verify's spatial certificate (every s, by the skew symmetry of Mdot - 2 C'):
    on the 6-DOF arm, from an s(0) three times beyond the frozen certificate's
    level along its worst direction (where the frozen dynamics M sdot = -C'(q0, s) s
    - 20 M s grow V), the sliding dynamics with the configuration moving (qdot = s)
    keep dV/dt = -40 V (V within 1e-6 of V0 exp(-40 t) over 0.2 s, RK4 at 0.1 ms);
    the certificate fails when C' is not the Christoffel form of M's derivative
    (C' scaled by 1.01)."""
    from dacph_drake.analysis.region_of_attraction import moving_region_of_attraction
    model = FloatingBaseModel(MakeRobotPlant("satellite_6dof"))
    q0 = np.array([0.3, -0.8, 1.6, 0.2, 0.6, -0.3])
    assert moving_region_of_attraction(model, q0, 20.0).Contains(1e9)
    M0 = model.MassMatrix(q0)
    eigenvalues, eigenvectors = np.linalg.eigh(M0)
    L = eigenvectors @ np.diag(eigenvalues**-0.5) @ eigenvectors.T      # M^-1/2
    # s = L w r (V = r^2 / 2): the frozen dV/dt = -20 r^2 - c(w) r^3,
    # c(w) = s^T C'(q0, s) s at r = 1; the worst w of 4000.
    directions = np.random.default_rng(3).normal(size=(4000, 6))
    directions /= np.linalg.norm(directions, axis=1)[:, None]
    c = [(L @ w) @ model.Coriolis(q0, L @ w) @ (L @ w) for w in directions]
    worst = int(np.argmin(c))
    r = 3 * 20.0 / -c[worst]
    s0 = L @ directions[worst] * r
    assert -s0 @ model.Coriolis(q0, s0) @ s0 - 20.0 * s0 @ M0 @ s0 > 0

    def moving(x):
        q, s = x[:6], x[6:]
        M, C = model.MassAndCoriolis(q, s)
        return np.concatenate([s, np.linalg.solve(M, -C @ s - 20.0 * M @ s)])

    def rk4(f, x, h):
        k1 = f(x); k2 = f(x + h / 2 * k1); k3 = f(x + h / 2 * k2); k4 = f(x + h * k3)
        return x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    h, x, V0 = 1e-4, np.concatenate([q0, s0]), 0.5 * r**2
    for step in range(1, 2001):
        x = rk4(moving, x, h)
        if step % 200 == 0:
            V = 0.5 * x[6:] @ model.MassMatrix(x[:6]) @ x[6:]
            assert V == pytest.approx(V0 * np.exp(-40 * step * h), rel=1e-6)

    christoffel = model.Coriolis
    model.Coriolis = lambda q, qdot: 1.01 * christoffel(q, qdot)
    assert not moving_region_of_attraction(model, q0, 20.0).Contains(0.0)

@pytest.mark.parametrize("robot", [*SPATIAL_ROBOTS, "planar 3 links"])
def test_the_compiled_model_is_drakes(robot, rng):
    """FloatingBaseModel's compiled kernel (kernels/spatial.py) against Drake at
    random configurations and base poses: M the Schur complement of CalcMassMatrix
    (relative 1e-13), dM/dq and dA/dq (A = H_bb^-1 H_bm) from Drake's AutoDiff of
    H (1e-12), the end effector's
    generalized Jacobian J_m - J_b H_bb^-1 H_bm from CalcJacobianSpatialVelocity
    (1e-12) and the zero-momentum base velocity (1e-12)."""
    from pydrake.autodiffutils import ExtractGradient, ExtractValue, InitializeAutoDiff
    from conftest import three_link_robot
    plant = (MakeArmPlant(three_link_robot()) if robot.startswith("planar")
             else MakeRobotPlant(robot))
    model = FloatingBaseModel(plant)
    context, ad_plant = plant.CreateDefaultContext(), plant.ToAutoDiffXd()
    ad_context = ad_plant.CreateDefaultContext()
    n, b, m = model.num_joints, model.coordinates.base_v, model.coordinates.joint_v
    selector = np.zeros((plant.num_positions(), n))
    selector[model.coordinates.joint_q, np.arange(n)] = 1.0
    end_effector = plant.GetFrameByName("end_effector")
    for _ in range(5):
        q, qdot = rng.uniform(-np.pi, np.pi, n), rng.normal(size=n)
        base = model.coordinates.base_origin + rng.uniform(-1, 1,
                                                           len(model.coordinates.base_q))
        if len(base) == 7:
            base[:4] /= np.linalg.norm(base[:4])
        ad_plant.SetPositions(ad_context, InitializeAutoDiff(model.FullPositions(q),
                                                            selector))
        H_ad = ad_plant.CalcMassMatrix(ad_context)
        H = ExtractValue(H_ad)
        N = H.shape[0]
        dH = ExtractGradient(H_ad.reshape(-1)).reshape(N, N, n).transpose(2, 0, 1)
        A = np.linalg.solve(H[np.ix_(b, b)], H[np.ix_(b, m)])
        M = H[np.ix_(m, m)] - H[np.ix_(m, b)] @ A
        dM = np.array([d[np.ix_(m, m)] - d[np.ix_(m, b)] @ A - A.T @ d[np.ix_(b, m)]
                       + A.T @ d[np.ix_(b, b)] @ A for d in dH])
        dA = np.array([np.linalg.solve(H[np.ix_(b, b)], d[np.ix_(b, m)]
                                       - d[np.ix_(b, b)] @ A) for d in dH])
        M_k, dM_k, A_k, dA_k = model.Evaluate(q)[:4]
        scale = np.abs(M).max()
        np.testing.assert_allclose(M_k, M, rtol=0, atol=1e-13 * scale)
        np.testing.assert_allclose(dM_k, dM, rtol=0, atol=1e-12 * scale)
        np.testing.assert_allclose(A_k, A, rtol=0, atol=1e-12 * np.abs(A).max())
        np.testing.assert_allclose(dA_k, dA, rtol=0, atol=1e-12 * np.abs(A).max())
        plant.SetPositions(context, model.FullPositions(q, base))
        H = plant.CalcMassMatrix(context)
        J = plant.CalcJacobianSpatialVelocity(
            context, JacobianWrtVariable.kV, end_effector, np.zeros(3),
            plant.world_frame(), plant.world_frame())
        A = np.linalg.solve(H[np.ix_(b, b)], H[np.ix_(b, m)])
        np.testing.assert_allclose(model.GeneralizedJacobian(q, end_effector,
                                                             base_positions=base),
                                   J[:, m] - J[:, b] @ A, rtol=0, atol=1e-12)
        np.testing.assert_allclose(model.BaseVelocity(q, qdot, base), -A @ qdot,
                                   rtol=0, atol=1e-12 * np.abs(qdot).max())


@pytest.mark.parametrize("robot", SPATIAL_ROBOTS)
def test_the_attitude_task_rates_are_the_motion_s(robot, rng):
    """nu_dot and e_dot of the compiled attitude task (kernels.attitude.task_rates:
    from dA/dq, the joints' axes and the error quaternion) against central
    differences (h = 1e-5 s) of nu along the motion: joints at qdot, the base
    turning at a random omega_b, the reference at t, a secondary motion xi(q) with
    its rate (relative 1e-7)."""
    from dacph_drake.kernels.attitude import quaternion_rotation, task_rates, turned
    plant = MakeRobotPlant(robot)
    model = FloatingBaseModel(plant)
    n, tree = model.num_joints, model.kernel_tree
    node, X_CE = model.FrameNode(plant.GetFrameByName("end_effector"))
    end_effector = (node, np.ascontiguousarray(X_CE[:3, :3]))
    W = 0.1 * rng.normal(size=(n, n))
    for _ in range(5):
        q, qdot, omega_base = rng.uniform(-2, 2, n), rng.normal(size=n), rng.normal(size=3)
        quaternion, t = rng.normal(size=4), rng.uniform(0, 10)
        quaternion /= np.linalg.norm(quaternion)
        axis = rng.normal(size=3)
        reference = (quaternion_rotation(rng.normal(size=4)), axis / np.linalg.norm(axis),
                     0.3, 2 * np.pi / 4)

        def at(h):
            q_h = q + h * qdot
            nu, nu_dot, e, _ = task_rates(
                tree[0], tree[1], tree[2], tree[7], model.Evaluate(q_h), qdot,
                turned(quaternion, h * omega_base), omega_base, t + h, reference,
                end_effector, W @ q_h, W @ qdot, 2.0, 0.05)
            return nu, nu_dot, e
        nu, nu_dot, e = at(0.0)
        (nu_p, _, e_p), (nu_m, _, e_m) = at(1e-5), at(-1e-5)
        np.testing.assert_allclose(nu_dot, (nu_p - nu_m) / 2e-5, rtol=0,
                                   atol=1e-7 * np.abs(nu_dot).max())
        assert np.max(np.abs(e_p - e_m)) > 1e-7          # the error does move
