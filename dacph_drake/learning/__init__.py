"""Learners of the port's RHS behind one protocol (paper section "RHS Control and
Learning", SPEC section 6).

A learner fits the port relation (the paper's tau_breve model, eq. "rhs_data_model")

    tau_obs = B~(x) u - D~(x) qdot + d(t),      x = (q, p)

to the band-passed port samples of a window, per trial of a batch, and publishes
what the fast loops need as one vector per trial: an estimate B_hat(x), D_hat(x)
and, if it knows it, a credible set of B (the RHS integrator adopts an estimate only
if the loop's certificate holds on the whole set: gain_rule.CertifiedGains) and
credible intervals of every entry (logged, for the metrics). A quantity the data
do not determine is published at the prior (B0, D0) with the prior's range.

- PortLearner: what systems.learner.RhsLearner asks of a learner: the channels its
  regression filter forms (Channels), how its published vector is evaluated
  (PublishedModel), its state in the Context, and Update.
- learning.local_bayes.LocalBayesLearner (``learner.model: local_bayes``, the
  default): a local Bayesian linear model per joint with calibrated intervals.
- learning.network_learner.NetworkLearner (``learner.model: network``): the paper's
  physics-informed network (network.RhsNetwork), a point estimate.

make_port_learner chooses by ``learner.model``; every learner runs through the
same diagram, metrics and ablation (scripts/learning_families.py)."""
from dataclasses import dataclass
from typing import Optional, Protocol, Sequence, Tuple

import numpy as np

