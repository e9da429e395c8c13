"""The physics-informed RHS network (docs/equations.md E34-E35):

    h_B = MLP_B(X(x)), h_D = MLP_D(X(x)),  X(x) = (q, p / p_scale)
    B_hat(x) = F o mat(W_B h_B + b_B)             (n x n, o: entrywise product)
    D_hat(x) = diag(softplus(W_D h_D + b_D))      (positive definite)
    tau_hat = B_hat(x) u - D_hat(x) qdot          (d_known = 0)

Trained in torch (float64); the fast loops evaluate a compiled copy (ExportedNetwork). The
output layers start at zero, biases vec(B0 / F) and softplus^-1(D0): the nominal RHS."""
from typing import List, Optional, Sequence, Tuple, Union

import numpy as np
import torch

from dacph_drake.kernels.network import evaluate_networks
from dacph_drake.dynamics import ReducedModel
from dacph_drake.learning.protocol import PortEstimate
from dacph_drake.scenario import LEARNER_COUPLINGS, Learner


def coupling_factors(coupling: str, joint_inertias: Sequence[float]) -> np.ndarray:
    """The coupling scale F (n x n) of B_hat = F o mat(W_B h_B + b_B):

        "uniform": F_ij = 1 (the paper's network)
        "inertia": F_ij = min(1, m_i / m_j),  m = ``joint_inertias`` (diag M(q0))

    An error delta in B_ij adds delta u_j to joint i's torque; for a shoulder's u_j and a
    light wrist i no in-band data bound delta tightly, so F scales it and its steps down.

    Args:
        coupling: "uniform" or "inertia" (the learner's ``coupling`` setting).
        joint_inertias: diag M(q0), m above.

    Raises:
        ValueError: An unknown ``coupling``."""
    m = np.asarray(joint_inertias, float)
    if coupling == "uniform":
        return np.ones((len(m), len(m)))
    if coupling == "inertia":
        return np.minimum(1.0, m[:, None] / m[None, :])
    raise ValueError(f"coupling = {coupling!r}; allowed: {', '.join(LEARNER_COUPLINGS)}")


def port_torque(B: torch.Tensor, D: torch.Tensor, u: torch.Tensor,
                qdot: torch.Tensor) -> torch.Tensor:
    """The port torque tau = B u - D qdot (..., n) in torch; the leading axes broadcast.

    Args:
        B: Shape (..., n, n).
        D: The diagonal of D, shape (..., n).
        u: Shape (..., n).
        qdot: Shape (..., n)."""
    return torch.einsum("...ij,...j->...i", B, u) - D * qdot


class RhsNetwork(torch.nn.Module):
    """One trial's physics-informed RHS network (module docstring), starting at (B0, D0).

    Args:
        n: The number of joints.
        hidden: The MLPs' hidden layer widths.
        B0: The prior B (n x n).
        D0: The prior diag D (n); entries below 1e-6 count as 1e-6.
        momentum_scale: p_scale.
        seed: The seed of the initial weights (torch's global generator is left as is).
        coupling: F (coupling_factors; None: all ones)."""
    def __init__(self, n: int, hidden: List[int], B0: np.ndarray, D0: Sequence[float],
                 momentum_scale: float, seed: int, coupling: Optional[np.ndarray] = None):
        super().__init__()
        generator_state = torch.random.get_rng_state()
        torch.manual_seed(seed)
        self.n = n
        self.momentum_scale = momentum_scale
        coupling = np.ones((n, n)) if coupling is None else np.asarray(coupling, float)
        self.coupling = torch.as_tensor(coupling)
        self.body_B = _mlp(2 * n, hidden)
        self.body_D = _mlp(2 * n, hidden)
        self.head_B = torch.nn.Linear(hidden[-1], n * n, dtype=torch.float64)
        self.head_D = torch.nn.Linear(hidden[-1], n, dtype=torch.float64)
        self.set_constant(B0, np.maximum(np.asarray(D0, float), 1e-6))
        torch.random.set_rng_state(generator_state)

    def set_constant(self, B: np.ndarray, D: Sequence[float]) -> None:
        """Sets the output layers to B_hat = B, D_hat = diag(D) everywhere (zero weights).

        Args:
            B: The constant B_hat (n x n).
            D: The constant diag D_hat (n), each > 0."""
        self.set_constant_B(B)
        with torch.no_grad():
            self.head_D.weight.zero_()
            self.head_D.bias.copy_(torch.as_tensor(np.log(np.expm1(np.asarray(D, float)))))

    def set_constant_B(self, B: np.ndarray) -> None:
        """Sets B's output layer to B_hat = B at every state (zero weights), not D_hat's.

        Args:
            B: The constant B_hat (n x n)."""
        with torch.no_grad():
            self.head_B.weight.zero_()
            self.head_B.bias.copy_(torch.as_tensor(
                (np.asarray(B, float) / self.coupling.numpy()).reshape(-1)))

    def features(self, q: torch.Tensor, p: torch.Tensor) -> torch.Tensor:
        """The MLPs' input X = (q, p / p_scale), shape (m, 2n).

        Args:
            q: The joint angles, shape (m, n) [rad].
            p: The momenta, shape (m, n) [kg m^2/s]."""
        return torch.cat([q, p / self.momentum_scale], dim=-1)

    def forward(self, q: torch.Tensor, p: torch.Tensor
                ) -> Tuple[torch.Tensor, torch.Tensor]:
        """The estimates (B_hat (m, n, n), D_hat's diagonal (m, n)) for a batch of states.

        Args:
            q: The joint angles, shape (m, n) [rad].
            p: The momenta, shape (m, n) [kg m^2/s]."""
        X = self.features(q, p)
        B = self.head_B(self.body_B(X)).reshape(-1, self.n, self.n) * self.coupling
        D = torch.nn.functional.softplus(self.head_D(self.body_D(X)))
        return B, D


    def export(self) -> np.ndarray:
        """All parameters as one float64 vector (ExportedNetwork.Evaluate's order)."""
        return torch.cat([t.detach().reshape(-1) for t in self.parameters()]).numpy()


