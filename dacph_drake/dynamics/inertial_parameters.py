"""The inertial parameters of a free-floating robot's bodies, and the two things the
controller needs that are linear in them: the mass matrix and the momentum.

Body k has ten parameters, in its own frame B about its origin Bo,

    pi_k = [m, h_x, h_y, h_z, I_xx, I_yy, I_zz, I_xy, I_xz, I_yz],

the mass m, the first moment h = m p_BoBcm and the rotational inertia I about Bo.
In the world frame (R = R_WB, o = p_WoBo) the body's spatial inertia about Bo is

    M_k = [[R I R^T, S(R h)], [S(R h)^T, m 1]]        (Drake's [omega; v] order)

so that H(q) = sum_k J_k^T M_k J_k (J_k the body origin's spatial velocity Jacobian)
and the system's momentum about the world origin, with (omega_k, v_k) the body's
angular velocity and its origin's velocity,

    P = sum_k m v_k + omega_k x (R h)
    L = sum_k R I R^T omega_k + (R h) x v_k + o x P_k

are both linear in pi = [pi_1, ..., pi_N] for given positions and velocities:
P, L = Y(x) pi (MomentumRegressor). In free flight from rest, P = L = 0, so
Y(x) pi~ = 0 along any motion: the measured base and joint rates determine the
true parameters up to one common factor (Yoshida and Abiko, "Inertia parameter
identification for a free-flying space robot", AIAA GNC 2002) with no actuator
model at all (systems/inertial_identifier.py).
"""
from typing import List, Optional

import numpy as np
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import (BodyIndex, JacobianWrtVariable, SpatialInertia,
                                    UnitInertia)
from pydrake.systems.framework import Context

from dacph_drake.dynamics.kinematic_tree import KinematicTree

PER_BODY = 10
MASS, MOMENT, INERTIA = 0, slice(1, 4), slice(4, 10)


def _skew(a: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])


def _inertia_matrix(theta: np.ndarray) -> np.ndarray:
    """The symmetric 3 x 3 inertia of theta = [Ixx, Iyy, Izz, Ixy, Ixz, Iyz]."""
    xx, yy, zz, xy, xz, yz = theta
    return np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])


def _inertia_regressor(w: np.ndarray) -> np.ndarray:
    """W(w) with I w = W(w) theta for theta = [Ixx, Iyy, Izz, Ixy, Ixz, Iyz]."""
    return np.array([[w[0], 0, 0, w[1], w[2], 0],
                     [0, w[1], 0, w[0], 0, w[2]],
                     [0, 0, w[2], 0, w[0], w[1]]])


