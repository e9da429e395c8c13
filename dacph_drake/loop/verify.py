"""``dacph verify``: the paper's Lyapunov claims checked on a DAC run; ``ok`` is False
when any fails.

1. LHS: V = s^T M s / 2 inside its envelope wherever ||e_tau|| <= chi (lyapunov_envelope);
   with noisy sensors V at the true state, the command's error a bounded input.
2. RHS (rhs_loop): at every learner update, the discrete loop with B_hat, K, h and the
   observer's delay (spectral radius with margin, P > 0, DIC, time-scale separation),
   and with the truth's B~ at every logged sample; with credible intervals, every B of
   the box where an estimate was adopted (kernels.certificate.box_certificate).
3. A region-of-attraction certificate contains s(0) (region_of_attraction)."""
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, List, Optional, Union

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from dacph_drake.analysis.lyapunov_envelope import (  # noqa: E402
    check_envelope, envelope_bounds)
from dacph_drake.analysis.region_of_attraction import REGION_BUDGET  # noqa: E402
from dacph_drake.analysis.rhs_loop import (check_rhs_loop,  # noqa: E402
                                           largest_tolerated_delay)
from dacph_drake.gain_rule import (STABILITY_MARGIN, best_damped_gain,  # noqa: E402
                                   certified_radius, decay_rate, lag_pole,
                                   separates_by_decay)
from dacph_drake.kernels.certificate import box_certificate  # noqa: E402
from dacph_drake.dynamics.model_error import realized_model_error  # noqa: E402
from dacph_drake.dynamics.plant import ArmCoordinates  # noqa: E402
from dacph_drake.robots.robot import Robot  # noqa: E402
from dacph_drake.scenario.errors import ConfigError  # noqa: E402
from dacph_drake.log_layout import RhsLog  # noqa: E402
from dacph_drake.assembly.registry import robot_of  # noqa: E402
from dacph_drake.loop.run_store import load_run  # noqa: E402
from dacph_drake.scenario import Scenario  # noqa: E402


@dataclass
class LoopSeries:
    """Checks of the RHS loop over a run (one row per learner update).

    Attributes:
        time: The checked samples' times [s].
        margin: Each check's margin 1 - spectral radius.
        separation: Each check's sigma_RHS / lambda_LHS.
        failures: The failed checks, as "t = ...: reason".
        failure_times: The failed checks' times [s]."""
    time: List[float] = field(default_factory=list)
    margin: List[float] = field(default_factory=list)
    separation: List[float] = field(default_factory=list)
    failures: List[str] = field(default_factory=list)       # "t = ...: reason"
    failure_times: List[float] = field(default_factory=list)

    def summary(self) -> Dict:
        """{evaluated, ok, min_margin, and the worst sample's time} of the series."""
        if not self.time:
            return {"evaluated": 0, "ok": True, "min_margin": None}
        worst = int(np.argmin(self.margin))
        return {"evaluated": len(self.time), "failed": len(self.failures),
                "ok": not self.failures, "min_margin": self.margin[worst],
                "min_margin_time": self.time[worst],
                "min_separation": float(np.min(self.separation)),
                "first_failure": self.failures[0] if self.failures else "",
                "first_failure_time": self.failure_times[0] if self.failures else None}