class StackedRhsNetworks(torch.nn.Module):
    """A batch's RhsNetworks as one parameter ``flat`` (trials x P, row i trial i's export),
    the layers its views: one batched pass trains all, each trial's gradient its own row.

    Args:
        networks: Each trial's RhsNetwork, alike but for weights and coupling scales."""

    def __init__(self, networks: List[RhsNetwork]):
        super().__init__()
        first = networks[0]
        self.n, self.momentum_scale = first.n, first.momentum_scale
        self.coupling = torch.stack([network.coupling for network in networks])
        self.layers = len(first.body_B) // 2
        self.flat = torch.nn.Parameter(torch.as_tensor(np.array(
            [network.export() for network in networks])))
        # In RhsNetwork.parameters()'s order: body_B's, body_D's, head_B, head_D.
        self._views, start = [], 0
        for parameter in first.parameters():
            size = parameter.numel()
            self._views.append((slice(start, start + size), tuple(parameter.shape)))
            start += size
        head_B = self._views[-4:-2]
        self.head_B_columns = slice(head_B[0][0].start, head_B[1][0].stop)

    def forward(self, q: torch.Tensor, p: torch.Tensor,
                trials: Optional[Union[Sequence[int], torch.Tensor]] = None
                ) -> Tuple[torch.Tensor, torch.Tensor]:
        """Some trials' (B_hat (t, m, n, n), D_hat's diagonal (t, m, n)) at their samples.

        Args:
            q: The joint angles, shape (t, m, n) [rad].
            p: The momenta, shape (t, m, n) [kg m^2/s].
            trials: The trials' indices (all by default; t of them)."""
        flat = self.flat if trials is None else self.flat[trials]
        params = [flat[:, columns].reshape((-1,) + shape) for columns, shape in self._views]
        coupling = self.coupling if trials is None else self.coupling[trials]
        X = torch.cat([q, p / self.momentum_scale], dim=-1)
        L = 2 * self.layers
        hB, hD = X, X
        for i in range(0, L, 2):
            hB = torch.tanh(_dense(params[i], params[i + 1], hB))
            hD = torch.tanh(_dense(params[L + i], params[L + i + 1], hD))
        W_B, b_B, W_D, b_D = params[2 * L:]
        t, m = q.shape[0], q.shape[1]
        B = _dense(W_B, b_B, hB).reshape(t, m, self.n, self.n) * coupling[:, None]
        D = torch.nn.functional.softplus(_dense(W_D, b_D, hD))
        return B, D

    def set_constant_B(self, trial: int, B: np.ndarray) -> None:
        """Sets one trial's B output layer to B_hat = B (as RhsNetwork.set_constant_B).

        Args:
            trial: The trial's index.
            B: The constant B_hat (n x n)."""
        (weight, _), (bias, _) = self._views[-4:-2]
        with torch.no_grad():
            self.flat[trial, weight] = 0.0
            self.flat[trial, bias] = torch.as_tensor(
                (np.asarray(B, float) / self.coupling[trial].numpy()).reshape(-1))

    def export(self) -> np.ndarray:
        """Each trial's parameters in RhsNetwork.export's order (trials, size)."""
        return self.flat.detach().numpy().copy()


def _dense(weight, bias, x):
    """x W^T + b per trial: weight (t, out, in), bias (t, out), x (t, m, in)."""
    return torch.baddbmm(bias[:, None, :], x, weight.transpose(1, 2))