from dacph_drake.scenario import Learner


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
        D_interval: The same of D (2, trials, n).
    """
    B: np.ndarray
    D: np.ndarray
    B_set: Optional[np.ndarray]
    B_interval: np.ndarray
    D_interval: np.ndarray


class PublishedModel(Protocol):
    """How the fast loops evaluate what a learner publishes.

    One per trial (published_model); Stack(models) evaluates a batch's.

    Attributes:
        size: The published vector's length per trial.
        has_uncertainty: Whether the vector carries a credible set.
    """
    size: int
    has_uncertainty: bool

    def Stack(self, models: Sequence["PublishedModel"]) -> "PublishedModel":
        """The evaluator of a batch.

        Args:
            models: The batch's trials' models (this one's kind).

        Returns:
            The batch's PublishedModel."""

    def Estimate(self, published: np.ndarray, t: float, q: np.ndarray,
                 p: np.ndarray) -> PortEstimate:
        """Every trial's estimate at its state.

        Args:
            published: Each trial's published vector (trials, size).
            t: The time [s].
            q: Each trial's joint angles (trials, n) [rad].
            p: Each trial's momenta (trials, n).

        Returns:
            The PortEstimate."""


class Channels(Protocol):
    """The signals a learner's regression filter band-passes (systems.regression_filter).

    Attributes:
        size: The channels per trial.
        port_columns: Where the filtered sample [q, p, channels] holds the
            band-passed [qdot, u, tau_obs] (the RHS integrator's evidence reads them).
    """
    size: int
    port_columns: np.ndarray

    def Of(self, t: float, samples: np.ndarray) -> np.ndarray:
        """Each trial's channels from its port sample.

        Args:
            t: The sample's time [s].
            samples: Each trial's identification.PortSample (trials, 5 n).

        Returns:
            The channels (trials, size)."""


class PortLearner(Protocol):
    """A learner of a batch's trials (one: a single run), as RhsLearner drives it.

    Every ``period`` RhsLearner calls Update with the buffered band-passed samples
    of each trial; the learner returns what it publishes, its log row and its
    state, which lives in the Context (so that a run restored from a snapshot
    learns as the one it was taken from).

    Attributes:
        channels: The channels its regression filter forms (Channels).
        model: How its published vector is evaluated (PublishedModel).
        state_size: Its state's length per trial.
    """
    channels: Channels
    model: PublishedModel
    state_size: int

    def InitialState(self) -> np.ndarray:
        """Each trial's state at the start (trials, state_size)."""

    def Prior(self) -> np.ndarray:
        """Each trial's published vector of the prior (B0, D0) (trials, model.size)."""

    def Update(self, t: float, rows: np.ndarray, state: np.ndarray,
               model_changed: np.ndarray, learning: bool
               ) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
        """One learner update.

        Args:
            t: The time [s].
            rows: Each trial's buffered samples, oldest first (trials, samples,
                1 + 2 n + channels.size): [t, q, p, channels].
            state: Each trial's state (trials, state_size).
            model_changed: Whether each trial's LHS model changed since the last
                update (an InertialIdentifier's new epoch).
            learning: False publishes the prior (the dac-nominal ablation).

        Returns:
            (published (trials, model.size), log rows (trials, LearnerLog size),
                state (trials, state_size))."""


@dataclass
class LearnerTrial:
    """One trial's part of a learner.

    Attributes:
        model: The controller's model (the network's coupling scale reads
            diag M(q0); p = M qdot where input ``reduced_model`` is not connected).
        B0: The prior's B0 (its diagonal, n).
        D0: The prior's D0 (its diagonal, n) [N m s].
        seed: The learner's seed.
        q0: The start configuration [rad] (n).
    """
    model: object
    B0: Sequence[float]
    D0: Sequence[float]
    seed: int
    q0: Sequence[float]


def uses_local_bayes(settings: Learner) -> bool:
    """Whether the settings name the local Bayesian learner: ``model``
    "local_bayes" in regularized mode (``mode`` "plain" is the paper's plain
    learner, the network, whatever ``model`` says).

    Args:
        settings: The learner's settings.

    Returns:
        True for the local Bayesian learner, False for the network."""
    return settings.model == "local_bayes" and settings.mode == "regularized"


def make_port_learner(settings: Learner, trials: Sequence[LearnerTrial],
                      period: float, sample_period: float) -> PortLearner:
    """The learner ``settings.model`` names, for a batch's trials.

    Args:
        settings: The learner's settings (scenario.learner).
        trials: Each trial's LearnerTrial.
        period: The training period [s] (periods.learner).
        sample_period: The sampling period [s] (periods.learner_sample).

    Returns:
        A PortLearner."""
    if uses_local_bayes(settings):
        from dacph_drake.learning.local_bayes import LocalBayesLearner
        return LocalBayesLearner(settings, trials, period, sample_period)
    from dacph_drake.learning.network_learner import NetworkLearner
    return NetworkLearner(settings, trials, period, sample_period)


def published_model(settings: Learner, trial: LearnerTrial) -> PublishedModel:
    """The evaluator of one trial's published vector, as make_port_learner's
    learner publishes it (the RHS integrator builds its own from the same
    settings).

    Args:
        settings: The learner's settings.
        trial: The trial.

    Returns:
        The PublishedModel of the trial (its Stack evaluates a batch's)."""
    if uses_local_bayes(settings):
        from dacph_drake.learning.local_bayes import LocalModel
        return LocalModel(len(trial.B0))
    from dacph_drake.network import ExportedNetwork
    return ExportedNetwork.ForLearner(settings, trial.model, trial.q0)


def prior_set(settings: Learner, B0: Sequence[float], D0: Sequence[float]
              ) -> Optional[np.ndarray]:
    """The credible set of B the learner publishes before it has learned anything
    (the local Bayesian learner's prior range, learning.local_bayes.prior_range),
    or None for a learner without a credible set.

    Args:
        settings: The learner's settings.
        B0: The prior's B0 (its diagonal, n).
        D0: The prior's D0 (its diagonal, n).

    Returns:
        [lower, upper] of B (2 x n x n), or None."""
    if not uses_local_bayes(settings):
        return None
    from dacph_drake.learning.local_bayes import prior_range
    n = len(B0)
    return prior_range(settings.bayes, B0, D0)[:, :n * n].reshape(2, n, n)