def _rhs_series(logs, scenario: Scenario, lambda_lhs: float, B_column: str,
                every: int) -> LoopSeries:
    """check_rhs_loop on every ``every``-th logged sample with the gains K in effect
    and B from logs[B_column] ("estimates": the learner's, scaled as the stress
    setting asks; "true_matrices": the ground truth's)."""
    n = len(scenario.q0)
    t, rhs, R = logs["time"], logs["rhs_log"], RhsLog(n)
    learned = B_column == "estimates"
    # The learner's estimate the gains of sample k were set with: the one the last
    # refresh before it read (a sample's estimate is judged at the next refresh).
    read = _refresh_reads(t, scenario.periods.learner_sample) if learned else None
    series = LoopSeries()
    for k in range(0, len(t), every):
        if learned and rhs[k, R.trusted] < 0.5:
            continue               # the integrator rejected this estimate, kept gains
        B = logs[B_column][k if read is None else read[k], :n * n].reshape(n, n)
        # A logged sample shows the state before the updates at its own time.
        if learned and t[k] > scenario.stress.start:
            B = scenario.stress.B_hat_scale * B
        check = check_rhs_loop(B, rhs[k, R.K], scenario.periods.rhs,
                               lambda_lhs, scenario.rhs.Td,
                               *scenario.sensing.TrueCommandDelay())
        series.time.append(float(t[k]))
        series.margin.append(check.margin)
        series.separation.append(check.separation)
        if not check.ok:
            series.failures.append(f"t = {t[k]:.3f} s: {check.reason}")
            series.failure_times.append(float(t[k]))
    return series


def delay_tolerance(logs: Dict[str, np.ndarray], scenario: Scenario, robot: Robot,
                    lambda_lhs: float, every: int = 1) -> Dict:
    """The largest delay of the RHS loop's command (samples of periods.rhs, and
    seconds) that keeps it stable, and that keeps its certificate, with the run's
    actuator lag, at every ``every``-th logged sample: the least over the run, and when.
    The loop's gain there is the one the integrator meets, (I + E) B~ with the gains K
    in effect: the observer's tau_obs = M_hat qddot + ... is (I + E) times the port's
    torque, E = M_hat M~^-1 - I the LHS model's realized inertia error. Beside: the
    largest delay at which the loop still decays at least at lambda_LHS (-ln(radius) /
    h >= lambda_LHS: the time-scale separation at factor 1; past it the LHS and the RHS
    loop couple through chi, and runs diverge there before the RHS loop alone turns
    unstable: docs/results/sensing.md), and the fastest decay any loop gain gives with
    the run's delay and lag (gain_rule.best_damped_gain) against the separation's
    Td lambda_LHS.

    Args:
        logs: The run's logs.
        scenario: The scenario it ran.
        robot: Its Robot (the model's and the truth's plants).
        lambda_lhs: lambda_LHS [1/s] (eq. 45).
        every: Every how many logged samples to evaluate."""
    n, h = len(scenario.q0), scenario.periods.rhs
    rhs, R = logs["rhs_log"], RhsLog(n)
    delay, lag = scenario.sensing.TrueCommandDelay()
    samples = np.array([k for k in range(0, len(logs["time"]), every)
                        if np.all(np.isfinite(rhs[k, R.K]))])
    pis = logs.get("inertial_parameters")
    pis = (np.tile(robot.model.inertial_parameters, (len(samples), 1)) if pis is None
           else pis[samples])
    joints = ArmCoordinates.FromPlant(robot.model.plant).joint_q
    E = realized_model_error(robot.model.plant, robot.truth_plant, pis,
                             logs["state"][samples][:, joints])
    stable, certified, separated = [], [], []
    separated_radius = float(np.exp(-h * lambda_lhs))
    for k, error in zip(samples, E):
        B = (np.eye(n) + error) @ logs["true_matrices"][k, :n * n].reshape(n, n)
        stable.append(largest_tolerated_delay(B, rhs[k, R.K], h, lag, radius=1.0,
                                              start=delay))
        certified.append(largest_tolerated_delay(B, rhs[k, R.K], h, lag, start=delay))
        separated.append(largest_tolerated_delay(B, rhs[k, R.K], h, lag,
                                                 radius=separated_radius, start=delay))
    worst = int(np.argmin(stable))
    gain, radius = best_damped_gain(h, delay, lag)
    return {"time": float(logs["time"][samples[worst]]), "in_the_run": delay,
            "best_damped_gain": gain, "fastest_decay_rate": decay_rate(radius, h),
            "separation_rate": scenario.rhs.Td * lambda_lhs,
            "actuator_lag": lag, "stable_samples": stable[worst],
            "stable_seconds": stable[worst] * h, "certified_samples": int(min(certified)),
            "certified_seconds": min(certified) * h,
            "separated_samples": int(min(separated)),
            "separated_seconds": min(separated) * h}


