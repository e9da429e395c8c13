"""The AttitudeController's task, compiled (systems/attitude_controller.py states
the law): the reference R_d(t) (scenario.AttitudeReference.At), the attitude error
and the reference joint rates (tasks/attitude.py) at a configuration the compiled
reduced model (kernels/spatial.py) was evaluated at, and the base's attitude turned
along the motion for nu_dot's central difference. tests/test_kernels.py checks
each against the Python and Drake computation it replaces."""
import numpy as np
from numba import njit

from dacph_drake.kernels.arm import inverse3, matmul, matvec
from dacph_drake.kernels.spatial import (_rotation, christoffel, point_jacobian,
                                         reduced_model)


@njit(cache=True)
def quaternion_rotation(quaternion):
    """R of a (w, x, y, z) quaternion (normalized here)."""
    w, x, y, z = quaternion / np.sqrt(np.sum(quaternion * quaternion))
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


@njit(cache=True)
def rotation_quaternion(R):
    """The (w, x, y, z) quaternion of R with w >= 0 (Shepperd's method)."""
    trace = R[0, 0] + R[1, 1] + R[2, 2]
    out = np.empty(4)
    if trace >= max(R[0, 0], R[1, 1], R[2, 2]):
        r = np.sqrt(1.0 + trace)
        out[0], out[1] = 0.5 * r, 0.5 * (R[2, 1] - R[1, 2]) / r
        out[2], out[3] = 0.5 * (R[0, 2] - R[2, 0]) / r, 0.5 * (R[1, 0] - R[0, 1]) / r
    elif R[0, 0] >= R[1, 1] and R[0, 0] >= R[2, 2]:
        r = np.sqrt(1.0 + R[0, 0] - R[1, 1] - R[2, 2])
        out[0], out[1] = 0.5 * (R[2, 1] - R[1, 2]) / r, 0.5 * r
        out[2], out[3] = 0.5 * (R[0, 1] + R[1, 0]) / r, 0.5 * (R[0, 2] + R[2, 0]) / r
    elif R[1, 1] >= R[2, 2]:
        r = np.sqrt(1.0 - R[0, 0] + R[1, 1] - R[2, 2])
        out[0], out[1] = 0.5 * (R[0, 2] - R[2, 0]) / r, 0.5 * (R[0, 1] + R[1, 0]) / r
        out[2], out[3] = 0.5 * r, 0.5 * (R[1, 2] + R[2, 1]) / r
    else:
        r = np.sqrt(1.0 - R[0, 0] - R[1, 1] + R[2, 2])
        out[0], out[1] = 0.5 * (R[1, 0] - R[0, 1]) / r, 0.5 * (R[0, 2] + R[2, 0]) / r
        out[2], out[3] = 0.5 * (R[1, 2] + R[2, 1]) / r, 0.5 * r
    if out[0] < 0:
        out = -out
    return out


@njit(cache=True)
def turned(quaternion, rotation_vector):
    """The quaternion of the attitude ``quaternion`` turned by ``rotation_vector``
    (world frame), sign as rotation_quaternion gives it."""
    angle = np.sqrt(np.sum(rotation_vector * rotation_vector))
    R = quaternion_rotation(quaternion)
    if angle > 0:
        R = matmul(_rotation(rotation_vector / angle, angle), R)
    return rotation_quaternion(R)


@njit(cache=True)
def attitude_error(R_WE, R_WD):
    """e = 2 sgn(eta) epsilon of the error rotation R_WE R_WD^T
    (tasks.attitude.attitude_error)."""
    error = rotation_quaternion(matmul(R_WE, R_WD.T))       # w >= 0
    return 2.0 * error[1:]


@njit(cache=True)
def reference_rates(D, omega_d, e, Lambda, xi, damping):
    """nu = D^+ (omega_d - Lambda e) + (I - D^+ D) xi, D^+ = D^T (D D^T + mu^2 I)^-1
    (tasks.attitude.reference_rates)."""
    DDt = matmul(D, D.T)
    for i in range(3):
        DDt[i, i] += damping * damping
    D_plus = matmul(D.T, inverse3(DDt))
    return matvec(D_plus, omega_d - Lambda * e) + xi - matvec(D_plus, matvec(D, xi))


