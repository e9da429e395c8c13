"""The port learner's protocol: its inputs, what it publishes and how it is driven."""
from dataclasses import dataclass
from typing import Optional, Protocol, Sequence, Tuple

import numpy as np


@dataclass
class PortEstimate:
    """A batch's published estimates evaluated at each trial's state.

    Attributes:
        B: B_hat (trials, n, n).
        D: diag D_hat (trials, n) [N m s].
        B_set: B's certificate-level credible set [lower, upper] (2, trials, n, n), or None.
        B_interval: B's interval at credible_level (2, trials, n, n); else the point twice.
        D_interval: The same of D (2, trials, n)."""
    B: np.ndarray
    D: np.ndarray
    B_set: Optional[np.ndarray]
    B_interval: np.ndarray
    D_interval: np.ndarray


class PublishedModel(Protocol):
    """How the fast loops evaluate what a learner publishes per trial; Stack: a batch's.

    Attributes:
        size: The published vector's length per trial.
        has_uncertainty: Whether the vector carries a credible set."""
    size: int
    has_uncertainty: bool

    def Stack(self, models: Sequence["PublishedModel"]) -> "PublishedModel":
        """The evaluator (PublishedModel) of a batch.

        Args:
            models: The batch's trials' models (this one's kind)."""

    def Estimate(self, published: np.ndarray, t: float, q: np.ndarray,
                 p: np.ndarray) -> PortEstimate:
        """Every trial's estimate (PortEstimate) at its state.

        Args:
            published: Each trial's published vector (trials, size).
            t: The time [s].
            q: Each trial's joint angles (trials, n) [rad].
            p: Each trial's momenta (trials, n)."""


class Channels(Protocol):
    """The signals a learner's regression filter band-passes (systems.regression_filter).

    Attributes:
        size: The channels per trial.
        port_columns: Where [q, p, channels] holds the band-passed [qdot, u, tau_obs]."""
    size: int
    port_columns: np.ndarray

    def Of(self, t: float, samples: np.ndarray) -> np.ndarray:
        """Each trial's channels (trials, size) from its port sample.

        Args:
            t: The sample's time [s].
            samples: Each trial's identification.PortSample (trials, 5 n)."""


class PortLearner(Protocol):
    """A batch's learner, state in the Context (a restored snapshot learns alike).

    Attributes:
        channels: The channels its regression filter forms (Channels).
        model: How its published vector is evaluated (PublishedModel).
        state_size: Its state's length per trial."""
    channels: Channels
    model: PublishedModel
    state_size: int

    @staticmethod
    def BandPassed(settings: object) -> bool:
        """Whether it learns from band-passed samples (a RegressionFilter before it).

        Args:
            settings: The learner's settings (scenario.Learner)."""

    @staticmethod
    def Published(settings: object, trial: "LearnerTrial") -> PublishedModel:
        """The evaluator of one trial's published vector.

        Args:
            settings: The learner's settings.
            trial: The trial."""

    @staticmethod
    def PriorSet(settings: object, B0: Sequence[float], D0: Sequence[float]
                 ) -> Optional[np.ndarray]:
        """The credible set [lower, upper] of B (2 x n x n) before learning, or None.

        Args:
            settings: The learner's settings.
            B0: The prior's B0 (its diagonal, n).
            D0: The prior's D0 (its diagonal, n)."""

    def InitialState(self) -> np.ndarray:
        """Each trial's state at the start (trials, state_size)."""

    def Prior(self) -> np.ndarray:
        """Each trial's published vector of the prior (B0, D0) (trials, model.size)."""

    def Update(self, t: float, rows: np.ndarray, state: np.ndarray,
               model_changed: np.ndarray, learning: bool
               ) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
        """One update: (published (trials, model.size), LearnerLog rows, state) per trial.

        Args:
            t: The time [s].
            rows: Each trial's buffered samples [t, q, p, channels], oldest first.
            state: Each trial's state (trials, state_size).
            model_changed: Whether each trial's LHS model changed since the last update.
            learning: False publishes the prior (the dac-nominal ablation)."""


@dataclass
class LearnerTrial:
    """One trial's part of a learner.

    Attributes:
        model: The controller's model (the network's coupling scale reads
            diag M(q0); p = M qdot where input ``reduced_model`` is not connected).
        B0: The prior's B0 (its diagonal, n).
        D0: The prior's D0 (its diagonal, n) [N m s].
        seed: The learner's seed.
        q0: The start configuration [rad] (n)."""
    model: object
    B0: Sequence[float]
    D0: Sequence[float]
    seed: int
    q0: Sequence[float]
