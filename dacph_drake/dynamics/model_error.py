"""The LHS model's inertia error E, measured rather than assumed.

The port observer builds tau_obs from the LHS model M_hat, so the learner sees
(I + E) B~ and (I + E) D~ with E = M_hat M~^-1 - I (M~ the true reduced mass matrix,
docs/equations.md): port data alone cannot tell a gain from an inertia. What a run can
say about E comes from the momentum data the inertial identifier fits and from what the
user states about robot.nominal (scenario.InertiaIdentification):

- ``anchor_tolerance``: the measured mass that fixes the common scale momentum data
  leave free, known to this relative sd;
- ``nominal_tolerance``: robot.nominal's inertial parameters known to this relative sd
  (it matters only along the directions the data do not inform);
- ``kinematic_tolerance``: the components of every joint placement (X_PF's
  translation) known to this relative sd.

ModelErrorEnsemble draws ``error_draws`` plausible models per trial from these
statements, fits each to the same momentum data as the identifier (each with its own
kinematics, its own prior and its own anchor), and takes E's sd per entry as the RMS
over the draws of M_hat M_k^-1 - I at the current q, times Student's factor for that
many draws. Every draw that explains the data as well as the identified model is a
model the data cannot rule out, so their spread is what the data leave of E (with exact
kinematics, about the anchor's tolerance; with a few per cent of kinematic tolerance,
tens of per cent, since the identification then bends the inertias to fit)."""
from statistics import NormalDist
from typing import Optional, Sequence

import numpy as np
from pydrake.multibody.plant import MultibodyPlant

from dacph_drake.dynamics.inertial_parameters import identify_draws, identify_parameters
from dacph_drake.dynamics.tree_stack import TreeStack, positive_definite
from dacph_drake.quantiles import student_quantile
from dacph_drake.scenario import InertiaIdentification

# The level of the t factor on the draws' sd (the claims' credible_level default).
_LEVEL = 0.9


def stated_model_error(settings: InertiaIdentification, identified: bool) -> float:
    """E's relative sd from the statements alone, for a run without the ensemble's
    measurement: the nominal's inertial and kinematic tolerances (in quadrature) when
    nothing is identified; 0 when the identifier's ensemble measured it.

    Args:
        settings: The identification's settings (scenario.inertia).
        identified: Whether an identifier ran."""
    if identified:
        return 0.0
    return float(np.hypot(settings.nominal_tolerance, settings.kinematic_tolerance))


