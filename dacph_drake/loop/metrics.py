"""The metrics of a run (the paper's reported quantities and this project's,
docs/results/paper.md), computed from its logs."""
from dataclasses import dataclass
from typing import Dict, Optional, Tuple

import numpy as np

from dacph_drake.analysis.phases import (PHASES, phase_windows,  # noqa: F401
                                         relative_error_rms, rms)
from dacph_drake.dynamics.model_error import realized_model_error
from dacph_drake.dynamics.plant import ArmCoordinates
from dacph_drake.log_layout import LearnerLog, RhsLog
from dacph_drake.assembly.registry import robot_of
from dacph_drake.robots.robot import Robot
from dacph_drake.scenario import Scenario


FAULT_WINDOW = 2.0      # [s] before and after an actuator fault (run_metrics)


def nominal_estimates(scenario: Scenario) -> np.ndarray:
    """The prior (B0, D0) laid out as the ``estimates`` log: [vec(B0), diag(D0)].

    Args:
        scenario: The scenario (its uncertainty's B0 and D0).

    Returns:
        [vec(B0), diag(D0)] (n * n + n)."""
    return np.concatenate([np.diag(scenario.uncertainty.B0).reshape(-1),
                           scenario.uncertainty.D0])


def identified_scale(logs: Dict[str, np.ndarray], total_mass: float) -> np.ndarray:
    """k(t): the identified bodies' total mass over the true robot's, the common factor
    momentum data leave to the prior (1 without an identifier).

    Args:
        logs: The run's logs (RunResult.logs).
        total_mass: The true robot's total mass [kg].

    Returns:
        k at every logged sample (T)."""
    from dacph_drake.dynamics.inertial_parameters import MASS, PER_BODY
    if "inertial_parameters" not in logs:
        return np.ones(len(logs["time"]))
    return logs["inertial_parameters"][:, MASS::PER_BODY].sum(axis=1) / total_mass


