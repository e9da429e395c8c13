"""The paper's figures as six panels, from the logs of a DAC run
and a model-based run of the same scenario:

(a) uncertainty (= the nominal prior's error), learned estimation error and RHS
    control error (norms)
(b) true, learned and nominal (prior) entries of B~ and D~
(c) zoom on (b) shortly after the nonlinear terms switch on
(d) RHS gains K, c against its lower bound c_min (eq. 48), chi
(e) DAC against model-based: alpha~, ||s||, d(t)
(f) control inputs and states

Each panel is written as PNG and PDF; phases are shaded and labelled as in the
paper, every axis carries its unit."""
from pathlib import Path
from typing import Dict, List

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from dacph_drake.log_layout import LhsLog, RhsLog  # noqa: E402
from dacph_drake.metrics import nominal_estimates  # noqa: E402
from dacph_drake.plant import ArmCoordinates  # noqa: E402
from dacph_drake.scenario import Scenario  # noqa: E402

Logs = Dict[str, np.ndarray]
PANELS = ("a_uncertainty_and_errors", "b_estimated_entries", "c_zoom_nonlinear",
          "d_rhs_gains", "e_dac_vs_model_based", "f_inputs_and_states")
_PHASES = (("linear", "#dbe9f6"), ("nonlinear", "#fde9c9"), ("disturbance", "#f6d5d5"))
_MAX_POINTS = 20000          # per plotted line; longer logs are strided


def _phase_spans(scenario: Scenario):
    p = scenario.phases
    return [("Phase 1: linear", p.linear_start, p.nonlinear_start, _PHASES[0][1]),
            ("Phase 2: + nonlinear", p.nonlinear_start, p.disturbance_start, _PHASES[1][1]),
            ("Phase 3: + disturbance", p.disturbance_start, p.end, _PHASES[2][1])]


def _shade(ax, scenario: Scenario, label: bool, xlim=None) -> None:
    for text, start, end, color in _phase_spans(scenario):
        ax.axvspan(start, end, color=color, alpha=0.6, lw=0, zorder=0)
        if label and (xlim is None or (start < xlim[1] and end > xlim[0])):
            mid = 0.5 * (max(start, xlim[0] if xlim else start)
                         + min(end, xlim[1] if xlim else end))
            ax.text(mid, 1.02, text, transform=ax.get_xaxis_transform(),
                    ha="center", va="bottom", fontsize=8)