@njit(cache=True)
def desired_attitude(R_d0, axis, amplitude, omega, t):
    """(R_d(t), omega_d(t)) of scenario.AttitudeReference.At (``axis`` unit,
    ``omega`` = 2 pi / period)."""
    phi, phi_dot = amplitude * np.sin(omega * t), amplitude * omega * np.cos(omega * t)
    return matmul(R_d0, _rotation(axis, phi)), matvec(R_d0, axis) * phi_dot


@njit(cache=True)
def task_rates(base_subspace, parent, joint, evaluation, quaternion, t, reference,
               end_effector, xi, Lambda, damping):
    """(nu, e, R_d) at a configuration whose compiled model ``evaluation``
    (FloatingBaseModel.Evaluate: M, dM, A, X, S) is given, the base's attitude
    ``quaternion`` and time t. ``reference``: (R_d0, unit axis, amplitude, 2 pi /
    period); ``end_effector``: (node, R_CE, its frame's rotation in the node's
    body)."""
    A, X, S = evaluation[2], evaluation[3], evaluation[4]
    node, R_CE = end_effector
    R_WB = quaternion_rotation(quaternion)
    R_WE = matmul(R_WB, matmul(X[node, :3, :3], R_CE))
    R_d, omega_d = desired_attitude(reference[0], reference[1], reference[2],
                                    reference[3], t)
    e = attitude_error(R_WE, R_d)
    D = matmul(R_WB, point_jacobian(base_subspace, parent, joint, X, S, A, node,
                                    X[node, :3, 3])[:3])
    return reference_rates(D, omega_d, e, Lambda, xi, damping), e, R_d


@njit(cache=True)
def attitude_update(tree, evaluation, q, qdot, quaternion, omega_base, t, h,
                    reference, end_effector, xi, xi_plus, xi_minus, gains, chi,
                    excitation):
    """One AttitudeController update (its docstring states the law) from the
    compiled model's ``evaluation`` at q (FloatingBaseModel.Evaluate with
    derivatives; ``tree``: FloatingBaseModel.kernel_tree): nu and e there, nu_dot
    by the central difference along the motion (q +- h qdot, the base turned by
    +- h omega_base, t +- h; xi_plus, xi_minus the secondary motion there),
    ``gains`` = (Lambda, task_damping, damping_rate, epsilon, boundary_rate),
    ``excitation`` = (amplitude, 2 pi f_1, ..., 2 pi f_n). Returns (tau, M, C',
    [e, |e|, ||s||, V], the quaternion of R_d)."""
    (base_subspace, parent, joint, X_PF, axis, X_MC, below, joint_below, mass,
     moment, inertia) = tree
    Lambda, damping, damping_rate, epsilon, boundary_rate = (
        gains[0], gains[1], gains[2], gains[3], gains[4])
    nu, e, R_d = task_rates(base_subspace, parent, joint, evaluation, quaternion, t,
                            reference, end_effector, xi, Lambda, damping)
    rates = np.empty((2, q.shape[0]))
    for side in range(2):
        sign = 1.0 - 2.0 * side
        q_h = q + sign * h * qdot
        quaternion_h = turned(quaternion, sign * h * omega_base)
        evaluation_h = reduced_model(base_subspace, parent, joint, X_PF, axis, X_MC,
                                     below, joint_below, mass, moment, inertia, q_h,
                                     False)
        rates[side] = task_rates(base_subspace, parent, joint, evaluation_h,
                                 quaternion_h, t + sign * h, reference, end_effector,
                                 xi_plus if side == 0 else xi_minus, Lambda,
                                 damping)[0]
    nu_dot = (rates[0] - rates[1]) / (2 * h)
    M, dM = evaluation[0], evaluation[1]
    C = christoffel(dM, qdot)
    s = qdot - nu
    Ms = matvec(M, s)
    phi = epsilon + chi / boundary_rate
    tau = matvec(M, nu_dot) + matvec(C, nu) - damping_rate * Ms
    for i in range(q.shape[0]):
        tau[i] -= chi * np.tanh(M[i, i] * s[i] / phi)
        if excitation[0] > 0:
            tau[i] += excitation[0] * np.sin(excitation[1 + i] * t)
    log = np.array([e[0], e[1], e[2], np.sqrt(np.sum(e * e)), np.sqrt(np.sum(s * s)),
                    0.5 * np.sum(s * Ms)])
    return tau, M, C, log, rotation_quaternion(R_d)