def _refresh_reads(t: np.ndarray, period: float) -> np.ndarray:
    """For each logged sample, the sample whose learner output its gains were set with: the
    integrator's last refresh strictly before it (every ``period`` [s]), as a sample logs
    the state before its own instant's discrete updates."""
    refresh = (np.ceil(t / period - 1e-9) - 1.0) * period
    return np.clip(np.searchsorted(t, refresh - 1e-9), 0, len(t) - 1)


def _set_series(logs, scenario: Scenario, lambda_lhs: float) -> Dict:
    """box_certificate on the learner's reported interval of B with the gains in
    effect, at every logged sample whose refresh adopted an estimate; skipped
    (ok) for a learner without intervals."""
    n = len(scenario.q0)
    t, rhs, R = logs["time"], logs["rhs_log"], RhsLog(n)
    if "estimate_bounds" not in logs:
        return {"ok": True, "evaluated": 0, "skipped": "the run logs no intervals"}
    k = n * n + n
    bounds = logs["estimate_bounds"]
    if np.allclose(bounds[:, :n * n], bounds[:, k:k + n * n]):
        return {"ok": True, "evaluated": 0,
                "skipped": "the learner reports no credible set (a point estimate)"}
    adopted = np.flatnonzero(rhs[:, R.trusted] > 0.5)
    h = scenario.periods.rhs
    delay, lag = scenario.sensing.TrueCommandDelay()
    pole = lag_pole(h, lag)
    rate = scenario.rhs.Td * lambda_lhs
    allowed = certified_radius(h, delay, lag)
    by_decay = separates_by_decay(delay, lag)
    read = _refresh_reads(t, scenario.periods.learner_sample)
    failures, worst_separation, worst_radius = [], np.inf, 0.0
    for i in adopted:
        scale = scenario.stress.B_hat_scale if t[i] > scenario.stress.start else 1.0
        j = read[i]
        lower = scale * bounds[j, :n * n].reshape(n, n)
        upper = scale * bounds[j, k:k + n * n].reshape(n, n)
        slowest, radius = box_certificate(lower, upper, rhs[i, R.K], h, delay, pole)
        if by_decay:
            slowest = decay_rate(radius, h)
        worst_separation = min(worst_separation, slowest / lambda_lhs)
        worst_radius = max(worst_radius, radius)
        # 1e-6: the integrator and this check find inf lambda_min(M) of eq. (45)
        # by separate searches; the rate at the set's edge is met to round-off.
        if not (slowest >= rate * (1 - 1e-6) and radius <= allowed):
            failures.append(float(t[i]))
    return {"ok": not failures, "evaluated": int(len(adopted)),
            "failed": len(failures),
            "min_separation": float(worst_separation) if len(adopted) else None,
            "max_spectral_radius": float(worst_radius) if len(adopted) else None,
            "first_failure_time": failures[0] if failures else None}


