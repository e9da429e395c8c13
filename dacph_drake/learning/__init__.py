"""Learners of the port's RHS behind one protocol (paper section "RHS Control and
Learning").

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
  (PublishedModel), its state in the Context, and Update; its class says whether it
  learns from band-passed samples (BandPassed), how a trial's vector is evaluated
  (Published) and its prior's credible set (PriorSet).
- LEARNERS, by ``learner.model``: "local_bayes" (learning.local_bayes.LocalBayesLearner,
  the default), a local Bayesian linear model per joint with calibrated intervals;
  "network" (learning.network_learner.NetworkLearner), the paper's physics-informed
  network (network.RhsNetwork), a point estimate (``learner.mode`` "plain": the
  paper's learner, whatever ``model`` says).

A new learner is one module with its PortLearner class and one register_learner
line; every learner runs through the same diagram, metrics and ablation
(scripts/learning_families.py)."""
from typing import Dict, Optional, Sequence, Type

import numpy as np

from dacph_drake.learning.local_bayes import LocalBayesLearner
from dacph_drake.learning.network_learner import NetworkLearner
from dacph_drake.learning.protocol import (Channels, LearnerTrial, PortEstimate,  # noqa: F401
                                           PortLearner, PublishedModel)
from dacph_drake.scenario import Learner
from dacph_drake.scenario.errors import require_one_of

LEARNERS: Dict[str, Type[PortLearner]] = {"local_bayes": LocalBayesLearner,
                                          "network": NetworkLearner}


def register_learner(name: str, kind: Type[PortLearner]) -> None:
    """Registers a learner: ``learner.model: name`` runs it.

    Args:
        name: Its ``learner.model`` name.
        kind: Its PortLearner class."""
    LEARNERS[name] = kind


def learner_kind(settings: Learner) -> Type[PortLearner]:
    """The PortLearner class the settings name: LEARNERS[``model``], the network in
    ``mode`` "plain" (the paper's plain learner).

    Args:
        settings: The learner's settings.

    Raises:
        ConfigError: ``model`` names no registered learner."""
    require_one_of("learner.model", settings.model, tuple(LEARNERS))
    return NetworkLearner if settings.mode == "plain" else LEARNERS[settings.model]


def make_port_learner(settings: Learner, trials: Sequence[LearnerTrial],
                      period: float, sample_period: float) -> PortLearner:
    """The PortLearner the settings name (learner_kind), for a batch's trials.

    Args:
        settings: The learner's settings (scenario.learner).
        trials: Each trial's LearnerTrial.
        period: The training period [s] (periods.learner).
        sample_period: The sampling period [s] (periods.learner_sample)."""
    return learner_kind(settings)(settings, trials, period, sample_period)


def published_model(settings: Learner, trial: LearnerTrial) -> PublishedModel:
    """The evaluator (PublishedModel; its Stack evaluates a batch's) of one trial's
    published vector, as make_port_learner's learner publishes it (the RHS integrator
    builds its own from the same settings).

    Args:
        settings: The learner's settings.
        trial: The trial."""
    return learner_kind(settings).Published(settings, trial)


def prior_set(settings: Learner, B0: Sequence[float], D0: Sequence[float]
              ) -> Optional[np.ndarray]:
    """The credible set [lower, upper] of B (2 x n x n) the learner publishes before it has
    learned anything, or None for a learner without a credible set.

    Args:
        settings: The learner's settings.
        B0: The prior's B0 (its diagonal, n).
        D0: The prior's D0 (its diagonal, n)."""
    return learner_kind(settings).PriorSet(settings, B0, D0)
