"""Running the spatial model-based attitude loop (spatial_diagrams.py) as a user
does (`dacph spatial`): built-in and YAML scenarios, a progress bar, a stop with a
reason when the state turns non-finite, the metrics, and the saved run
(logs.npz, scenario.yaml, run.json, optionally the 3D replay)."""
import json
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict

import numpy as np
from pydrake.common.yaml import yaml_dump_typed

from dacph_drake.animation import LiveView
from dacph_drake.errors import ConfigError, require_positive
from dacph_drake.log_layout import AttitudeLog
from dacph_drake.progress import progress_bar
from dacph_drake.robot import load_yaml_dataclass
from dacph_drake.run import advance_in_chunks, collect_logs, prepare_out_dir
from dacph_drake.spatial_diagrams import build_spatial_model_based_diagram
from dacph_drake.spatial_scenario import SpatialScenario

SETTLING_TIME = 1.0             # [s] left out of the steady-state error metrics
BUILT_IN_SPATIAL_SCENARIOS = {
    "satellite_6dof": SpatialScenario,
    "satellite_3dof": lambda: SpatialScenario(robot="satellite_3dof", q0=[0.3, -0.8, 1.6]),
}


def load_spatial_scenario(path) -> SpatialScenario:
    """A built-in name (BUILT_IN_SPATIAL_SCENARIOS) or a SpatialScenario YAML file
    (errors name the file and the setting)."""
    if str(path) in BUILT_IN_SPATIAL_SCENARIOS and not Path(path).is_file():
        return BUILT_IN_SPATIAL_SCENARIOS[str(path)]()
    if not Path(path).is_file():
        raise ConfigError(f"spatial scenario {str(path)!r}: no such file; allowed: a "
                          "YAML file or a built-in name "
                          f"({', '.join(BUILT_IN_SPATIAL_SCENARIOS)})")
    return load_yaml_dataclass(path, SpatialScenario)


def save_spatial_scenario(scenario: SpatialScenario, path) -> None:
    Path(path).write_text(yaml_dump_typed(scenario))


@dataclass
class SpatialRunResult:
    status: str                     # "ok" or "diverged"
    reason: str
    final_time: float
    wall_time: float
    logs: Dict[str, np.ndarray] = field(default_factory=dict)
    metrics: Dict[str, float] = field(default_factory=dict)


def simulate_spatial(scenario: SpatialScenario, duration: float = None, out_dir=None,
                     progress: bool = False, meshcat=None) -> SpatialRunResult:
    """Simulates the loop for ``duration`` (default: the scenario's), checking the
    state every run.MONITOR_PERIOD (run.advance_in_chunks); with ``out_dir``, saves
    the run there; with ``meshcat``, draws it there while it simulates
    (animation.LiveView)."""
    duration = scenario.duration if duration is None else duration
    require_positive("duration", duration, "s")
    if out_dir is not None:
        prepare_out_dir(out_dir)           # checked before any time is spent
    loop = build_spatial_model_based_diagram(scenario)
    simulator = loop.CreateSimulator()
    context = simulator.get_mutable_context()
    plant_context = loop.plant.GetMyContextFromRoot(context)
    live_view = LiveView.ForSpatialLoop(loop, meshcat) if meshcat is not None else None
    simulator.Initialize()
    bar = progress_bar(duration, "spatial", "s", enabled=progress)
    start = time.perf_counter()

    def check(t: float):
        if not np.all(np.isfinite(loop.plant.GetPositionsAndVelocities(plant_context))):
            return f"non-finite plant state at t = {t:.4f} s"
        return None

    def after_chunk(last: bool) -> None:
        if live_view is not None:
            live_view.Update(context)
        bar.update(context.get_time() - bar.n)

    try:
        reason = advance_in_chunks(simulator, duration, check, after_chunk)
    finally:
        bar.close()
    logs = collect_logs(loop, context)
    result = SpatialRunResult(status="diverged" if reason else "ok", reason=reason,
                              final_time=context.get_time(),
                              wall_time=time.perf_counter() - start, logs=logs,
                              metrics=spatial_metrics(loop, logs))
    if out_dir is not None:
        save_spatial_run(result, scenario, out_dir)
    return result


def spatial_metrics(loop, logs) -> Dict[str, float]:
    """Attitude error |e| (final, RMS and max after SETTLING_TIME) [rad], the
    smallest link-base distance [m] (nan without the potential, which measures it),
    and the largest |spatial momentum| over the logged states."""
    layout = AttitudeLog()
    t, error = logs["time"], logs["attitude_log"][:, layout.e_norm]
    settled = t >= SETTLING_TIME
    clearance = logs["attitude_log"][:, layout.clearance]
    context = loop.plant.CreateDefaultContext()
    momentum = 0.0
    for x in logs["state"]:
        loop.plant.SetPositionsAndVelocities(context, x)
        momentum = max(momentum, float(np.max(np.abs(
            loop.plant.CalcSpatialMomentumInWorldAboutPoint(context, np.zeros(3)
                                                            ).get_coeffs()))))
    nan = float("nan")
    return {"attitude_error_final": float(error[-1]) if len(error) else nan,
            "attitude_error_rms_settled": (float(np.sqrt(np.mean(error[settled]**2)))
                                           if settled.any() else nan),
            "attitude_error_max_settled": (float(np.max(error[settled]))
                                           if settled.any() else nan),
            "min_clearance": (float(np.min(clearance)) if np.all(np.isfinite(clearance))
                              and len(clearance) else nan),
            "max_momentum": momentum}


def save_spatial_run(result: SpatialRunResult, scenario: SpatialScenario, out_dir) -> Path:
    """logs.npz, scenario.yaml and run.json in out_dir, each replaced atomically."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "logs.npz.tmp", "wb") as f:
        np.savez_compressed(f, **result.logs)
    os.replace(out / "logs.npz.tmp", out / "logs.npz")
    save_spatial_scenario(scenario, out / "scenario.yaml.tmp")
    os.replace(out / "scenario.yaml.tmp", out / "scenario.yaml")
    meta = {"status": result.status, "reason": result.reason,
            "final_time": result.final_time, "wall_time": result.wall_time,
            "metrics": result.metrics}
    (out / "run.json.tmp").write_text(json.dumps(meta, indent=2))
    os.replace(out / "run.json.tmp", out / "run.json")
    return out