def verify_logs(logs: Dict[str, np.ndarray], scenario: Scenario, run_meta: Dict,
                out_dir: Optional[Union[str, Path]] = None,
                region_budget: float = REGION_BUDGET) -> Dict:
    """All checks on the logs of a DAC run of ``scenario``: the report (``ok``: verdict).

    Args:
        logs: The run's logs (RunResult.logs).
        scenario: The scenario it ran.
        run_meta: The run's metadata (its "status", "reason", "final_time").
        out_dir: Where verification.{md,json} and the plots go; None: not written.
        region_budget: Wall-time budget [s] of the region-of-attraction search."""
    n = len(scenario.q0)
    robot = robot_of(scenario)
    lhs = robot.task.VerifyLhs(robot, logs, region_budget)
    t, rhs, R = logs["time"], logs["rhs_log"], RhsLog(n)
    e_norm, chi = rhs[:, R.e_norm], rhs[:, R.chi]

    # The learner's excitation tau_pe enters the s dynamics as a known input, and with
    # noisy sensors the command's error as a bounded one (LhsSide.command_error; V
    # then the true state's).
    excitation_norm = float(np.linalg.norm(scenario.excitation.Amplitudes(n)))
    input_bound = excitation_norm + lhs.command_error
    envelope = check_envelope(t, lhs.V, e_norm, chi, lhs.constants,
                              excitation_norm=input_bound)
    per_update = max(1, int(round(scenario.periods.learner / scenario.periods.log)))
    learned = _rhs_series(logs, scenario, lhs.lambda_lhs, "estimates", per_update)
    truth = _rhs_series(logs, scenario, lhs.lambda_lhs, "true_matrices", 1)
    rejected = np.flatnonzero(rhs[:, R.trusted] < 0.5)
    checks = {
        "run_finished": {"ok": run_meta.get("status") == "ok",
                         "status": run_meta.get("status"),
                         "reason": run_meta.get("reason", ""),
                         "final_time": run_meta.get("final_time")},
        "lhs_envelope": envelope.as_dict(),
        "rhs_loop_learned": learned.summary(),
        "rhs_loop_truth": truth.summary(),
        "rhs_loop_credible_set": _set_series(logs, scenario, lhs.lambda_lhs),
        # A region the budget did not allow is reported as skipped, with why.
        "region_of_attraction": {**lhs.region.as_dict(), "s0_norm": lhs.s0_norm,
                                 "ok": bool(lhs.region.skipped)
                                 or lhs.region.Contains(lhs.s0_norm)},
    }
    estimates = {"rejected_samples": int(len(rejected)), "logged_samples": int(len(t)),
                 "first_rejection_time": float(t[rejected[0]]) if len(rejected) else None,
                 "dic_violations": int(np.sum(rhs[:, R.dic_ok] < 0.5))}
    from dacph_drake.loop.metrics import learning_report
    report = {"ok": all(c["ok"] for c in checks.values()), "checks": checks,
              "controller": run_meta.get("controller", "dac"),
              "learning": learning_report(logs, scenario),
              "delay_tolerance": delay_tolerance(logs, scenario, robot, lhs.lambda_lhs,
                                                 per_update),
              "estimates_rejected_by_the_integrator": estimates,
              "settings": {"stability_margin": STABILITY_MARGIN,
                           "certified_radius": certified_radius(
                               scenario.periods.rhs, *scenario.sensing.TrueCommandDelay()),
                           "Td": scenario.rhs.Td,
                           "excitation_norm": excitation_norm,
                           "command_error": lhs.command_error,
                           "lambda_lhs": lhs.lambda_lhs,
                           "rhs_period": scenario.periods.rhs, **lhs.settings}}
    if out_dir is not None:
        _write(report, out_dir, t, lhs.V, e_norm, chi, learned, truth,
               lhs.constants, input_bound)
    return report


def verify_run(run_dir: Union[str, Path], out_dir: Optional[Union[str, Path]] = None,
               controller: str = "dac",
               region_budget: float = REGION_BUDGET) -> Dict:
    """Verifies a saved run against its Lyapunov claims (verify_logs); returns the report.

    Args:
        run_dir: A run directory written by ``dacph simulate`` or ``dacph reproduce``.
        out_dir: Where the report goes; default: run_dir.
        controller: The run to verify: one with the RHS integrator (DAC, its ablation, ...).
        region_budget: Wall-time budget [s] of the region-of-attraction search.

    Raises:
        ConfigError: The run has no RHS loop to verify, or a file is missing."""
    logs, scenario, meta = load_run(run_dir, controller)
    if "rhs_log" not in logs:
        raise ConfigError(f"{run_dir}: the {controller} run has no RHS loop to verify "
                          "(no rhs_log); allowed: the run of a controller with the RHS "
                          "integrator (dac, dac-nominal)")
    return verify_logs(logs, scenario, meta, run_dir if out_dir is None else out_dir,
                       region_budget)


