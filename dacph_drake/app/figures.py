"""The paper's figures as six panels, from the logs of one scenario's runs:

(a) uncertainty (the prior's error) against the learned estimation error, and the RHS
    control error (norms, log axes)
(b) true, learned and prior value of every entry of B~ and D~, one axis per entry
(c) zoom on (b) shortly after the nonlinear terms switch on
(d) RHS gains K, c against its lower bound c_min (eq. 48), chi
(e) every run: |alpha~| and ||s|| (log axes), d(t)
(f) control inputs (DAC, and the model-based input's difference from it) and states

(a)-(d) are DAC's (else the first run with a learner); (e) and (f) are the task's
(tasks.task.Task.panels): a described arm's (e) shows |e| (pose: and |e_p|), ||s||, the
smallest link-base distance and d(t), its (f) u and the joints. Panels are PNG and PDF;
a series with more samples than pixel columns is drawn as its min/max envelope."""
from pathlib import Path
from typing import Dict, List, Sequence, Tuple, Union

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.patches import Patch  # noqa: E402

from dacph_drake.controllers import BASELINE, REFERENCE, REGISTRY  # noqa: E402
from dacph_drake.log_layout import LhsLog, RhsLog  # noqa: E402
from dacph_drake.robots.start_pose import ATTITUDE_ROWS, POSITION_ROWS  # noqa: E402
from dacph_drake.loop.metrics import (nominal_estimates, physical_view,  # noqa: E402
                                          port_truth, realized_error_of)
from dacph_drake.dynamics.plant import ArmCoordinates  # noqa: E402
from dacph_drake.assembly.registry import robot_of, task_of  # noqa: E402
from dacph_drake.scenario import Scenario  # noqa: E402

Logs = Dict[str, np.ndarray]
DAC_PANELS = ("a_uncertainty_and_errors", "b_estimated_entries", "c_zoom_nonlinear",
              "d_rhs_gains")
# The port model the loop closes on against its own truth, for a run whose LHS model
# error was measured (its ``model_error`` log).
PORT_PANEL = "g_port_entries"
WIDTH, DPI = 11.0, 130          # [in], PNG dots per inch
COLUMNS = 1000                  # envelope columns per axis (about one per pixel)
LOG_DECADES = 7                 # a log axis spans at most this many decades
ENTRY_STYLES = {"true": dict(color="k", ls="-", lw=1.0),
                "learned": dict(color="C0", ls="--", lw=1.0),
                "nominal": dict(color="0.55", ls=":", lw=1.2)}


def _phase_spans(scenario: Scenario):
    p = scenario.phases
    return [("Warm-up: B0, D0", 0.0, p.linear_start, "#ececec"),
            ("Phase 1: linear", p.linear_start, p.nonlinear_start, "#dbe9f6"),
            ("Phase 2: + nonlinear", p.nonlinear_start, p.disturbance_start, "#fde9c9"),
            ("Phase 3: + disturbance", p.disturbance_start, p.end, "#f6d5d5")]


def _shade(ax, scenario: Scenario, xlim, label: bool) -> None:
    """Shades warm-up and phases; with ``label``, names each visible one above ax."""
    for text, start, end, color in _phase_spans(scenario):
        if end <= start:
            continue
        ax.axvspan(start, end, color=color, alpha=0.6, lw=0, zorder=0)
        visible = (max(start, xlim[0]), min(end, xlim[1]))
        if not label or visible[1] <= visible[0]:
            continue
        if visible[1] - visible[0] > 0.15 * (xlim[1] - xlim[0]):
            ax.text(0.5 * sum(visible), 1.02, text, transform=ax.get_xaxis_transform(),
                    ha="center", va="bottom", fontsize=8)
        else:           # a narrow span (the paper's warm-up): its short name, from its start
            ax.text(visible[0], 1.02, text.split(":")[0], ha="left", va="bottom",
                    transform=ax.get_xaxis_transform(), fontsize=8)


def _phase_handles(scenario: Scenario) -> List[Patch]:
    return [Patch(color=color, alpha=0.6, label=text)
            for text, start, end, color in _phase_spans(scenario) if end > start]