def _mlp(inputs: int, hidden: List[int]) -> torch.nn.Sequential:
    layers, width = [], inputs
    for h in hidden:
        layers += [torch.nn.Linear(width, h, dtype=torch.float64), torch.nn.Tanh()]
        width = h
    return torch.nn.Sequential(*layers)


class ExportedNetwork:
    """RhsNetwork from its exported parameters: a PublishedModel with no credible set.

    Args:
        n: The number of joints.
        hidden: The MLPs' hidden layer widths.
        momentum_scale: p_scale.
        coupling: F (coupling_factors; None: all ones)."""

    def __init__(self, n: int, hidden: List[int], momentum_scale: float,
                 coupling: Optional[np.ndarray] = None):
        self.n = n
        self._momentum_scale = momentum_scale
        self.coupling = np.ones((n, n)) if coupling is None else np.asarray(coupling, float)
        shapes = []
        for _ in range(2):                    # body_B then body_D
            width = 2 * n
            for h in hidden:
                shapes += [(h, width), (h,)]
                width = h
        shapes_B, shapes_D = shapes[:len(shapes) // 2], shapes[len(shapes) // 2:]
        # torch's parameters() order: body_B, body_D, head_B, head_D.
        self._shapes = (shapes_B + shapes_D + [(n * n, hidden[-1]), (n * n,),
                                               (n, hidden[-1]), (n,)])
        self.size = int(sum(np.prod(s) for s in self._shapes))
        self._hidden = np.asarray(hidden, np.int64)

    has_uncertainty = False

    @staticmethod
    def Stack(models: Sequence["ExportedNetwork"]) -> "NetworkStack":
        """The evaluator (NetworkStack) of a batch whose trials' networks are ``models``.

        Args:
            models: Each trial's ExportedNetwork."""
        return NetworkStack(models)

    @staticmethod
    def ForLearner(settings: Learner, model: ReducedModel, q0: Sequence[float]
                   ) -> "ExportedNetwork":
        """The evaluator of a learner's network (each reader of ``weights`` builds its own).

        Args:
            settings: The learner's settings (scenario.Learner).
            model: The controller's model (num_joints, MassMatrix).
            q0: The initial joint angles [rad] (F from diag M(q0): coupling_factors)."""
        return ExportedNetwork(model.num_joints, settings.hidden, settings.momentum_scale,
                               coupling_factors(settings.coupling, np.diag(
                                   model.MassMatrix(np.asarray(q0, float)))))

    def Evaluate(self, weights: np.ndarray, q: np.ndarray, p: np.ndarray
                 ) -> Tuple[np.ndarray, np.ndarray]:
        """The estimates (B_hat (n x n), D_hat's diagonal (n,)) at one state.

        Args:
            weights: The exported parameters (RhsNetwork.export), shape (size,).
            q: The joint angles (n) [rad].
            p: The momenta (n) [kg m^2/s]."""
        B, D = evaluate_networks(
            self._hidden, self._momentum_scale, np.asarray(weights, float)[None],
            np.asarray(q, float)[None], np.asarray(p, float)[None], self.coupling[None])
        return B[0], D[0]


class NetworkStack:
    """A batch's exported networks, evaluated in one compiled call (its PublishedModel).

    Args:
        networks: Each trial's ExportedNetwork, alike but for their coupling scales."""
    has_uncertainty = False

    def __init__(self, networks: Sequence[ExportedNetwork]):
        self._hidden = networks[0]._hidden
        self._momentum_scale = networks[0]._momentum_scale
        self._coupling = np.array([network.coupling for network in networks])
        self.size = networks[0].size

    def Estimate(self, published: np.ndarray, t: float, q: np.ndarray, p: np.ndarray
                 ) -> PortEstimate:
        """PublishedModel.Estimate: the point, which is also its interval (no credible set).

        Args:
            published: Each trial's exported parameters (trials, size).
            t: The time [s] (unused).
            q: Each trial's joint angles (trials, n) [rad].
            p: Each trial's momenta (trials, n)."""
        B, D = self.Evaluate(published, q, p)
        return PortEstimate(B=B, D=D, B_set=None, B_interval=np.stack([B, B]),
                            D_interval=np.stack([D, D]))

    def Evaluate(self, weights: np.ndarray, q: np.ndarray, p: np.ndarray
                 ) -> Tuple[np.ndarray, np.ndarray]:
        """(B_hat (trials, n, n), diag D_hat (trials, n)), each trial at its weights, q, p.

        Args:
            weights: Each trial's exported parameters, shape (trials, size).
            q: Each trial's joint angles, shape (trials, n) [rad].
            p: Each trial's momenta, shape (trials, n) [kg m^2/s]."""
        return evaluate_networks(self._hidden, self._momentum_scale, weights, q, p,
                                 self._coupling)
