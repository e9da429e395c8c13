"""The inertial parameters of a free-floating robot's bodies, and what is linear in them:
the mass matrix and the momentum. Body k has ten, in its frame B about its origin Bo,

    pi_k = [m, h_x, h_y, h_z, I_xx, I_yy, I_zz, I_xy, I_xz, I_yz],      h = m p_BoBcm,

its spatial inertia M_k = [[R I R^T, S(R h)], [S(R h)^T, m 1]] in the world (Drake's
[omega; v]), H(q) = sum_k J_k^T M_k J_k, and the momentum about the world origin

    P = sum_k m v_k + omega_k x (R h)
    L = sum_k R I R^T omega_k + (R h) x v_k + o x P_k

is [L; P] = Y(x) pi. In free flight from rest Y(x) pi~ = 0: the rates determine the
parameters up to a common factor, without an actuator model (Yoshida and Abiko, 2002)."""
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
    """The parameter layout of a finalized plant's bodies with mass, and the maps above.

    Args:
        plant: The finalized plant."""

    def __init__(self, plant: MultibodyPlant):
        self.plant = plant
        self.bodies = [body for body in (plant.get_body(BodyIndex(i))
                                         for i in range(1, plant.num_bodies()))
                       if body.default_mass() > 0]
        self.size = PER_BODY * len(self.bodies)

    def body_slice(self, k: int) -> slice:
        """The slice of a body's ten parameters' columns in pi.

        Args:
            k: The body's position in the layout (0-based)."""
        return slice(PER_BODY * k, PER_BODY * (k + 1))

    def FromContext(self, context: Context) -> np.ndarray:
        """pi (size) of the inertias the plant holds in a context.

        Args:
            context: A context of the plant."""
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
        """One Drake SpatialInertia per body about its origin, unchecked.

        Args:
            pi: The bodies' parameters (size)."""
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
        """Each body's node in a kinematic tree, in layout order.

        Args:
            tree: The plant's kinematic_tree.KinematicTree."""
        node_of = {int(body.index()): node for node, body in enumerate(tree.bodies)}
        return np.array([node_of[int(body.index())] for body in self.bodies])

    def IntoTreeInertias(self, pi: np.ndarray, nodes: np.ndarray, mass: np.ndarray,
                         moment: np.ndarray, inertia: np.ndarray) -> None:
        """Writes pi into a kinematic tree's inertia arrays, in place.

        Args:
            pi: The bodies' parameters (size).
            nodes: Each body's node in the tree (Nodes).
            mass: The nodes' masses (nodes,) [kg].
            moment: Their first moments m c (nodes, 3) [kg m].
            inertia: Their rotational inertias about their origins (nodes, 3, 3)."""
        blocks = np.asarray(pi, float).reshape(-1, PER_BODY)
        mass[nodes] = blocks[:, MASS]
        moment[nodes] = blocks[:, MOMENT]
        xx, yy, zz, xy, xz, yz = blocks[:, INERTIA].T
        inertia[nodes] = np.stack([np.stack([xx, xy, xz], -1), np.stack([xy, yy, yz], -1),
                                   np.stack([xz, yz, zz], -1)], -2)

    def Apply(self, context: Context, pi: np.ndarray) -> None:
        """Sets the plant's bodies in a context to the inertias pi.

        Args:
            context: A context of the plant.
            pi: The bodies' parameters (size)."""
        for body, M in zip(self.bodies, self.SpatialInertias(pi)):
            body.SetSpatialInertiaInBodyFrame(context, M)

    def _Kinematics(self, context, body):
        X = self.plant.EvalBodyPoseInWorld(context, body)
        V = self.plant.EvalBodySpatialVelocityInWorld(context, body)
        return X.rotation().matrix(), X.translation(), V.rotational(), V.translational()

    def MomentumRegressor(self, context: Context) -> np.ndarray:
        """The momentum regressor Y (6 x size): [L about the world origin; P] = Y pi.

        Args:
            context: A context of the plant (its positions and velocities)."""
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
        """The basis H_j (size x nv x nv) of H(q) = sum_j pi_j H_j: a = R^T J_w,
        b = R^T J_v, H_m = b^T b, H_h_i = a^T S(e_i) b + transpose, H_I_xx = a_x^T a_x...

        Args:
            context: A context of the plant (its positions)."""
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
    """Each prior parameter's scale per body: m, m r for the first moments, m r^2 for the
    inertias (r = sqrt(I_max / m)), so a relative error counts alike in each.

    Args:
        parameters: The parameter layout.
        pi0: The prior (parameters.size)."""
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
    """The inertial parameters pi (size, or a stack; pi0 where r is not > 0) the momentum
    samples identify, regularized by the prior:

        argmin_pi  pi^T A pi + r (pi - pi0)^T S^-2 (pi - pi0)  subject to  c^T pi = v

    with A = sum_k Y_k^T Y_k, S the prior's scales, r = prior_weight trace(S A S) / size:
    directions informed less than prior_weight times the average stay at the prior; the
    constraint fixes the common scale (c = S^-2 pi0, v = c^T pi0; or a measured mass).

    Args:
        information: A = sum_k Y_k^T Y_k (size x size), or a stack (trials, size, size).
        pi0: The prior (size), or a stack.
        scales: S, the prior's scales (prior_scales), or a stack.
        prior_weight: The prior's weight relative to the average information.
        anchor: The constraint's c (size), or a stack; None: c = S^-2 pi0.
        anchor_value: v = c^T pi (a scalar, or one per trial); with ``anchor`` only."""
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