def envelope(t: np.ndarray, y: np.ndarray, xlim: Tuple[float, float],
             columns: int = COLUMNS) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The min/max envelope of y(t) inside xlim over ``columns`` equal intervals, at their
    centres (the samples themselves for at most 2 ``columns`` of them); NaNs left out.

    Args:
        t: The sample times [s] (T, increasing).
        y: The signal at them (T).
        xlim: The time window (start, end) [s].
        columns: The number of intervals (about one per pixel column).

    Returns:
        (t, low, high): the intervals' centres [s] (or the samples' times) and y's
            min and max over each."""
    inside = (t >= xlim[0]) & (t <= xlim[1])
    t, y = t[inside], y[inside]
    if len(t) <= 2 * columns:
        return t, y, y
    edges = np.linspace(t[0], t[-1], columns + 1)
    starts = np.unique(np.searchsorted(t, edges[:-1]))
    with np.errstate(invalid="ignore"):
        low = np.fmin.reduceat(y, starts)
        high = np.fmax.reduceat(y, starts)
    ends = np.append(starts[1:], len(t)) - 1
    return 0.5 * (t[starts] + t[ends]), low, high


def _trace(ax, t, y, xlim, log: bool = False, label=None, alpha=0.6, **style):
    """Draws y(t) inside xlim as a line, or as its min/max band if over-sampled."""
    y = np.asarray(y, float)
    if log:
        y = np.where(y > 0, y, np.nan)
    tc, low, high = envelope(np.asarray(t), y, xlim)
    style.setdefault("lw", 0.8)
    (line,) = ax.plot(tc, high, label=label, **style)
    if low is not high:
        ax.plot(tc, low, **{**style, "label": None})
        ax.fill_between(tc, low, high, color=line.get_color(), alpha=alpha, lw=0)
    if log:
        ax.set_yscale("log")
    return line


def _fit_log_axes(fig) -> None:
    """Each log axis of ``fig`` spans its positive data, at most LOG_DECADES decades."""
    for ax in fig.axes:
        if ax.get_yscale() != "log" or not ax.lines:
            continue
        y = np.concatenate([np.asarray(line.get_ydata(), float) for line in ax.lines])
        y = y[np.isfinite(y) & (y > 0)]
        if len(y):
            top = y.max()
            ax.set_ylim(max(y.min(), top * 10.0 ** -LOG_DECADES) / 1.5, top * 1.5)


def _figure(rows: int, scenario: Scenario, xlim=None, height: float = 2.0):
    """A column of ``rows`` axes sharing time, shaded by phase, labelled on top."""
    xlim = xlim or (0.0, scenario.duration)
    fig, axes = plt.subplots(rows, 1, figsize=(WIDTH, height * rows + 0.7),
                             sharex=True, squeeze=False, layout="constrained")
    axes = axes[:, 0]
    for i, ax in enumerate(axes):
        _shade(ax, scenario, xlim, label=(i == 0))
        ax.grid(True, lw=0.3)
    axes[-1].set_xlabel("time t [s]")
    axes[-1].set_xlim(xlim)
    return fig, axes, xlim


def _legend_outside(ax, **kwargs) -> None:
    """The axes' legend to the right of its data area."""
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0,
              fontsize=7, **kwargs)


def _matrix_norms(logs: Logs, scenario: Scenario, n: int, B0, D0):
    """||B~ - B0||_F, ||D~ - D0||, ||B_hat - B~||_F, ||D_hat - D~|| over time, B_hat and
    D_hat the claims about B~ and D~ (loop.metrics.physical_view)."""
    truth, estimate = logs["true_matrices"], physical_view(logs, scenario)[0]
    B0 = np.diag(B0).reshape(-1)
    return (np.linalg.norm(truth[:, :n * n] - B0, axis=1),
            np.linalg.norm(truth[:, n * n:] - np.asarray(D0), axis=1),
            np.linalg.norm(estimate[:, :n * n] - truth[:, :n * n], axis=1),
            np.linalg.norm(estimate[:, n * n:] - truth[:, n * n:], axis=1))


def _panel_a(dac: Logs, scenario: Scenario):
    n = len(scenario.q0)
    t = dac["time"]
    dB, dD, eB, eD = _matrix_norms(dac, scenario, n, scenario.uncertainty.B0,
                                   scenario.uncertainty.D0)
    fig, (ax1, ax2, ax3), xlim = _figure(3, scenario)
    for ax, prior, learned, name, unit in [
            (ax1, dB, eB, r"\tilde B", "[-]"), (ax2, dD, eD, r"\tilde D", "[N m s]")]:
        symbol = name[-1]
        _trace(ax, t, prior, xlim, log=True, color="0.4", ls=":", lw=1.2,
               label=rf"$\|{symbol}_0 - {name}\|$ (nominal prior = uncertainty)")
        _trace(ax, t, learned, xlim, log=True, color="C0",
               label=rf"$\|\hat {symbol} - {name}\|$ (claimed)")
        ax.set_ylabel(f"error of {symbol} {unit}")
        _legend_outside(ax)
    _trace(ax3, t, dac["rhs_log"][:, RhsLog(n).e_norm], xlim, log=True, color="C3",
           label=r"$\|e_\tau\|$ (DAC-pH)")
    ax3.set_ylabel(r"$\|e_\tau\|$ [N m]")
    _legend_outside(ax3)
    return fig