def _write(report, out_dir, t, V, e_norm, chi, learned, truth, constants, input_bound):
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    (out / "verification.json").write_text(json.dumps(report, indent=2))
    lower, upper = envelope_bounds(V, np.diff(t), e_norm, chi, constants, input_bound)
    fig, axes = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
    axes[0].semilogy(t, np.maximum(V, 1e-30), "k-", lw=0.8, label="V = s^T M s / 2")
    axes[0].semilogy(t[1:], np.maximum(upper, 1e-30), "C3--", lw=0.6,
                     label=f"upper bound (rate {constants.rate_slow:.3g} 1/s, "
                           "halved with an input)")
    axes[0].set_ylabel("V [J]")
    axes[0].legend(fontsize=7)
    for series, label, style in [(learned, "loop with learned B_hat", "C0."),
                                 (truth, "loop with true B~", "C1.")]:
        axes[1].plot(series.time, series.margin, style, ms=2, label=label)
    axes[1].axhline(1.0 - report["settings"]["certified_radius"], color="k", ls="--",
                    lw=0.8, label="required margin")
    axes[1].set_ylabel("1 - spectral radius [-]")
    axes[1].set_xlabel("time t [s]")
    axes[1].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out / "verification.png", dpi=120)
    plt.close(fig)
    lines = [f"# Verification: {'PASS' if report['ok'] else 'FAIL'}", ""]
    for name, check in report["checks"].items():
        lines.append(f"## {name}: {'ok' if check['ok'] else 'FAILED'}")
        lines += [_Item(k, v) for k, v in check.items() if k != "ok"]
        lines.append("")
    learning = report["learning"]
    lines.append("## learning, as the robot's data show it (no truth)")
    for phase, entry in learning["phases"].items():
        lines.append(f"- {phase}: " + ", ".join(f"{k} {_Item(k, v)[len(k) + 4:]}"
                                               for k, v in entry.items()))
    lines += [f"- warning: {text}" for text in learning["warnings"]]
    lines.append("")
    lines.append("## estimates rejected by the integrator (DIC or trust band; the "
                 "loop kept its gains)")
    lines += [_Item(k, v) for k, v in report["estimates_rejected_by_the_integrator"].items()]
    lines += ["", "![V and margins](verification.png)"]
    (out / "verification.md").write_text("\n".join(lines) + "\n")


# Units of the report's quantities (verification.json keeps full precision).
_UNITS = {"rate_slow": "1/s", "rate_fast": "1/s", "rate_low": "1/s", "final_time": "s",
          "worst_time": "s", "min_margin_time": "s", "first_failure_time": "s",
          "first_rejection_time": "s", "radius": "rad/s", "frozen_radius": "rad/s",
          "s0_norm": "rad/s",
          "rho": "J", "q": "rad", "fraction_inside": "-", "worst_violation": "-",
          "min_margin": "-", "min_separation": "-", "max_spectral_radius": "-"}


def _Item(key: str, value) -> str:
    """One line of verification.md: 4 significant digits with units; nothing as "none"."""
    if value is None or value == "" or (isinstance(value, float) and value != value):
        return f"- {key}: none"
    if isinstance(value, float):
        value = f"{value:.4g}"
    elif isinstance(value, list) and all(isinstance(v, float) for v in value):
        value = "[" + ", ".join(f"{v:.4g}" for v in value) + "]"
    unit = _UNITS.get(key)
    return f"- {key}: {value}" + (f" {unit}" if unit and unit != "-" else "")