# Eigenvalues of a compensated information below this fraction of its largest are the
# whitening's round-off (compensated_information).
ROUND_OFF = 1e-8


def compensated_information(information: np.ndarray, noise_information: np.ndarray,
                            readings: int) -> np.ndarray:
    """The information of the noiseless momentum samples from the measured A and the
    noise's expected share Sigma (TreeStack.AddNoiseInformation): the bias-compensated
    least squares of errors in variables, A - Sigma, kept only in the directions where
    the samples inform beyond the noise's own fluctuation.

    Whitened by Sigma (W = Sigma^-1/2, C = W A W = I + the signal's share, noise and
    signal-noise terms fluctuating), each eigendirection's excess e = lambda(C) - 1 of
    ``readings`` samples has sd about sqrt((2 + 4 e) / readings) from the noise (a sum of
    squares and of cross terms): a direction is kept, at e, where e exceeds three of
    them, else set to 0 (it stays at the prior). Sigma's null directions (no noise) keep
    A.

    Args:
        information: A (size x size), or a stack.
        noise_information: Sigma, as A, or a stack that broadcasts against A's with
            ones where several A share one Sigma (its whitening is computed once).
        readings: The number of samples summed in A."""
    A = np.asarray(information, float)
    Sigma = np.asarray(noise_information, float)
    size = A.shape[-1]
    # W's floor, 1e-9 of Sigma's scale (of 1e-12 of A's where Sigma vanishes): where
    # A's share one Sigma, of the largest A's.
    trace_A = np.trace(A, axis1=-2, axis2=-1)
    shared = tuple(axis for axis, length in enumerate(Sigma.shape[:-2])
                   if length == 1 and trace_A.shape[axis] > 1)
    trace = (np.trace(Sigma, axis1=-2, axis2=-1)
             + 1e-12 * np.max(trace_A, axis=shared, keepdims=True))
    floor = 1e-9 * np.maximum(trace, 1e-300) / size
    values, vectors = np.linalg.eigh(Sigma + floor[..., None, None] * np.eye(size))
    root = np.sqrt(np.maximum(values, floor[..., None]))
    W = _spectral(vectors, 1.0 / root)
    W_inverse = _spectral(vectors, root)
    excess, directions = np.linalg.eigh(W @ A @ W)
    excess = excess - 1.0
    sd = np.sqrt((2.0 + 4.0 * np.maximum(excess, 0.0)) / max(readings, 1))
    kept = np.where(excess > 3.0 * sd, excess, 0.0)
    compensated = W_inverse @ _spectral(directions, kept) @ W_inverse
    # The whitening's round-off (its floor is 1e-9 of Sigma's scale) is set to 0, so a
    # direction without information stays at the prior, whose weight is 1e-12 of A's.
    values, vectors = np.linalg.eigh(0.5 * (compensated + np.swapaxes(compensated, -1, -2)))
    largest = np.max(np.abs(values), axis=-1, keepdims=True)
    return _spectral(vectors, np.where(values > ROUND_OFF * largest, values, 0.0))


def _spectral(vectors: np.ndarray, values: np.ndarray) -> np.ndarray:
    """V diag(values) V^T of a stack of eigenvectors (columns) and values."""
    return (vectors * values[..., None, :]) @ np.swapaxes(vectors, -1, -2)


def identify_draws(information: np.ndarray, pi0: np.ndarray, scales: np.ndarray,
                   prior_weight: float, anchor: np.ndarray, anchor_values: np.ndarray
                   ) -> np.ndarray:
    """identify_parameters for draws sharing A, S, c: one KKT factorization per trial.

    Args:
        information: Each trial's A (trials, size, size).
        pi0: Each draw's prior (trials, draws, size).
        scales: Each trial's prior scales S (trials, size).
        prior_weight: The prior's weight relative to the average information.
        anchor: Each trial's constraint c (trials, size).
        anchor_values: Each draw's anchored value v (trials, draws)."""
    S2 = np.asarray(scales, float) ** 2
    size = pi0.shape[-1]
    r = prior_weight * np.sum(np.diagonal(information, axis1=-2, axis2=-1) * S2,
                              axis=-1) / size
    out = np.array(pi0, float)
    for i in np.flatnonzero(r > 0):
        system = np.zeros((size + 1, size + 1))
        system[:size, :size] = S2[i, :, None] * information[i] + r[i] * np.eye(size)
        system[:size, size] = S2[i] * anchor[i]
        system[size, :size] = anchor[i]
        rhs = np.concatenate([r[i] * pi0[i], anchor_values[i][:, None]], axis=1)
        out[i] = np.linalg.solve(system, rhs.T)[:size].T
    return out


def mass_anchor(parameters: InertialParameters, bodies: Optional[List[int]] = None
                ) -> np.ndarray:
    """c (parameters.size), c^T pi the mass of some bodies (identify_parameters' anchor).

    Args:
        parameters: The parameter layout.
        bodies: The bodies' positions in the layout (None: all, the total mass)."""
    c = np.zeros(parameters.size)
    for k in (range(len(parameters.bodies)) if bodies is None else bodies):
        c[PER_BODY * k + MASS] = 1.0
    return c


def momentum_misfit(information: np.ndarray, pi: np.ndarray, size_of_body: int = PER_BODY
                    ) -> np.ndarray:
    """The momentum the parameters leave unexplained relative to the bodies' own,
    sqrt(pi^T A pi / sum_b pi_b^T A_bb pi_b): round-off when the kinematics are right.

    Args:
        information: A = sum_k Y_k^T Y_k (size x size), or a stack.
        pi: The parameters (size), or a stack.
        size_of_body: The parameters per body."""
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