def _stride(t: np.ndarray, xlim=None) -> np.ndarray:
    """Indices of at most _MAX_POINTS samples inside xlim."""
    idx = np.arange(len(t)) if xlim is None else np.flatnonzero(
        (t >= xlim[0]) & (t <= xlim[1]))
    return idx[::max(1, len(idx) // _MAX_POINTS)]


def _figure(rows: int, scenario: Scenario, xlim=None):
    fig, axes = plt.subplots(rows, 1, figsize=(9, 2.1 * rows + 0.6), sharex=True,
                             squeeze=False)
    axes = axes[:, 0]
    for i, ax in enumerate(axes):
        _shade(ax, scenario, label=(i == 0), xlim=xlim)
        ax.grid(True, lw=0.3)
    axes[-1].set_xlabel("time t [s]")
    axes[-1].set_xlim(xlim if xlim else (0.0, scenario.phases.end))
    return fig, axes


def _save(fig, out: Path, name: str) -> List[Path]:
    fig.tight_layout()
    paths = [out / f"{name}.png", out / f"{name}.pdf"]
    fig.savefig(paths[0], dpi=130)
    fig.savefig(paths[1])
    plt.close(fig)
    return paths


def _matrix_norms(logs: Logs, n: int, B0, D0):
    """||B~ - B0||_F, ||D~ - D0||, ||B_hat - B~||_F, ||D_hat - D~|| over time."""
    truth, estimate = logs["true_matrices"], logs["estimates"]
    B0 = np.diag(B0).reshape(-1)
    return (np.linalg.norm(truth[:, :n * n] - B0, axis=1),
            np.linalg.norm(truth[:, n * n:] - np.asarray(D0), axis=1),
            np.linalg.norm(estimate[:, :n * n] - truth[:, :n * n], axis=1),
            np.linalg.norm(estimate[:, n * n:] - truth[:, n * n:], axis=1))


def _panel_a(dac: Logs, scenario: Scenario, out: Path):
    n = scenario.robot.num_links
    t = dac["time"]
    i = _stride(t)
    dB, dD, eB, eD = _matrix_norms(dac, n, scenario.uncertainty.B0, scenario.uncertainty.D0)
    fig, (ax1, ax2) = _figure(2, scenario)
    ax1.plot(t[i], dB[i], "C0:", lw=1.2,
             label=r"$\|B_0 - \tilde B\|_F$ (nominal prior = uncertainty)")
    ax1.plot(t[i], dD[i], "C1:", lw=1.2,
             label=r"$\|D_0 - \tilde D\|$ (nominal prior = uncertainty)")
    ax1.plot(t[i], eB[i], "C0-", lw=0.8, label=r"$\|\hat B - \tilde B\|_F$ (learned)")
    ax1.plot(t[i], eD[i], "C1-", lw=0.8, label=r"$\|\hat D - \tilde D\|$ (learned)")
    ax1.set_ylabel("norm [-] / [N m s]")
    ax1.legend(fontsize=7, ncol=2, loc="upper left")
    ax2.semilogy(t[i], np.maximum(dac["rhs_log"][i, RhsLog(n).e_norm], 1e-12), "C3-",
                 lw=0.6)
    ax2.set_ylabel(r"$\|e_\tau\|$ [N m]")
    return _save(fig, out, PANELS[0])


def _entries(dac: Logs, scenario: Scenario, out: Path, name: str, xlim=None):
    n = scenario.robot.num_links
    t = dac["time"]
    i = _stride(t, xlim)
    fig, axes = _figure(2, scenario, xlim)
    labels = [(r"$B_{%d%d}$" % (r + 1, c + 1), r * n + c) for r in range(n)
              for c in range(n)]
    labels += [(r"$D_{%d%d}$" % (k + 1, k + 1), n * n + k) for k in range(n)]
    prior = nominal_estimates(scenario)
    for ax, group, unit in [(axes[0], labels[:n * n], "[-]"),
                            (axes[1], labels[n * n:], "[N m s]")]:
        for color, (label, col) in enumerate(group):
            ax.plot(t[i], dac["true_matrices"][i, col], color=f"C{color}", lw=1.2,
                    label=f"true {label}")
            ax.plot(t[i], dac["estimates"][i, col], color=f"C{color}", lw=0.8, ls="--",
                    label=f"learned {label}")
            ax.axhline(prior[col], color=f"C{color}", lw=0.8, ls=":",
                       label=f"nominal {label}")
        ax.set_ylabel(f"entries of {'B' if unit == '[-]' else 'D'} {unit}")
        ax.legend(fontsize=7, ncol=3 * n, loc="upper left")
    return _save(fig, out, name)


def _panel_d(dac: Logs, scenario: Scenario, out: Path):
    n = scenario.robot.num_links
    t, rhs, R = dac["time"], dac["rhs_log"], RhsLog(n)
    i = _stride(t)
    fig, (ax1, ax2, ax3) = _figure(3, scenario)
    for k in range(n):
        ax1.plot(t[i], rhs[i, R.K][:, k], lw=0.8, label=f"$k_{k + 1}$")
    ax1.set_ylabel(r"gains $k_p$ [1/s]")
    ax1.legend(fontsize=7)
    ax2.plot(t[i], rhs[i, R.c], "C0-", lw=1, label="c")
    ax2.plot(t[i], rhs[i, R.c_min], "k--", lw=1, label=r"$c_{min}$ (eq. 48)")
    ax2.set_ylabel("c [1/s]")
    ax2.legend(fontsize=7)
    ax3.semilogy(t[i], rhs[i, R.chi], "C2-", lw=0.8)
    ax3.set_ylabel(r"$\chi$ [N m]")
    return _save(fig, out, PANELS[3])


def _panel_e(dac: Logs, model_based: Logs, scenario: Scenario, out: Path):
    n = scenario.robot.num_links
    fig, (ax1, ax2, ax3) = _figure(3, scenario)
    for logs, label, style in [(model_based, "model-based", "C1-"), (dac, "DAC-pH", "C0-")]:
        t = logs["time"]
        i = _stride(t)
        ax1.plot(t[i], logs["lhs_log"][i, LhsLog(n).alpha_error], style, lw=0.7,
                 label=label)
        ax2.plot(t[i], np.linalg.norm(logs["lhs_log"][i, LhsLog(n).s], axis=1), style,
                 lw=0.7,
                 label=label)
    ax1.set_ylabel(r"$\tilde\alpha$ [rad]")
    ax1.legend(fontsize=7)
    ax2.set_ylabel(r"$\|s\|$ [rad/s]")
    t = dac["time"]
    i = _stride(t)
    for k in range(n):
        ax3.plot(t[i], dac["disturbance"][i, k], lw=0.5, label=f"$d_{k + 1}$")
    ax3.set_ylabel("d(t) [N m]")
    ax3.legend(fontsize=7)
    return _save(fig, out, PANELS[4])


def _panel_f(dac: Logs, model_based: Logs, scenario: Scenario, out: Path):
    n = scenario.robot.num_links
    fig, (ax1, ax2, ax3) = _figure(3, scenario)
    for logs, label, ls in [(model_based, "model-based", ":"), (dac, "DAC-pH", "-")]:
        t = logs["time"]
        i = _stride(t)
        for k in range(n):
            ax1.plot(t[i], logs["u"][i, k], color=f"C{k}", ls=ls, lw=0.6,
                     label=f"$u_{k + 1}$ {label}")
    ax1.set_ylabel("u [N m]")
    ax1.legend(fontsize=7, ncol=2)
    t = dac["time"]
    base_pose, q, _, qdot = ArmCoordinates.ForPlanarArm(n).Split(dac["state"])
    i = _stride(t)
    ax2.plot(t[i], base_pose[i, 2], "k-", lw=0.8, label=r"$\theta_0$ (base)")
    for k in range(n):
        ax2.plot(t[i], q[i, k], color=f"C{k}", lw=0.8, label=f"$q_{k + 1}$")
    ax2.plot(t[i], dac["lhs_log"][i, LhsLog(n).alpha_desired], "C3--", lw=0.8,
             label=r"$\alpha_d$")
    ax2.set_ylabel("angles [rad]")
    ax2.legend(fontsize=7, ncol=n + 2)
    for k in range(n):
        ax3.plot(t[i], qdot[i, k], color=f"C{k}", lw=0.6,
                 label=r"$\dot q_{%d}$" % (k + 1))
    ax3.set_ylabel("joint rates [rad/s]")
    ax3.legend(fontsize=7)
    return _save(fig, out, PANELS[5])


def zoom_window(scenario: Scenario):
    """(c)'s window: from shortly before the nonlinear terms switch on to a twelfth
    of phase 2 after (40 s of the paper's 480 s phase)."""
    start, length = scenario.phases.nonlinear_start, scenario.phases.nonlinear
    return (start - length / 48, start + length / 12)


def plot_panels(dac: Logs, model_based: Logs, scenario: Scenario, out_dir) -> List[Path]:
    """Writes the six panels (PNG and PDF) into out_dir; returns their paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    return (_panel_a(dac, scenario, out)
            + _entries(dac, scenario, out, PANELS[1])
            + _entries(dac, scenario, out, PANELS[2], zoom_window(scenario))
            + _panel_d(dac, scenario, out)
            + _panel_e(dac, model_based, scenario, out)
            + _panel_f(dac, model_based, scenario, out))
