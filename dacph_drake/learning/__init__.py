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
  (PublishedModel), its state in the Context, and Update.
- learning.local_bayes.LocalBayesLearner (``learner.model: local_bayes``, the
  default): a local Bayesian linear model per joint with calibrated intervals.
- learning.network_learner.NetworkLearner (``learner.model: network``): the paper's
  physics-informed network (network.RhsNetwork), a point estimate.

make_port_learner chooses by ``learner.model``; every learner runs through the
same diagram, metrics and ablation (scripts/learning_families.py)."""
from typing import Optional, Sequence

import numpy as np

from dacph_drake.learning.protocol import (Channels, LearnerTrial, PortEstimate,  # noqa: F401
                                           PortLearner, PublishedModel)
from dacph_drake.scenario import Learner


def uses_local_bayes(settings: Learner) -> bool:
    """Whether the settings name the local Bayesian learner (else the network): ``model``
    "local_bayes" in regularized mode (``mode`` "plain" is the paper's plain learner, the
    network, whatever ``model`` says).

    Args:
        settings: The learner's settings."""
    return settings.model == "local_bayes" and settings.mode == "regularized"


def make_port_learner(settings: Learner, trials: Sequence[LearnerTrial],
                      period: float, sample_period: float) -> PortLearner:
    """The PortLearner ``settings.model`` names, for a batch's trials.

    Args:
        settings: The learner's settings (scenario.learner).
        trials: Each trial's LearnerTrial.
        period: The training period [s] (periods.learner).
        sample_period: The sampling period [s] (periods.learner_sample)."""
    if uses_local_bayes(settings):
        from dacph_drake.learning.local_bayes import LocalBayesLearner
        return LocalBayesLearner(settings, trials, period, sample_period)
    from dacph_drake.learning.network_learner import NetworkLearner
    return NetworkLearner(settings, trials, period, sample_period)


def published_model(settings: Learner, trial: LearnerTrial) -> PublishedModel:
    """The evaluator (PublishedModel; its Stack evaluates a batch's) of one trial's
    published vector, as make_port_learner's learner publishes it (the RHS integrator builds
    its own from the same settings).

    Args:
        settings: The learner's settings.
        trial: The trial."""
    if uses_local_bayes(settings):
        from dacph_drake.learning.local_bayes import LocalModel
        return LocalModel(len(trial.B0))
    from dacph_drake.learning.network import ExportedNetwork
    return ExportedNetwork.ForLearner(settings, trial.model, trial.q0)


def prior_set(settings: Learner, B0: Sequence[float], D0: Sequence[float]
              ) -> Optional[np.ndarray]:
    """The credible set [lower, upper] of B (2 x n x n) the learner publishes before it has
    learned anything (the local Bayesian learner's prior range,
    learning.local_bayes.prior_range), or None for a learner without a credible set.

    Args:
        settings: The learner's settings.
        B0: The prior's B0 (its diagonal, n).
        D0: The prior's D0 (its diagonal, n)."""
    if not uses_local_bayes(settings):
        return None
    from dacph_drake.learning.local_bayes import prior_range
    n = len(B0)
    return prior_range(settings.bayes, B0, D0)[:, :n * n].reshape(2, n, n)