def _entries(dac: Logs, scenario: Scenario, xlim=None, port: bool = False):
    """One small axis per entry (B_rc in an n x n grid, D_kk in a row below): the claims
    about B~ and D~ with their credible band, the truth and the prior; with ``port``, the
    published estimates against (I + E) B~, diag((I + E) D~)."""
    n = len(scenario.q0)
    t = dac["time"]
    xlim = xlim or (0.0, scenario.duration)
    fig, grid = plt.subplots(n + 1, n, figsize=(WIDTH, 1.7 * (n + 1) + 1.0),
                             sharex=True, squeeze=False, layout="constrained")
    prior = nominal_estimates(scenario)
    if port:
        truth = port_truth(dac["true_matrices"],
                           realized_error_of(dac, robot_of(scenario)))
        estimate, band = dac["estimates"], None
        labels = (r"port truth $(I + E)\,\tilde X$", "port model (the loop's)")
    else:
        truth = dac["true_matrices"]
        estimate, lower, upper = physical_view(dac, scenario)
        band = (lower, upper)
        labels = ("true", "claimed (learned or prior)")
    inside = (t >= xlim[0]) & (t <= xlim[1])
    stride = max(1, int(np.count_nonzero(inside) // (2 * COLUMNS)))
    cells = [(grid[r, c], r * n + c, r"$B_{%d%d}$ [-]" % (r + 1, c + 1))
             for r in range(n) for c in range(n)]
    cells += [(grid[n, k], n * n + k, r"$D_{%d%d}$ [N m s]" % (k + 1, k + 1))
              for k in range(n)]
    for ax, column, name in cells:
        _shade(ax, scenario, xlim, label=False)
        ax.grid(True, lw=0.3)
        if band is not None:
            ax.fill_between(t[inside][::stride], band[0][inside, column][::stride],
                            band[1][inside, column][::stride], color="C0", alpha=0.18,
                            lw=0, label="90 % interval")
        _trace(ax, t, truth[:, column], xlim, label=labels[0], **ENTRY_STYLES["true"])
        _trace(ax, t, estimate[:, column], xlim, label=labels[1],
               **ENTRY_STYLES["learned"])
        ax.axhline(prior[column], label="nominal (prior)", **ENTRY_STYLES["nominal"])
        ax.set_ylabel(name, fontsize=8)
        ax.tick_params(labelsize=7)
    for ax in grid[-1]:
        ax.set_xlabel("time t [s]", fontsize=8)
    grid[-1, 0].set_xlim(xlim)
    series = grid[0, 0].get_legend_handles_labels()[0]
    fig.legend(handles=series + _phase_handles(scenario), loc="outside upper center",
               ncol=4, fontsize=8)
    return fig


def _panel_d(dac: Logs, scenario: Scenario):
    n = len(scenario.q0)
    t, rhs, R = dac["time"], dac["rhs_log"], RhsLog(n)
    fig, (ax1, ax2, ax3), xlim = _figure(3, scenario)
    for k in range(n):
        _trace(ax1, t, rhs[:, R.K][:, k], xlim, color=f"C{k}", label=f"$k_{k + 1}$")
    ax1.set_ylabel(r"gains $k_p$ [1/s]")
    _legend_outside(ax1)
    _trace(ax2, t, rhs[:, R.c], xlim, color="C0", lw=1.0, label="c")
    _trace(ax2, t, rhs[:, R.c_min], xlim, color="k", ls="--", lw=1.0,
           label=r"$c_{min}$ (eq. 48)")
    ax2.set_ylabel("c [1/s]")
    _legend_outside(ax2)
    _trace(ax3, t, rhs[:, R.chi], xlim, log=True, color="C2", label=r"$\chi$")
    ax3.set_ylabel(r"$\chi$ [N m]")
    _legend_outside(ax3)
    return fig


def _style(controller: str) -> Dict:
    """A controller's registered colour, line style and label."""
    entry = REGISTRY[controller]
    return dict(color=entry.color, ls=entry.linestyle, label=entry.label or controller)


def _compared(runs: Dict[str, Logs]):
    """(controller, logs) of every run, the reference (DAC) last, on top."""
    return sorted(runs.items(), key=lambda item: item[0] == REFERENCE)


def _primary(runs: Dict[str, Logs]) -> Logs:
    """The run whose own signals (d(t), u, states) a panel shows: DAC's, else the first."""
    return runs.get(REFERENCE, next(iter(runs.values())))


def _panel_e(runs: Dict[str, Logs], scenario: Scenario):
    n = len(scenario.q0)
    layout = LhsLog(n)
    dac = _primary(runs)
    fig, (ax1, ax2, ax3), xlim = _figure(3, scenario)
    for name, logs in _compared(runs):
        t, lhs = logs["time"], logs["lhs_log"]
        _trace(ax1, t, np.abs(lhs[:, layout.alpha_error]), xlim, log=True,
               **_style(name))
        _trace(ax2, t, np.linalg.norm(lhs[:, layout.s], axis=1), xlim, log=True,
               **_style(name))
    ax1.set_ylabel(r"$|\tilde\alpha|$ [rad]")
    ax2.set_ylabel(r"$\|s\|$ [rad/s]")
    _legend_outside(ax1)
    _legend_outside(ax2)
    for k in range(n):
        _trace(ax3, dac["time"], dac["disturbance"][:, k], xlim, color=f"C{k + 2}",
               label=f"$d_{k + 1}$")
    ax3.set_ylabel("d(t) [N m]")
    _legend_outside(ax3)
    return fig


def _panel_f(runs: Dict[str, Logs], scenario: Scenario):
    """(f) of a planar arm: _panel_inputs with the base's angle and alpha_d."""
    return _panel_inputs(runs, scenario, ArmCoordinates.ForPlanarArm(len(scenario.q0)),
                         planar=True)


def _panel_inputs(runs: Dict[str, Logs], scenario: Scenario,
                  coordinates: ArmCoordinates, planar: bool = False):
    """The primary run's inputs u, joint angles and rates; beside DAC's, the baseline's
    input minus DAC's; a planar arm's theta_0 and alpha_d with its angles."""
    n = len(scenario.q0)
    dac = _primary(runs)
    name = next(c for c, logs in runs.items() if logs is dac)
    label = REGISTRY[name].label or name
    compared = REFERENCE in runs and BASELINE in runs
    fig, axes, xlim = _figure(4 if compared else 3, scenario)
    ax1, ax3, ax4 = axes[0], axes[-2], axes[-1]
    t = dac["time"]
    for k in range(n):
        _trace(ax1, t, dac["u"][:, k], xlim, color=f"C{k % 10}", label=f"$u_{k + 1}$")
        if compared:
            u_model_based = np.interp(t, runs[BASELINE]["time"],
                                      runs[BASELINE]["u"][:, k], right=np.nan)
            _trace(axes[1], t, u_model_based - dac["u"][:, k], xlim,
                   color=f"C{k % 10}", label=f"$u_{k + 1}$")
    ax1.set_ylabel(f"u, {label} [N m]")
    _legend_outside(ax1)
    if compared:
        axes[1].set_ylabel(f"u, model-based\nminus {label} [N m]")
        _legend_outside(axes[1])
    base_pose, q, _, qdot = coordinates.Split(dac["state"])
    if planar:
        _trace(ax3, t, base_pose[:, 2], xlim, color="k", label=r"$\theta_0$ (base)")
    for k in range(n):
        _trace(ax3, t, q[:, k], xlim, color=f"C{k % 10}", label=f"$q_{k + 1}$")
        _trace(ax4, t, qdot[:, k], xlim, color=f"C{k % 10}",
               label=r"$\dot q_{%d}$" % (k + 1))
    if planar:
        _trace(ax3, t, dac["lhs_log"][:, LhsLog(n).alpha_desired], xlim, color="C3",
               ls="--", label=r"$\alpha_d$")
    ax3.set_ylabel(f"angles, {label} [rad]")
    ax4.set_ylabel(f"joint rates, {label} [rad/s]")
    _legend_outside(ax3)
    _legend_outside(ax4)
    return fig


def _panel_spatial(runs: Dict[str, Logs], scenario):
    """(e) of a described arm: the errors its task tracks (|e| where its GJM rows hold
    the angular ones, |e_p| the linear ones) and ||s|| of every run, the smallest
    link-base distance against the potential's margin, d(t)."""
    task, n = task_of(scenario), len(scenario.q0)
    layout, log_name, rows = task.LogLayout(n), task.log_name, set(task.jacobian_rows)
    errors = [error for error, error_rows in (("attitude", ATTITUDE_ROWS),
                                              ("position", POSITION_ROWS))
              if set(error_rows) <= rows]
    dac = _primary(runs)
    fig, axes, xlim = _figure(3 + len(errors), scenario)
    error_axes, (ax2, ax3, ax4) = axes[:-3], axes[-3:]
    columns = {"attitude": "e_norm", "position": "e_position_norm"}
    for name, logs in _compared(runs):
        t, log = logs["time"], logs[log_name]
        for ax, error in zip(error_axes, errors):
            _trace(ax, t, log[:, getattr(layout, columns[error])], xlim, log=True, **_style(name))
        _trace(ax2, t, log[:, layout.s_norm], xlim, log=True, **_style(name))
        _trace(ax3, t, log[:, layout.clearance], xlim, **_style(name))
    ax3.axhline(scenario.robot.potential.margin, color="k", ls=":", lw=1.0,
                label="potential's margin")
    labels = {"attitude": r"attitude error $|e|$ [rad]",
              "position": r"position error $|e_p|$ [m]"}
    for ax, error in zip(error_axes, errors):
        ax.set_ylabel(labels[error])
    ax2.set_ylabel(r"$\|s\|$ [rad/s]")
    ax3.set_ylabel("link-base\ndistance [m]")
    for k in range(n):
        _trace(ax4, dac["time"], dac["disturbance"][:, k], xlim, color=f"C{k % 10}",
               label=f"$d_{k + 1}$")
    ax4.set_ylabel("d(t) [N m]")
    for ax in axes:
        _legend_outside(ax)
    return fig


def zoom_window(scenario: Scenario) -> Tuple[float, float]:
    """(c)'s window: just before the nonlinear terms switch on to 1/12 of phase 2 after.

    Args:
        scenario: The scenario (its phases).

    Returns:
        (start, end) [s]."""
    start, length = scenario.phases.nonlinear_start, scenario.phases.nonlinear
    return (start - length / 48, start + length / 12)


# The task panels by name (tasks.task.Task.panels).
TASK_PANELS = {"e_dac_vs_model_based": _panel_e, "f_inputs_and_states": _panel_f,
               "e_attitude_dac_vs_model_based": _panel_spatial,
               "e_pose_dac_vs_model_based": _panel_spatial,
               "e_position_dac_vs_model_based": _panel_spatial,
               "f_inputs_and_joints": lambda runs, scenario: _panel_inputs(
                   runs, scenario, robot_of(scenario).model.coordinates)}


def make_panels(runs: Dict[str, Logs], scenario: Scenario) -> Dict[str, object]:
    """The panels as matplotlib figures: DAC_PANELS of the learning run (DAC's, else the
    first with an RHS loop), PORT_PANEL where it measured the LHS model's error, and the
    task's panels comparing every run.

    Args:
        runs: Controller -> the logs of its run (one run alone is drawn by itself).
        scenario: The scenario the runs ran.

    Returns:
        Panel name -> matplotlib figure."""
    learning = [logs for name, logs in sorted(runs.items(), key=lambda r: r[0] != REFERENCE)
                if "rhs_log" in logs and "estimates" in logs]
    figures = {}
    if learning:
        dac = learning[0]
        figures = {name: figure for name, figure in zip(DAC_PANELS, (
            _panel_a(dac, scenario), _entries(dac, scenario),
            _entries(dac, scenario, zoom_window(scenario)), _panel_d(dac, scenario)))}
        if "model_error" in dac:
            figures[PORT_PANEL] = _entries(dac, scenario, port=True)
    for name in task_of(scenario).panels:
        figures[name] = TASK_PANELS[name](runs, scenario)
    for fig in figures.values():
        _fit_log_axes(fig)
    return figures


def plot_panels(runs: Dict[str, Logs], scenario: Scenario,
                out_dir: Union[str, Path],
                formats: Sequence[str] = ("png", "pdf")) -> List[Path]:
    """Writes the panels (make_panels) into out_dir, one file per format.

    Args:
        runs: Controller -> the logs of its run (any registered controllers).
        scenario: The scenario the runs ran.
        out_dir: The folder for the files (created if missing).
        formats: The files' formats (matplotlib's: png, pdf, svg).

    Returns:
        The files' paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for name, fig in make_panels(runs, scenario).items():
        for suffix in formats:
            paths.append(out / f"{name}.{suffix}")
            fig.savefig(paths[-1], dpi=DPI)
        plt.close(fig)
    return paths
