"""The LHS model's inertia error E, measured rather than assumed.

The port observer builds tau_obs from the LHS model M_hat, so the learner sees
(I + E) B~ and (I + E) D~ with E = M_hat M~^-1 - I: port data cannot tell a gain from an
inertia. E is measured from the momentum data and the user's statements
(scenario.InertiaIdentification): ``anchor_tolerance`` (the measured mass's relative sd),
``nominal_tolerance`` (robot.nominal's parameters') and ``kinematic_tolerance`` (the
joint placements'). ModelErrorEnsemble draws plausible models from these, fits each to
the same data, and takes E's sd per entry as the RMS over the draws (models the data
cannot rule out) of M_hat M_k^-1 - I at the current q, times Student's factor."""
from statistics import NormalDist
from typing import Optional, Sequence

import numpy as np
from pydrake.multibody.plant import MultibodyPlant

from dacph_drake.dynamics.inertial_parameters import (
    compensated_information, identify_draws, identify_parameters)
from dacph_drake.dynamics.plant import ArmCoordinates
from dacph_drake.dynamics.sensor_noise import StateNoise, base_rate_columns
from dacph_drake.dynamics.tree_stack import TreeStack, positive_definite
from dacph_drake.quantiles import student_quantile
from dacph_drake.scenario import InertiaIdentification

# The level of the t factor on the draws' sd (the claims' credible_level default).
_LEVEL = 0.9


def stated_model_error(settings: InertiaIdentification, identified: bool) -> float:
    """E's relative sd from the statements alone (a run without the ensemble): the nominal's
    inertial and kinematic tolerances in quadrature when nothing is identified, else 0.

    Args:
        settings: The identification's settings (scenario.inertia).
        identified: Whether an identifier ran."""
    if identified:
        return 0.0
    return float(np.hypot(settings.nominal_tolerance, settings.kinematic_tolerance))


class ModelErrorEnsemble:
    """``settings.error_draws`` plausible controller models per trial and E's sd. Draw k has
    its prior pi0 (1 + nominal_tolerance N(0, 1)) per parameter, its anchor's mass
    (1 + anchor_tolerance N(0, 1)) and its joint placements t (1 + kinematic_tolerance
    N(0, 1)), seeded by the trial's seed; with exact kinematics and noiseless sensors every
    draw uses the identifier's information, otherwise each accumulates its own
    (AddInformation).

    With noisy sensors (``noise``) each draw reads the measured state with noise of its
    own added, of the sensors' statistics (a parametric bootstrap): the momentum is
    linear in the rates, so white rate noise adds sigma^2 Y(q, e)^T Y(q, e) to the
    information and pulls the identified parameters off the truth in the directions the
    motion informs weakly. A draw that reads the noise twice lands about as far from the
    identified model as that model lies from the truth, so E's sd covers the noise's
    bias as well as its spread.

    Args:
        plants: Each trial's controller plant.
        settings: The identification's settings.
        priors: Each trial's prior pi0 (trials, parameters).
        scales: Each trial's prior scales S (trials, parameters).
        anchor: The anchor's constraint c (trials, parameters), or None (the prior's).
        anchor_values: Each trial's anchored mass [kg], or None.
        seeds: Each trial's seed.
        noise: The noise on each reading of the measured state (none: exact).
        period: The readings' period [s] (the gyro bias' walk between them)."""

    def __init__(self, *, plants: Sequence[MultibodyPlant],
                 settings: InertiaIdentification, priors: np.ndarray, scales: np.ndarray,
                 anchor: Optional[np.ndarray], anchor_values: Optional[np.ndarray],
                 seeds: Sequence[int], noise: StateNoise = StateNoise(),
                 period: float = 0.0):
        K = settings.error_draws
        self.draws, self._settings = K, settings
        self._noise, self._period = noise, period
        self.own_information = settings.kinematic_tolerance > 0 or noise.Any()
        self._rate_columns = base_rate_columns(
            ArmCoordinates.FromPlant(plants[0]).base_v.size)
        self._noise_rngs = [np.random.default_rng([int(seed), 0xE5, 1]) for seed in seeds]
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
                       q: np.ndarray, qdot: np.ndarray, information: np.ndarray,
                       bias: Optional[np.ndarray] = None) -> None:
        """information[i K + k] += vec(Y^T Y) of draw k of trial i at the state as draw k
        reads it (in place; with noisy sensors its own noise added and ``bias`` walked).

        Args:
            base_pose: Each trial's base pose (trials, base positions).
            base_velocity: Each trial's base velocity (trials, base velocities).
            q: Each trial's joint angles (trials, n) [rad].
            qdot: Each trial's joint rates (trials, n) [rad/s].
            information: The draws' information (members, parameters^2).
            bias: The draws' gyro biases (members, gyro axes) [rad/s] (InitialBias),
                with noisy sensors."""
        K = self.draws
        base_pose, base_velocity, q, qdot = (np.repeat(x, K, axis=0) for x in
                                             (base_pose, base_velocity, q, qdot))
        if self._noise.Any():
            self._AddNoise(base_velocity, q, qdot, bias)
        self._trees.AddInformation(base_pose, base_velocity, q, qdot, information)

    def InitialBias(self) -> np.ndarray:
        """Each draw's own gyro bias at the start (members, gyro axes) [rad/s]: N(0,
        gyro_bias^2) per axis, seeded by the trial's seed."""
        axes = self._rate_columns.stop - self._rate_columns.start
        return np.concatenate([rng.standard_normal((self.draws, axes))
                               for rng in self._noise_rngs]) * self._noise.gyro_bias

    def _AddNoise(self, base_velocity, q, qdot, bias) -> None:
        """Each draw's reading noise on the repeated state (in place); its gyro bias walks
        by gyro_bias_walk sqrt(period) (``bias`` in place)."""
        noise, K = self._noise, self.draws
        n, axes = q.shape[1], bias.shape[1]
        draws = np.concatenate([rng.standard_normal((K, 2 * n + 2 * axes))
                                for rng in self._noise_rngs])
        q += noise.joint_angle * draws[:, :n]
        qdot += noise.joint_rate * draws[:, n:2 * n]
        bias += noise.gyro_bias_walk * np.sqrt(self._period) * draws[:, 2 * n:2 * n + axes]
        base_velocity[:, self._rate_columns] += (bias
                                                 + noise.base_rate * draws[:, 2 * n + axes:])

    def ErrorSd(self, information: np.ndarray, M_hat: np.ndarray, q: np.ndarray,
                noise_information: Optional[np.ndarray] = None, readings: int = 1
                ) -> np.ndarray:
        """E's sd per entry (trials, n, n) at q: the RMS of M_hat M_k^-1 - I over the PD
        draws times Student's factor; nominal_tolerance where there is none.

        Args:
            information: The draws' information (members, p, p), or with exact kinematics
                and noiseless sensors the trials' own (trials, p, p).
            M_hat: Each trial's identified M(q) (trials, n, n).
            q: Each trial's joint angles (trials, n) [rad].
            noise_information: With noisy sensors, each trial's noise information
                (trials, p, p): a draw, which reads the noise twice, is identified from
                its information less twice it (compensated_information).
            readings: The samples the information holds."""
        K, (count, n) = self.draws, q.shape
        if noise_information is not None:
            size = information.shape[-1]
            information = compensated_information(
                information.reshape(count, K, size, size),
                2.0 * noise_information[:, None], readings).reshape(count * K, size, size)
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
    """E = M_hat M~^-1 - I at each sample (T, n, n), which only a simulation knows.

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