def physical_view(logs: Dict[str, np.ndarray], scenario: Scenario
                  ) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The learned estimates as claims about the physical B~, D~, with their intervals: the
    logged ``estimates`` and ``estimate_bounds`` widened by the LHS model's inertia error E
    (learning.local_bayes.physical_claims; E's sd from model_error_sd); the prior and its
    range where LearnerLog.physical says the port is not in physical units.

    Args:
        logs: The run's logs.
        scenario: The scenario it ran.

    Returns:
        (estimate, lower, upper), each [vec(B), diag(D)] per sample (T x (n^2 + n))."""
    from dacph_drake.learning.local_bayes import physical_claims, prior_range
    n = len(scenario.q0)
    k = n * n + n
    bayes, u = scenario.learner.bayes, scenario.uncertainty
    point = logs["estimates"]
    bounds = logs.get("estimate_bounds", np.concatenate([point, point], axis=1))
    estimate, lower, upper = physical_claims(point, bounds[:, :k], bounds[:, k:], bayes,
                                             u.B0, u.D0, model_error_sd(logs, scenario))
    learner = logs.get("learner_log")
    if learner is None or learner.shape[1] <= LearnerLog().physical:
        return estimate, lower, upper
    physical = (learner[:, LearnerLog().physical] > 0.5)[:, None]
    prior_low, prior_high = prior_range(bayes, u.B0, u.D0)
    return (np.where(physical, estimate, nominal_estimates(scenario)[None, :]),
            np.where(physical, lower, prior_low[None, :]),
            np.where(physical, upper, prior_high[None, :]))


def model_error_sd(logs: Dict[str, np.ndarray], scenario: Scenario) -> np.ndarray:
    """E's sd per entry at every logged sample (T, n, n): the ``model_error`` log, else
    dynamics.model_error.stated_model_error (0 for a run saved before E was measured).

    Args:
        logs: The run's logs.
        scenario: The scenario it ran."""
    from dacph_drake.dynamics.model_error import stated_model_error
    n, T = len(scenario.q0), len(logs["time"])
    if "model_error" in logs:
        return logs["model_error"].reshape(T, n, n)
    stated = stated_model_error(scenario.inertia, "inertial_parameters" in logs)
    return np.full((T, n, n), stated)


def learning_metrics(logs: Dict[str, np.ndarray], scenario: Scenario,
                     mask: np.ndarray, total_mass: float,
                     realized_error: Optional[np.ndarray] = None) -> Dict[str, float]:
    """Learning's own value over the samples ``mask``: the time-RMS relative errors
    ||X_hat - X~|| / ||X~|| of the claims about B and D (physical_view) and of the prior,
    their ratio (below 1: learning beats the prior), interval_metrics, the share of B_hat
    the RHS integrator rejected, and the share with beta_hat > rhs.beta_max. With an
    inertial identifier also the identified scale k (mean) and ``*_error_ratio_scaled``
    against k B~, k D~.

    Args:
        logs: The run's logs (RunResult.logs).
        scenario: The scenario it ran.
        mask: The samples to average over (boolean, T).
        total_mass: The ground truth's total mass [kg].
        realized_error: The run's true E (T, n, n), simulation only (model_error_metrics).

    Returns:
        Metric name -> value."""
    n = len(scenario.q0)
    view = physical_view(logs, scenario)
    truth, estimate = logs["true_matrices"][mask], view[0][mask]
    prior = np.tile(nominal_estimates(scenario), (len(truth), 1))
    out = {}
    for name, columns in (("B", slice(0, n * n)), ("D", slice(n * n, n * n + n))):
        learned = relative_error_rms(estimate[:, columns], truth[:, columns])
        nominal = relative_error_rms(prior[:, columns], truth[:, columns])
        out.update({f"{name}_error": learned, f"{name}_error_nominal": nominal,
                    f"{name}_error_ratio": learned / nominal if nominal > 0
                    else float("nan")})
    if "inertial_parameters" in logs:
        # The identified model is k times the truth's at best (momentum data do not
        # fix the common scale), so the observer's port, and what the learner
        # learns, is k (B~ u - D~ qdot): the errors against k B~, k D~ too.
        scale = identified_scale(logs, total_mass)[mask][:, None]
        out["identified_scale"] = float(np.mean(scale)) if len(scale) else float("nan")
        published = logs["estimates"][mask]        # the port as the model sees it
        for name, columns in (("B", slice(0, n * n)), ("D", slice(n * n, n * n + n))):
            learned = relative_error_rms(published[:, columns], scale * truth[:, columns])
            nominal = relative_error_rms(prior[:, columns], scale * truth[:, columns])
            out[f"{name}_error_ratio_scaled"] = (learned / nominal if nominal > 0
                                                 else float("nan"))
    out.update(interval_metrics(view, truth, nominal_estimates(scenario), n, mask))
    if realized_error is not None:
        out.update(model_error_metrics(logs, scenario, mask, realized_error))
    learner, layout = logs["learner_log"], LearnerLog()
    learned = mask & (learner[:, layout.holding] < 0.5)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = learner[learned, layout.loss] / learner[learned, layout.nominal_loss]
    ratio = ratio[np.isfinite(ratio)]
    out["residual_ratio"] = float(np.sqrt(np.median(ratio))) if len(ratio) else 1.0
    trusted = logs["rhs_log"][mask, RhsLog(n).trusted]
    out["rejected_share"] = float(np.mean(trusted < 0.5)) if len(trusted) else float("nan")
    beta_hat = logs["learner_log"][mask, LearnerLog().beta_hat]
    out["beta_clipped_share"] = (float(np.mean(beta_hat > scenario.rhs.beta_max))
                                 if len(beta_hat) else float("nan"))
    return out


def port_truth(true_matrices: np.ndarray, realized_error: np.ndarray) -> np.ndarray:
    """The port's own truth, what a perfect learner publishes through the LHS model:
    [vec((I + E) B~), diag((I + E) D~)] per sample (T, n^2 + n).

    Args:
        true_matrices: The true [vec(B~), diag(D~)] per sample (T, n^2 + n).
        realized_error: The run's true E per sample (T, n, n)."""
    n = realized_error.shape[1]
    port = np.eye(n) + realized_error
    B = port @ true_matrices[:, :n * n].reshape(-1, n, n)
    D = np.einsum("tii->ti", port * true_matrices[:, None, n * n:])
    return np.concatenate([B.reshape(-1, n * n), D], axis=1)


def realized_error_of(logs: Dict[str, np.ndarray], robot: Robot) -> np.ndarray:
    """The run's true E per sample (realized_model_error), with the identified parameters.

    Args:
        logs: The run's logs.
        robot: Its robots.Robot."""
    t = logs["time"]
    pis = logs.get("inertial_parameters")
    if pis is None:
        pis = np.tile(robot.model.inertial_parameters, (len(t), 1))
    joints = ArmCoordinates.FromPlant(robot.model.plant).joint_q
    return realized_model_error(robot.model.plant, robot.truth_plant, pis,
                                logs["state"][:, joints])


def model_error_metrics(logs: Dict[str, np.ndarray], scenario: Scenario,
                        mask: np.ndarray, realized_error: np.ndarray) -> Dict[str, float]:
    """The measured LHS model inertia error E against the true one over ``mask``:
    ``model_error_sd`` (median of E's largest measured sd), ``model_error_realized``
    (median of the true E's largest entry), ``model_error_coverage`` (share of true E_ij
    within the claims' z sd) and ``X_port_error_ratio`` (X in B, D: the port model's error
    against (I + E) B~, diag((I + E) D~), over the prior's).

    Args:
        logs: The run's logs.
        scenario: The scenario it ran.
        mask: The samples to average over.
        realized_error: The run's true E at every sample (T, n, n)."""
    from statistics import NormalDist
    n = len(scenario.q0)
    z = NormalDist().inv_cdf(0.5 + 0.5 * scenario.learner.bayes.credible_level)
    sd = np.sqrt(model_error_sd(logs, scenario)[mask] ** 2
                 + scenario.learner.bayes.model_error ** 2)
    E = realized_error[mask]
    if not len(E):
        return {name: float("nan") for name in (
            "model_error_sd", "model_error_realized", "model_error_coverage",
            "B_port_error_ratio", "D_port_error_ratio")}
    out = {"model_error_sd": float(np.median(np.max(sd, axis=(1, 2)))),
           "model_error_realized": float(np.median(np.max(np.abs(E), axis=(1, 2)))),
           # 1e-6: E's round-off (the identified model explains the momentum to
           # about 1e-9) is no miss of an interval of sd 0.
           "model_error_coverage": float(np.mean(np.abs(E) <= z * sd + 1e-6))}
    truth = port_truth(logs["true_matrices"][mask], E)
    published = logs["estimates"][mask]
    prior = nominal_estimates(scenario)[None, :]
    for name, columns in (("B", slice(0, n * n)), ("D", slice(n * n, n * n + n))):
        learned = relative_error_rms(published[:, columns], truth[:, columns])
        nominal = relative_error_rms(np.broadcast_to(prior[:, columns],
                                                     truth[:, columns].shape),
                                     truth[:, columns])
        out[f"{name}_port_error_ratio"] = learned / nominal if nominal > 0 else float("nan")
    return out


def interval_metrics(view: Tuple[np.ndarray, np.ndarray, np.ndarray],
                     truth: np.ndarray, prior: np.ndarray, n: int, mask: np.ndarray
                     ) -> Dict[str, float]:
    """How the claimed intervals about B~ and D~ hold the truth over ``mask``, for X in (B,
    D): ``X_coverage`` (share of entries inside), ``X_interval`` (time-RMS Frobenius
    half-width over ||X_hat||), ``X_interval_ratio`` (median half-width over the prior's
    error), and ``undetermined_share`` (share claimed at the prior).

    Args:
        view: physical_view's (estimate, lower, upper), all samples.
        truth: The true [vec(B~), diag(D~)] over the samples ``mask``.
        prior: [vec(B0), diag(D0)].
        n: The number of joints.
        mask: The samples to average over (boolean, T).

    Returns:
        Metric name -> value (nan over no samples)."""
    estimate, lower, upper = (x[mask] for x in view)
    k = n * n + n
    out = {}
    for name, columns in (("B", slice(0, n * n)), ("D", slice(n * n, k))):
        if not len(truth):
            out.update({f"{name}_coverage": float("nan"), f"{name}_interval": float("nan"),
                        f"{name}_interval_ratio": float("nan")})
            continue
        inside = ((lower[:, columns] - 1e-12 <= truth[:, columns])
                  & (truth[:, columns] <= upper[:, columns] + 1e-12))
        half = np.linalg.norm(0.5 * (upper[:, columns] - lower[:, columns]), axis=1)
        prior_error = np.linalg.norm(prior[columns][None, :] - truth[:, columns], axis=1)
        out[f"{name}_coverage"] = float(np.mean(inside))
        out[f"{name}_interval"] = relative_half_width(view, mask, columns)
        with np.errstate(divide="ignore", invalid="ignore"):
            out[f"{name}_interval_ratio"] = float(np.median(half / prior_error))
    out["undetermined_share"] = (float(np.mean(estimate == prior[None, :]))
                                 if len(truth) else float("nan"))
    return out


def relative_half_width(view: Tuple[np.ndarray, np.ndarray, np.ndarray],
                        mask: np.ndarray, columns: slice) -> float:
    """The time-RMS over ``mask`` of the intervals' Frobenius half-width over ||estimate||.

    Args:
        view: The claimed (estimate, lower, upper) (physical_view).
        mask: The samples to average over.
        columns: The entries (B's or D's columns of the view).

    Returns:
        The RMS relative half-width."""
    estimate, lower, upper = (x[mask][:, columns] for x in view)
    half = np.linalg.norm(0.5 * (upper - lower), axis=1)
    return rms(half / np.maximum(np.linalg.norm(estimate, axis=1), 1e-300))


# The joint-rate noise [rad/s per sample] above which the paper's arm's learner leaves
# most quantities at the prior (measured: docs/results/sensing.md).
RATE_NOISE_LIMIT = 1e-5


def _rate_noise_note(scenario: Scenario, undetermined: float) -> str:
    """Why most quantities may have stayed at the prior: the sensors' joint-rate noise,
    which the port observer differentiates ("" when it is not the likely cause)."""
    sensing = scenario.sensing
    rate_noise = sensing.rate_noise
    if not (sensing.enabled and sensing.rate_source == "tachometer"
            and undetermined >= 0.9 and rate_noise > RATE_NOISE_LIMIT):
        return ""
    return (f"{100 * undetermined:.0f} % of the quantities stayed at the prior with the "
            f"sensors' joint-rate noise {rate_noise:.2g} rad/s per sample, which the port "
            f"observer differentiates (sqrt(2) sd / h = "
            f"{np.sqrt(2) * rate_noise / scenario.periods.rhs:.3g} rad/s^2 of noise on "
            f"its acceleration): above {RATE_NOISE_LIMIT:g} rad/s the noise, not the "
            "excitation, is what keeps them undetermined (docs/results/sensing.md)")


def learning_report(logs: Dict[str, np.ndarray], scenario: Scenario) -> Dict:
    """What a real robot's user sees of the learning, without the truth, per phase:
    ``residual_ratio`` (sqrt of the median of the learner's loss over its nominal loss where
    it determined something; below 1: the learned model explains the port better),
    ``undetermined_share``, ``interval`` and ``model_error_sd``; and warnings for a phase
    not beating the prior, one where nothing was determined, a kinematic mismatch.

    Args:
        logs: A DAC run's logs (learner_log; estimate_bounds where reported).
        scenario: The scenario it ran.

    Returns:
        {"phases": {phase: {residual_ratio, undetermined_share, interval,
        model_error_sd}}, "warnings": [str]}."""
    t, learner = logs["time"], logs["learner_log"]
    layout = LearnerLog()
    view = physical_view(logs, scenario)
    prior = nominal_estimates(scenario)[None, :]
    phases, warnings = {}, []
    for phase, mask in phase_windows(scenario, t).items():
        if not mask.any():
            continue
        learned = mask & (learner[:, layout.holding] < 0.5)
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = learner[learned, layout.loss] / learner[learned, layout.nominal_loss]
        finite = ratio[np.isfinite(ratio)]
        residual = float(np.sqrt(np.median(finite))) if len(finite) else float("nan")
        undetermined = float(np.mean(view[0][mask] == prior))
        entry = {"residual_ratio": residual, "undetermined_share": undetermined}
        entry["interval"] = relative_half_width(view, mask,
                                                slice(0, len(scenario.q0) ** 2))
        error_sd = np.sqrt(model_error_sd(logs, scenario)[mask] ** 2
                           + scenario.learner.bayes.model_error ** 2)
        entry["model_error_sd"] = float(np.median(np.max(error_sd, axis=(1, 2))))
        phases[phase] = entry
        noise = _rate_noise_note(scenario, undetermined)
        if noise:
            warnings.append(f"{phase}: {noise}")
        if not len(finite):
            warnings.append(f"{phase}: the data determined no quantity; the prior "
                            "(B0, D0) stood throughout")
        elif residual >= 1.0:
            warnings.append(f"{phase}: the learned model explains the port no better "
                            f"than the prior (residual ratio {residual:.3g})")
    physical = learner[:, layout.physical] if learner.shape[1] > layout.physical else None
    if physical is not None and np.any(physical < 0.5):
        first = float(t[np.argmax(physical < 0.5)])
        warnings.append(f"the inertial identifier reported the controller's kinematics "
                        f"mismatched at t = {first:.2f} s: the learned B and D are the "
                        "port as the model sees it, not the robot's")
    return {"phases": phases, "warnings": warnings}


def run_metrics(logs: Dict[str, np.ndarray], scenario: Scenario) -> Dict[str, float]:
    """A run's metrics, over phases 1-3 (t >= end of warm-up) unless named "phaseK.NAME"
    (phase K only: 1 linear, 2 + nonlinear, 3 + disturbance) or "faultK.NAME" (the RMS
    tracking error FAULT_WINDOW s before and after the K-th actuator fault, and their
    ratio). The tracking error is the robot's (robots.Robot.TaskSignals, TaskMetrics).

    Args:
        logs: The run's logs (RunResult.logs).
        scenario: The scenario it ran.

    Returns:
        Metric name -> value; nan for a phase the run did not reach."""
    with np.errstate(invalid="ignore"):        # a phase not reached: nan
        return _RunMetrics(logs, scenario, robot_of(scenario))


def _RunMetrics(logs, scenario, robot) -> Dict[str, float]:
    n = len(scenario.q0)
    t = logs["time"]
    phases = scenario.phases
    active = t >= phases.linear_start
    phase3 = t >= scenario.disturbance_start
    R = RhsLog(n)
    alpha_error, sliding, clearance, base_turn = robot.task.Signals(robot, logs)
    total_mass = robot.MeasuredMasses()[0]
    e_tau = (logs["rhs_log"][:, R.e_tau] if "rhs_log" in logs
             else logs["tau_request"] - logs["tau"])
    out = {
        "tracking_error_rms": rms(alpha_error[active]),
        "tracking_error_rms_phase3": rms(alpha_error[phase3]),
        # Phases 2 and 3: after the start-up transient that dominates phase 1 (and
        # is the same with or without learning, which starts in phase 1).
        "tracking_error_rms_phases_2_3": rms(alpha_error[t >= phases.nonlinear_start]),
        "tracking_error_max": float(np.max(np.abs(alpha_error[active])))
        if active.any() else float("nan"),
        "control_effort_rms": rms(logs["u"][active]),
        "e_tau_rms": rms(e_tau[active]),
        "sliding_rms": rms(sliding[active]),
        "base_attitude_max_excursion": float(np.max(np.abs(base_turn))),
        "min_clearance": float(np.min(clearance)),
    }
    realized_error = None
    if "estimates" in logs:
        realized_error = realized_error_of(logs, robot)
        window = (t >= max(phases.nonlinear_start, phases.disturbance_start - 60.0)) & \
                 (t < phases.disturbance_start)
        truth = logs["true_matrices"][window]
        estimate = physical_view(logs, scenario)[0][window]
        out["estimation_error_B"] = relative_error_rms(estimate[:, :n * n], truth[:, :n * n])
        out["estimation_error_D"] = relative_error_rms(estimate[:, n * n:], truth[:, n * n:])
        rhs = logs["rhs_log"]
        out["c_min_over_bound"] = float(np.min(rhs[:, R.c] / rhs[:, R.c_min]))
        out["chi_final"] = float(rhs[-1, R.chi])
        out["dic_violations"] = int(np.sum(rhs[:, R.dic_ok] < 0.5))
        out["rejected_estimates"] = int(np.sum(rhs[:, R.trusted] < 0.5))
    for i, fault in enumerate(scenario.uncertainty.faults):
        # The first 2 s after an actuator fault against the 2 s before it.
        before = (t >= fault.time - FAULT_WINDOW) & (t < fault.time)
        after = (t >= fault.time) & (t < fault.time + FAULT_WINDOW)
        out[f"fault{i + 1}.tracking_error_rms_before"] = rms(alpha_error[before])
        out[f"fault{i + 1}.tracking_error_rms_after"] = rms(alpha_error[after])
        out[f"fault{i + 1}.tracking_error_ratio"] = (
            rms(alpha_error[after]) / rms(alpha_error[before])
            if before.any() and after.any() else float("nan"))
    for phase, mask in phase_windows(scenario, t).items():
        out[f"{phase}.tracking_error_rms"] = rms(alpha_error[mask])
        out[f"{phase}.e_tau_rms"] = rms(e_tau[mask])
        if "estimates" in logs:
            out[f"{phase}.chi_rms"] = rms(logs["rhs_log"][mask, R.chi])
            out.update({f"{phase}.{k}": v for k, v in learning_metrics(
                logs, scenario, mask, total_mass, realized_error).items()})
    if "identification_log" in logs and len(t):
        identified = logs["identification_log"]
        out["identified_mass_error"] = float(identified[-1, 0] / total_mass - 1.0)
        out["momentum_misfit"] = float(identified[-1, 1])
        out["kinematic_mismatch"] = float(identified[-1, 2])
    out.update(robot.task.Metrics(robot, logs))
    return out


def comparison(dac: Dict[str, float], model_based: Dict[str, float]) -> Dict[str, float]:
    """The paper's headline numbers: tracking-error reduction 1 - e_DAC / e_MB and
    control-effort increase effort_DAC / effort_MB - 1.

    Args:
        dac: The DAC run's metrics (run_metrics).
        model_based: The model-based run's metrics (run_metrics).

    Returns:
        Metric name -> value."""
    return {
        "tracking_error_reduction": 1 - dac["tracking_error_rms"]
        / model_based["tracking_error_rms"],
        "tracking_error_reduction_phase3": 1 - dac["tracking_error_rms_phase3"]
        / model_based["tracking_error_rms_phase3"],
        "control_effort_increase": dac["control_effort_rms"]
        / model_based["control_effort_rms"] - 1,
    }


# The scenario's phase (scenario.Phases' field) of each "phaseK." metric.
PHASE_NAMES = {"phase1": "linear", "phase2": "nonlinear", "phase3": "disturbance"}
# The metrics' units; every other metric is a ratio, a share or a count. The tracking
# error's unit is the task's (rad for the shipped tasks' angle and attitude errors).
UNITS = {"tracking_error_rms": "rad", "tracking_error_max": "rad",
         "tracking_error_rms_phase3": "rad", "tracking_error_rms_phases_2_3": "rad",
         "tracking_error_rms_before": "rad", "tracking_error_rms_after": "rad",
         "position_error_rms": "m", "attitude_error_final": "rad",
         "attitude_error_rms_settled": "rad", "attitude_error_max_settled": "rad",
         "control_effort_rms": "N m", "e_tau_rms": "N m", "chi_rms": "N m",
         "chi_final": "N m", "sliding_rms": "rad/s", "min_clearance": "m",
         "base_attitude_max_excursion": "rad", "max_momentum": "kg m^2/s",
         "momentum_misfit": "kg m^2/s"}


@dataclass
class RunMetrics:
    """A run's metrics as a typed record, per phase, with units (flat names: ``flat``).

    Attributes:
        run: Metric -> value over phases 1-3 (and the fault windows).
        phases: Phase (linear, nonlinear, disturbance) -> metric -> value.
        units: Metric -> unit ("" for ratios, shares and counts)."""
    run: Dict[str, float]
    phases: Dict[str, Dict[str, float]]
    units: Dict[str, str]

    @classmethod
    def Of(cls, logs: Dict[str, np.ndarray], scenario: Scenario) -> "RunMetrics":
        """The record of run_metrics(logs, scenario).

        Args:
            logs: The run's logs.
            scenario: The scenario it ran."""
        return cls.FromFlat(run_metrics(logs, scenario))

    @classmethod
    def FromFlat(cls, flat: Dict[str, float]) -> "RunMetrics":
        """The record of run_metrics' flat names ("phaseK.NAME" into phases).

        Args:
            flat: run_metrics' dictionary."""
        run, phases = {}, {name: {} for name in PHASE_NAMES.values()}
        for key, value in flat.items():
            head, _, name = key.partition(".")
            if head in PHASE_NAMES:
                phases[PHASE_NAMES[head]][name] = value
            else:
                run[key] = value
        names = {key.rpartition(".")[2] for key in flat}
        return cls(run=run, phases=phases,
                   units={name: UNITS.get(name, "") for name in sorted(names)})

    @property
    def flat(self) -> Dict[str, float]:
        """run_metrics' flat dictionary."""
        phase_keys = {name: key for key, name in PHASE_NAMES.items()}
        return {**self.run, **{f"{phase_keys[phase]}.{name}": value
                               for phase, values in self.phases.items()
                               for name, value in values.items()}}