class InertialParameters:
    """The parameter layout of a finalized plant's bodies and the maps above.

    The layout holds every body with mass but the world, in body index order (a
    massless frame body, such as a URDF's tool link, carries none); the maps are
    evaluated on a context of that plant (its kinematics only: the maps do not read
    the context's own inertias).

    Args:
        plant: The finalized plant.
    """

    def __init__(self, plant: MultibodyPlant):
        self.plant = plant
        self.bodies = [body for body in (plant.get_body(BodyIndex(i))
                                         for i in range(1, plant.num_bodies()))
                       if body.default_mass() > 0]
        self.size = PER_BODY * len(self.bodies)

    def body_slice(self, k: int) -> slice:
        """The columns of a body's ten parameters in pi.

        Args:
            k: The body's position in the layout (0-based).

        Returns:
            The slice of its columns."""
        return slice(PER_BODY * k, PER_BODY * (k + 1))

    def FromContext(self, context: Context) -> np.ndarray:
        """pi of the inertias the plant holds in a context.

        Args:
            context: A context of the plant.

        Returns:
            pi (size)."""
        pi = np.zeros(self.size)
        for k, body in enumerate(self.bodies):
            M = body.CalcSpatialInertiaInBodyFrame(context)
            m = M.get_mass()
            block = pi[self.body_slice(k)]
            block[MASS] = m
            block[MOMENT] = m * M.get_com()
            I = M.CalcRotationalInertia().CopyToFullMatrix3()
            block[INERTIA] = [I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]]
        return pi

    def SpatialInertias(self, pi: np.ndarray) -> List[SpatialInertia]:
        """One Drake SpatialInertia per body, unchecked.

        An identified pi is exact only in the directions the motion informs (a
        planar arm's out-of-plane inertias stay at the prior while its in-plane one
        moves, which may break the triangle inequality of a body that does not
        exist), so the identifier checks the mass matrix the controller will use
        instead.

        Args:
            pi: The bodies' parameters (size).

        Returns:
            The bodies' spatial inertias about their origins, in their frames, in
                layout order."""
        out = []
        for k in range(len(self.bodies)):
            block = pi[self.body_slice(k)]
            m = block[MASS]
            G = _inertia_matrix(block[INERTIA]) / m
            out.append(SpatialInertia(m, block[MOMENT] / m, UnitInertia(
                G[0, 0], G[1, 1], G[2, 2], G[0, 1], G[0, 2], G[1, 2]),
                skip_validity_check=True))
        return out


    def Nodes(self, tree: KinematicTree) -> np.ndarray:
        """The node of each body of this layout in a kinematic tree.

        Where the compiled kernels (kernels.identification) put each body's
        parameters.

        Args:
            tree: The plant's kinematic_tree.KinematicTree.

        Returns:
            The nodes, in layout order."""
        node_of = {int(body.index()): node for node, body in enumerate(tree.bodies)}
        return np.array([node_of[int(body.index())] for body in self.bodies])

    def Apply(self, context: Context, pi: np.ndarray) -> None:
        """Sets the plant's bodies in a context to the inertias pi.

        Args:
            context: A context of the plant.
            pi: The bodies' parameters (size).
        """
        for body, M in zip(self.bodies, self.SpatialInertias(pi)):
            body.SetSpatialInertiaInBodyFrame(context, M)

    def _Kinematics(self, context, body):
        X = self.plant.EvalBodyPoseInWorld(context, body)
        V = self.plant.EvalBodySpatialVelocityInWorld(context, body)
        return X.rotation().matrix(), X.translation(), V.rotational(), V.translational()

    def MomentumRegressor(self, context: Context) -> np.ndarray:
        """The momentum regressor Y: [L about the world origin; P] = Y pi.

        Args:
            context: A context of the plant, whose positions and velocities are
                used.

        Returns:
            Y (6 x size)."""
        Y = np.zeros((6, self.size))
        for k, body in enumerate(self.bodies):
            R, o, omega, v = self._Kinematics(context, body)
            block = Y[:, self.body_slice(k)]
            dP_dm, dP_dh = v, _skew(omega) @ R
            block[3:, MASS] = dP_dm
            block[3:, MOMENT] = dP_dh
            block[:3, MASS] = _skew(o) @ dP_dm
            block[:3, MOMENT] = -_skew(v) @ R + _skew(o) @ dP_dh
            block[:3, INERTIA] = R @ _inertia_regressor(R.T @ omega)
        return Y

    def MassMatrixBasis(self, context: Context) -> np.ndarray:
        """The mass matrix's basis H_j: H(q) = sum_j pi_j H_j.

        With the body's Jacobian rotated into its frame, a = R^T J_w,
        b = R^T J_v (rows a_x, a_y, a_z, ...): H_m = b^T b, H_h_i = a^T S(e_i) b + its
        transpose, H_I_xx = a_x^T a_x, H_I_xy = a_x^T a_y + a_y^T a_x, and so on.

        Args:
            context: A context of the plant, whose positions are used.

        Returns:
            H_j (size x nv x nv)."""
        nv = self.plant.num_velocities()
        world = self.plant.world_frame()
        out = np.zeros((self.size, nv, nv))
        for k, body in enumerate(self.bodies):
            J = self.plant.CalcJacobianSpatialVelocity(
                context, JacobianWrtVariable.kV, body.body_frame(), np.zeros(3), world,
                world)
            R = self.plant.EvalBodyPoseInWorld(context, body).rotation().matrix()
            a, b = R.T @ J[:3], R.T @ J[3:]
            block = out[self.body_slice(k)]
            block[MASS] = b.T @ b
            for i, (y, z) in enumerate(((1, 2), (2, 0), (0, 1))):   # S(e_i) b = e_i x b
                coupling = np.outer(a[z], b[y]) - np.outer(a[y], b[z])
                block[1 + i] = coupling + coupling.T
            for i, (x, y) in enumerate(((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))):
                product = np.outer(a[x], a[y])
                block[4 + i] = product if x == y else product + product.T
        return out


def prior_scales(parameters: InertialParameters, pi0: np.ndarray) -> np.ndarray:
    """A size for every parameter of the prior pi0, by body.

    The body's mass m, m r for the first moments and m r^2 for the inertia
    entries, r = sqrt(I_max / m) its radius of gyration about its origin. They
    weigh the prior term of identify_parameters so that a relative error counts
    alike in every entry.

    Args:
        parameters: The parameter layout.
        pi0: The prior (parameters.size).

    Returns:
        The scales (parameters.size)."""
    scales = np.empty(parameters.size)
    for k in range(len(parameters.bodies)):
        block = pi0[parameters.body_slice(k)]
        m = block[MASS]
        inertia = max(np.max(np.abs(block[INERTIA])), 1e-12 * m)
        r = np.sqrt(inertia / m)
        scales[parameters.body_slice(k)] = [m] + [m * r] * 3 + [inertia] * 6
    return scales