class ModelErrorEnsemble:
    """``settings.error_draws`` plausible controller models per trial and E's sd.

    Draw k of trial i has its prior pi0 (1 + nominal_tolerance N(0, 1)) per parameter
    (in the prior's scales), its anchor's mass (1 + anchor_tolerance N(0, 1)) and its
    joint placements' components t (1 + kinematic_tolerance N(0, 1)), from a generator
    seeded by the trial's seed (a batch's trial draws what it draws alone). With exact
    kinematics every draw fits the identifier's own information (one accumulation);
    otherwise each draw accumulates its own (AddInformation).

    Args:
        plants: Each trial's controller plant.
        settings: The identification's settings.
        priors: Each trial's prior pi0 (trials, parameters).
        scales: Each trial's prior scales S (trials, parameters).
        anchor: The anchor's constraint c (trials, parameters), or None (the prior's).
        anchor_values: Each trial's anchored mass [kg], or None.
        seeds: Each trial's seed."""

    def __init__(self, *, plants: Sequence[MultibodyPlant],
                 settings: InertiaIdentification, priors: np.ndarray, scales: np.ndarray,
                 anchor: Optional[np.ndarray], anchor_values: Optional[np.ndarray],
                 seeds: Sequence[int]):
        K, count = settings.error_draws, len(plants)
        self.draws, self._settings = K, settings
        self.own_information = settings.kinematic_tolerance > 0
        self._trees = TreeStack([plant for plant in plants for _ in range(K)])
        size = priors.shape[1]
        self._priors = np.repeat(priors, K, axis=0)
        self._scales = np.repeat(scales, K, axis=0)
        self._anchor = None if anchor is None else np.repeat(anchor, K, axis=0)
        self._anchor_values = (None if anchor_values is None
                               else np.repeat(np.asarray(anchor_values, float), K))
        offsets = self._trees.X_PF[:, :, :3, 3]
        for i, seed in enumerate(seeds):
            rng = np.random.default_rng([int(seed), 0xE5])
            draws = slice(i * K, (i + 1) * K)
            self._priors[draws] += (settings.nominal_tolerance * self._scales[draws]
                                    * rng.standard_normal((K, size)))
            relative = rng.standard_normal((K, 1))
            if self._anchor_values is not None:
                self._anchor_values[draws] *= 1.0 + settings.anchor_tolerance * relative[:, 0]
            offsets[draws] *= 1.0 + settings.kinematic_tolerance * rng.standard_normal(
                offsets[draws].shape)
        z = NormalDist().inv_cdf(0.5 + 0.5 * _LEVEL)
        self._factor = student_quantile(z, max(K, 2)) / z

    @property
    def members(self) -> int:
        """The number of draws of the batch (trials x error_draws)."""
        return len(self._trees)

    def AddInformation(self, base_pose: np.ndarray, base_velocity: np.ndarray,
                       q: np.ndarray, qdot: np.ndarray, information: np.ndarray) -> None:
        """information[i K + k] += vec(Y^T Y) of draw k of trial i at trial i's measured
        state (in place; with kinematic_tolerance > 0 only).

        Args:
            base_pose: Each trial's base pose (trials, base positions).
            base_velocity: Each trial's base velocity (trials, base velocities).
            q: Each trial's joint angles (trials, n) [rad].
            qdot: Each trial's joint rates (trials, n) [rad/s].
            information: The draws' information (members, parameters^2)."""
        K = self.draws
        self._trees.AddInformation(*(np.repeat(x, K, axis=0) for x in
                                     (base_pose, base_velocity, q, qdot)), information)

    def ErrorSd(self, information: np.ndarray, M_hat: np.ndarray, q: np.ndarray
                ) -> np.ndarray:
        """E's sd per entry (trials, n, n) at q: the RMS over each trial's usable draws
        (positive-definite M_k) of M_hat M_k^-1 - I, times Student's factor;
        nominal_tolerance where no draw is usable.

        Args:
            information: The draws' information (members, p, p), or with exact
                kinematics the trials' own (trials, p, p).
            M_hat: Each trial's identified M(q) (trials, n, n).
            q: Each trial's joint angles (trials, n) [rad]."""
        K, (count, n) = self.draws, q.shape
        if not self.own_information and self._anchor is not None:
            size = self._priors.shape[1]
            pis = identify_draws(
                information, self._priors.reshape(count, K, size), self._scales[::K],
                self._settings.prior_weight, self._anchor[::K],
                self._anchor_values.reshape(count, K)).reshape(count * K, size)
        else:
            if not self.own_information:
                information = np.repeat(information, K, axis=0)
            pis = identify_parameters(information, self._priors, self._scales,
                                      self._settings.prior_weight, self._anchor,
                                      self._anchor_values)
        M = self._trees.ReducedMassMatrices(pis, np.repeat(q, K, axis=0))
        usable = positive_definite(M).reshape(count, K)
        safe = np.where(usable.reshape(-1)[:, None, None], M, np.eye(n))
        E = (np.repeat(M_hat, K, axis=0) @ np.linalg.inv(safe) - np.eye(n)).reshape(
            count, K, n, n)
        squares = np.sum(np.where(usable[:, :, None, None], E ** 2, 0.0), axis=1)
        used = np.sum(usable, axis=1)
        sd = np.sqrt(squares / np.maximum(used, 1)[:, None, None]) * self._factor
        return np.where((used > 0)[:, None, None], sd, self._settings.nominal_tolerance)


def realized_model_error(model_plant: MultibodyPlant, truth_plant: MultibodyPlant,
                         pis: np.ndarray, q: np.ndarray) -> np.ndarray:
    """E = M_hat M~^-1 - I at each sample (T, n, n), which only a simulation knows:
    M_hat the model's plant at the parameters pis, M~ the truth's at its own.

    Args:
        model_plant: The controller's plant (its kinematics).
        truth_plant: The ground truth's plant (its kinematics and inertias).
        pis: The model's inertial parameters at each sample (T, parameters).
        q: The joint angles at each sample (T, n) [rad]."""
    from dacph_drake.dynamics.inertial_parameters import InertialParameters
    model, truth = TreeStack([model_plant]), TreeStack([truth_plant])
    pi_true = InertialParameters(truth_plant).FromContext(truth_plant.CreateDefaultContext())
    n = q.shape[1]
    out = np.empty((len(q), n, n))
    for k in range(len(q)):
        M_hat = model.ReducedMassMatrices(pis[k:k + 1], q[k:k + 1])[0]
        M_true = truth.ReducedMassMatrices(pi_true[None], q[k:k + 1])[0]
        out[k] = M_hat @ np.linalg.inv(M_true) - np.eye(n)
    return out
