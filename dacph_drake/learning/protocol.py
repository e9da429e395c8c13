"""The port learner's protocol: what it is given (LearnerTrial, Channels), what it
publishes (PortEstimate, PublishedModel) and how it is driven (PortLearner)."""
from dataclasses import dataclass
from typing import Optional, Protocol, Sequence, Tuple

import numpy as np


@dataclass
class PortEstimate:
    """A batch's published estimates evaluated at each trial's state.

    Attributes:
        B: B_hat (trials, n, n).
        D: diag D_hat (trials, n) [N m s].
        B_set: The credible set of B at the certificate level, entrywise bounds
            (2, trials, n, n) (lower, upper); None for a learner without one.
        B_interval: The reporting interval of B (learner.local_bayes.credible_level)
            (2, trials, n, n); the point twice for a learner without one.
        D_interval: The same of D (2, trials, n)."""
    B: np.ndarray
    D: np.ndarray
    B_set: Optional[np.ndarray]
    B_interval: np.ndarray
    D_interval: np.ndarray


class PublishedModel(Protocol):
    """How the fast loops evaluate what a learner publishes, one per trial
    (published_model); Stack(models) evaluates a batch's.

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
        port_columns: Where the filtered sample [q, p, channels] holds the
            band-passed [qdot, u, tau_obs] (the RHS integrator's evidence reads them)."""
    size: int
    port_columns: np.ndarray

    def Of(self, t: float, samples: np.ndarray) -> np.ndarray:
        """Each trial's channels (trials, size) from its port sample.

        Args:
            t: The sample's time [s].
            samples: Each trial's identification.PortSample (trials, 5 n)."""


class PortLearner(Protocol):
    """A learner of a batch's trials (one: a single run), as RhsLearner drives it.

    Every ``period`` RhsLearner calls Update with the buffered band-passed samples
    of each trial; the learner returns what it publishes, its log row and its
    state, which lives in the Context (so that a run restored from a snapshot
    learns as the one it was taken from).

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
        """The credible set [lower, upper] of B (2 x n x n) before any learning; None
        for a learner without one.

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
        """One learner update: (published (trials, model.size), log rows (trials, LearnerLog
        size), state (trials, state_size)).

        Args:
            t: The time [s].
            rows: Each trial's buffered samples, oldest first (trials, samples,
                1 + 2 n + channels.size): [t, q, p, channels].
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