def identify_parameters(information: np.ndarray, pi0: np.ndarray, scales: np.ndarray,
                        prior_weight: float, anchor: Optional[np.ndarray] = None,
                        anchor_value: Optional[np.ndarray] = None) -> np.ndarray:
    """The inertial parameters the momentum samples identify, regularized by the prior.

    argmin_pi  pi^T A pi + r (pi - pi0)^T S^-2 (pi - pi0)  subject to
    pi0^T S^-2 pi = pi0^T S^-2 pi0,  A = sum_k Y_k^T Y_k the ``information`` of the
    momentum samples (Y_k pi~ = 0 for the truth), S the prior's scales and
    r = prior_weight trace(S A S) / size: the data determine every direction they
    inform more than prior_weight times the average, the rest stays at the prior,
    and the common scale of all parameters, which momentum data cannot fix, is the
    prior's: pi's component along pi0 in the prior's metric S^-2 is pi0's (on the
    truth's ray, k = |pi0|^2_S / (pi0^T S^-2 pi~)). Without that constraint the
    ridge alone held the scale, and a controller's model whose link lengths were a
    few percent off the robot's (Y_k pi~ no longer exactly 0 for any pi) shrank to
    a quarter of the robot's mass.

    With ``anchor`` the common scale is fixed by what a user measures instead: the
    constraint is anchor^T pi = anchor_value (MassAnchor: the bodies' total mass,
    or the base's, equal to a measured mass).

    Stacked arguments (information (trials, size, size), pi0, scales and anchor
    (trials, size), anchor_value (trials,)) solve one problem per trial.

    Args:
        information: A = sum_k Y_k^T Y_k (size x size), or a stack.
        pi0: The prior (size), or a stack.
        scales: S, the prior's scales (prior_scales), or a stack.
        prior_weight: The prior's weight relative to the average information.
        anchor: The constraint's vector c (size), or a stack; None: the prior's
            component along pi0, c = S^-2 pi0.
        anchor_value: c^T pi (a scalar, or one per trial); with ``anchor`` only.

    Returns:
        pi (size), or a stack; pi0 where r is not > 0 (no information)."""
    information, pi0 = np.asarray(information, float), np.asarray(pi0, float)
    S2 = np.asarray(scales, float)**2
    size = pi0.shape[-1]
    r = prior_weight * np.sum(np.diagonal(information, axis1=-2, axis2=-1) * S2,
                              axis=-1) / size
    informed = r > 0
    out = pi0.copy()
    if not np.any(informed):
        return out
    # KKT: (S^2 A + r I) pi + mu S^2 c = r pi0,  c^T pi = v (c = S^-2 pi0, v = c^T pi0
    # without an anchor).
    S2, A, r, p = S2[informed], information[informed], r[informed], pi0[informed]
    if anchor is None:
        c = p / S2
        value = np.sum(c * p, axis=-1)
    else:
        c = np.broadcast_to(np.asarray(anchor, float), pi0.shape)[informed]
        value = np.broadcast_to(np.asarray(anchor_value, float), pi0.shape[:-1])[informed]
    system = np.zeros(p.shape[:-1] + (size + 1, size + 1))
    system[..., :size, :size] = S2[..., :, None] * A + r[..., None, None] * np.eye(size)
    system[..., :size, size] = S2 * c
    system[..., size, :size] = c
    rhs = np.concatenate([r[..., None] * p, value[..., None]], axis=-1)
    out[informed] = np.linalg.solve(system, rhs[..., None])[..., :size, 0]
    return out


def mass_anchor(parameters: InertialParameters, bodies: Optional[List[int]] = None
                ) -> np.ndarray:
    """The vector c with c^T pi the mass of some bodies (identify_parameters' anchor).

    Args:
        parameters: The parameter layout.
        bodies: The bodies' positions in the layout (None: all, the total mass).

    Returns:
        c (parameters.size)."""
    c = np.zeros(parameters.size)
    for k in (range(len(parameters.bodies)) if bodies is None else bodies):
        c[PER_BODY * k + MASS] = 1.0
    return c


def momentum_misfit(information: np.ndarray, pi: np.ndarray, size_of_body: int = PER_BODY
                    ) -> np.ndarray:
    """The momentum the parameters leave unexplained, relative to the bodies' own.

    sqrt(pi^T A pi / sum_b pi_b^T A_bb pi_b): with the controller's kinematics right
    the motion's momentum is Y(x) pi~ = 0 and this is round-off; with a link a few
    percent longer than the model says, no pi explains the samples and it is of
    that order (InertialIdentifier's kinematic-mismatch test).

    Args:
        information: A = sum_k Y_k^T Y_k (size x size), or a stack.
        pi: The parameters (size), or a stack.
        size_of_body: The parameters per body.

    Returns:
        The misfit (a scalar, or one per trial)."""
    A, pi = np.asarray(information, float), np.asarray(pi, float)
    total = np.einsum("...i,...ij,...j->...", pi, A, pi)
    bodies = pi.shape[-1] // size_of_body
    own = 0.0
    for b in range(bodies):
        block = slice(size_of_body * b, size_of_body * (b + 1))
        own = own + np.einsum("...i,...ij,...j->...", pi[..., block], A[..., block, block],
                              pi[..., block])
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.sqrt(np.maximum(total, 0.0) / own)
