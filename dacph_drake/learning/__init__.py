"""Learners of the port's RHS behind one protocol, PortLearner (paper section "RHS Control
and Learning"): each fits tau_obs = B~(x) u - D~(x) qdot + d(t), x = (q, p) (tau_breve,
eq. "rhs_data_model") to a window of band-passed port samples per trial and publishes
B_hat(x), D_hat(x) and, if it knows them, a credible set of B (adopted only if the
certificate holds on all of it: gain_rule.CertifiedGains) and intervals; what the data do
not determine, at the prior (B0, D0). LEARNERS, by ``learner.model``: "local_bayes" (the
default), "network" (the paper's, also for ``mode: plain``); register_learner adds one."""
from typing import Dict, Sequence, Type

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
    """The PortLearner class: LEARNERS[``model``], the network in ``mode`` "plain".

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
