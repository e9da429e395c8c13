"""A figure per sensing sweep: DAC's tracking error (phases 2-3) and the baseline's,
the learned claims' coverage of B~ and D~ and the share of quantities left at the
prior, against the sensors' noise scale and the command's delay, the actuators' lag as
the marker, a run verify failed hollow (run:
.venv/bin/python scripts/sensing_sweep_figure.py SWEEP_DIR [...] --out FIGURE.png).
Each SWEEP_DIR is a `dacph sweep` output of sweeps/sensing_*.yaml; a table of the
medians per (noise scale, delay) is printed beside."""
import argparse
import json
from collections import defaultdict
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

MARKERS = {0.0005: "o", 0.001: "s", 0.002: "^", 0.003: "v", 0.004: "P", 0.005: "D",
           0.006: "*"}


def points(rows_path: Path):
    """(noise scale, delay, lag, DAC error, baseline error, B coverage, D coverage,
    DAC finished, undetermined share, verify ok) per trial."""
    out = []
    for row in map(json.loads, rows_path.open()):
        sampled, runs = row["sampled"], row["runs"]
        dac, baseline = runs.get("dac", {}), runs.get("model-based", {})
        metrics = dac.get("metrics") or {}
        coverage = [np.nanmean([metrics.get(f"phase{k}.{name}", np.nan)
                                for k in (2, 3)])
                    for name in ("B_coverage", "D_coverage", "undetermined_share")]
        out.append((sampled.get("sensing_noise_scale", 1.0),
                    sampled.get("sensing_rhs_delay", 1),
                    sampled.get("sensing_actuator_lag", 0.001),
                    metrics.get("tracking_error_rms_phases_2_3", np.nan),
                    (baseline.get("metrics") or {}).get("tracking_error_rms_phases_2_3",
                                                        np.nan),
                    *coverage[:2], dac.get("status") == "ok", coverage[2],
                    (dac.get("verify") or {}).get("ok", False)))
    return out


def draw(axes, name: str, data) -> None:
    noise = sorted({p[0] for p in data})
    delays = sorted({p[1] for p in data})
    colours = plt.cm.viridis(np.linspace(0.1, 0.8, len(delays)))
    position = {value: i for i, value in enumerate(noise)}
    for delay, colour in zip(delays, colours):
        for p in (p for p in data if p[1] == delay):
            jitter = 0.08 * (delays.index(delay) - 0.5 * (len(delays) - 1))
            x = position[p[0]] + jitter
            marker = MARKERS.get(p[2], "x")
            style = dict(marker=marker, s=18, edgecolors=colour,
                         facecolors=colour if p[9] else "none")
            axes[0].scatter(x, p[3] if p[7] else np.nan, **style)
            axes[0].scatter(x, p[4], color="0.6", marker=marker, s=10)
            for ax, value in zip(axes[1:], (p[5], p[6], p[8])):
                ax.scatter(x, value, **style)
    for ax, label in zip(axes, ("tracking RMS, phases 2-3 [rad]", "B~ coverage",
                                "D~ coverage", "share at the prior")):
        ax.set_xticks(range(len(noise)), [f"{v:g}" for v in noise])
        ax.set_xlabel("noise scale (x the spacecraft set)")
        ax.set_ylabel(label)
        ax.set_title(name, fontsize=9)
    axes[0].set_yscale("log")
    for ax in axes[1:]:
        ax.set_ylim(0.0, 1.05)
    for ax in axes[1:3]:
        ax.axhline(0.85, color="k", lw=0.8, ls="--")
    handles = [plt.Line2D([], [], color=c, marker="o", ls="", label=f"delay {d}")
               for d, c in zip(delays, colours)]
    handles += [plt.Line2D([], [], color="k", marker=m, ls="", label=f"lag {lag * 1e3:g} ms")
                for lag, m in MARKERS.items() if any(p[2] == lag for p in data)]
    handles.append(plt.Line2D([], [], color="0.6", marker="o", ls="", label="baseline"))
    handles.append(plt.Line2D([], [], color="k", marker="o", mfc="none", ls="",
                              label="verify fails"))
    axes[0].legend(handles=handles, fontsize=7)


def table(name: str, data) -> None:
    groups = defaultdict(list)
    for p in data:
        groups[(p[0], p[1])].append(p)
    print(f"\n{name}: noise scale, delay: trials, DAC finished, verify passes, median "
          "DAC / baseline RMS, median ratio, min B / D coverage, median share at the prior")
    for key in sorted(groups):
        g = groups[key]
        finished = [p for p in g if p[7]]
        ratio = [p[4] / p[3] for p in finished]
        print(f"  {key[0]:5g} {key[1]:2d}: {len(g):3d} {len(finished):3d} "
              f"{sum(p[9] for p in g):3d}  "
              f"{np.median([p[3] for p in finished]) if finished else np.nan:.2e} / "
              f"{np.median([p[4] for p in g]):.2e}  "
              f"{np.median(ratio) if ratio else np.nan:7.1f}  "
              f"{np.nanmin([p[5] for p in finished]) if finished else np.nan:.3f} / "
              f"{np.nanmin([p[6] for p in finished]) if finished else np.nan:.3f}  "
              f"{np.nanmedian([p[8] for p in finished]) if finished else np.nan:.2f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("sweeps", nargs="+", type=Path)
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    figure, axes = plt.subplots(len(args.sweeps), 4, figsize=(16, 3.6 * len(args.sweeps)),
                                squeeze=False)
    for row, folder in zip(axes, args.sweeps):
        data = points(folder / "rows.jsonl")
        draw(row, folder.name, data)
        table(folder.name, data)
    figure.tight_layout()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(args.out, dpi=110)


if __name__ == "__main__":
    main()
