"""Running a spatial robot's closed loop (spatial_diagrams.py: DAC, its learning
ablation, the model-based baseline) as a user does (`dacph spatial`): built-in and
YAML scenarios, a progress bar, a stop with a reason when the state turns
non-finite, the metrics, and the saved run (logs.npz, scenario.yaml, run.json,
optionally the 3D replay), which `dacph verify` reads."""
import json
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict

import numpy as np
from pydrake.common.yaml import yaml_dump_typed

from dacph_drake.animation import LiveView
from dacph_drake.controllers import SPATIAL_REGISTRY, build_closed_loop
from dacph_drake.errors import ConfigError, require_positive
from dacph_drake.files import replaced_atomically
from dacph_drake.log_layout import AttitudeLog
from dacph_drake.metrics import run_metrics
from dacph_drake.progress import progress_bar
from dacph_drake.robot import load_yaml_dataclass
from dacph_drake.run import advance_in_chunks, collect_logs, prepare_out_dir
from dacph_drake.scenario import Disturbance, Phases, Uncertainty, load_scenario
from dacph_drake.spatial_scenario import SpatialScenario

SETTLING_TIME = 1.0             # [s] left out of the steady-state error metrics


def satellite_6dof_scenario() -> SpatialScenario:
    """The 6-DOF example (diagrams/satellite_6dof.yaml): 2 s warm-up on the nominal
    RHS, then 4 s each of linear uncertainty, nonlinear uncertainty and the
    disturbance (SpatialScenario's uncertainty and disturbance, switched on)."""
    scenario = SpatialScenario(duration=14.0, phases=Phases(
        warmup=2.0, linear=4.0, nonlinear=4.0, disturbance=4.0))
    scenario.uncertainty.linear_scale = scenario.uncertainty.nonlinear_scale = 1.0
    scenario.disturbance.scale = 1.0
    return scenario


def satellite_3dof_scenario() -> SpatialScenario:
    """The 3-DOF variant (diagrams/satellite_3dof.yaml) with the same phases and an
    uncertainty of the same form sized to its joints (shoulder yaw p ~ 0.3, pitch
    p ~ 1.1, forearm roll p ~ 5e-4 kg m^2/s)."""
    return SpatialScenario(
        robot="satellite_3dof", q0=[0.3, -0.8, 1.6], duration=14.0,
        phases=Phases(warmup=2.0, linear=4.0, nonlinear=4.0, disturbance=4.0),
        uncertainty=Uncertainty(
            B0=[1.0] * 3, D0=[0.2, 0.2, 0.01], D_offset=[0.04, 0.05, 0.002],
            D_linear=[0.15, 0.05, 0.1], D_quadratic=[0.1, -0.01, 1.0],
            B_linear=[[-0.1, 0.0, 0.0], [0.05, 0.15, 0.0], [0.0, 0.0, 0.1]],
            B_quadratic=[0.5, 0.02, 5.0],
            B_q1_squared=[[0.0, -0.1, 0.0], [0.4, 0.0, 0.0], [0.0, 0.0, 0.0]]),
        disturbance=Disturbance(lf_offset=[0.03, -0.02, 0.002],
                                lf_amplitude=[0.02, 0.02, 0.002],
                                lf_frequency=[0.05, 0.07, 0.09],
                                hf_direction=[1.0, -1.0, 0.1]))


BUILT_IN_SPATIAL_SCENARIOS = {"satellite_6dof": satellite_6dof_scenario,
                              "satellite_3dof": satellite_3dof_scenario}


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


def is_spatial_scenario(path) -> bool:
    """Whether ``path`` names a spatial scenario: a built-in spatial name, or a YAML
    file whose ``robot:`` is a description (a name or a path, not a planar arm's
    parameters)."""
    if str(path) in BUILT_IN_SPATIAL_SCENARIOS and not Path(path).is_file():
        return True
    try:
        import yaml
        raw = yaml.safe_load(Path(path).read_text())
    except (OSError, ValueError, yaml.YAMLError):
        return False
    return isinstance(raw, dict) and isinstance(raw.get("robot"), str)


def load_any_scenario(path):
    """A SpatialScenario where ``path`` names one (is_spatial_scenario), else a
    Scenario (scenario.load_scenario)."""
    return (load_spatial_scenario(path) if is_spatial_scenario(path)
            else load_scenario(path))


def save_spatial_scenario(scenario: SpatialScenario, path) -> None:
    Path(path).write_text(yaml_dump_typed(scenario))


@dataclass
class SpatialRunResult:
    controller: str                 # a name in controllers.SPATIAL_REGISTRY
    status: str                     # "ok" or "diverged"
    reason: str
    final_time: float
    wall_time: float
    logs: Dict[str, np.ndarray] = field(default_factory=dict)
    metrics: Dict[str, float] = field(default_factory=dict)


def simulate_spatial(scenario: SpatialScenario, duration: float = None, out_dir=None,
                     progress: bool = False, meshcat=None,
                     controller: str = "model-based") -> SpatialRunResult:
    """Simulates the loop of ``controller`` (controllers.SPATIAL_REGISTRY; the
    default is the one this function ran before the spatial DAC loop existed; `dacph
    spatial` runs dac unless told otherwise) for
    ``duration`` (default: the scenario's), checking the state every
    run.MONITOR_PERIOD (run.advance_in_chunks); with ``out_dir``, saves the run
    there; with ``meshcat``, draws it there while it simulates (animation.LiveView)."""
    duration = scenario.duration if duration is None else duration
    require_positive("duration", duration, "s")
    if out_dir is not None:
        prepare_out_dir(out_dir)           # checked before any time is spent
    loop = build_closed_loop(controller, scenario, SPATIAL_REGISTRY)
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
    result = SpatialRunResult(controller=controller,
                              status="diverged" if reason else "ok", reason=reason,
                              final_time=context.get_time(),
                              wall_time=time.perf_counter() - start, logs=logs,
                              metrics=spatial_metrics(loop, logs))
    if out_dir is not None:
        save_spatial_run(result, scenario, out_dir)
    return result


def spatial_metrics(loop, logs) -> Dict[str, float]:
    """Attitude error |e| (final, RMS and max after SETTLING_TIME) [rad], the
    smallest link-base distance [m] (nan without the potential, which measures it),
    the largest |spatial momentum| over the logged states, and the planar runs'
    metrics (metrics.run_metrics: tracking error = |e| over the phases, e_tau, the
    learned / nominal error ratios of B and D per phase, ...), so that sweeps and
    tables read spatial runs alike. A phase the run did not reach is nan."""
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
    with np.errstate(invalid="ignore"):        # a phase not reached: nan
        metrics = run_metrics(logs, loop.scenario)
    metrics.update({
        "attitude_error_final": float(error[-1]) if len(error) else nan,
        "attitude_error_rms_settled": (float(np.sqrt(np.mean(error[settled]**2)))
                                       if settled.any() else nan),
        "attitude_error_max_settled": (float(np.max(error[settled]))
                                       if settled.any() else nan),
        "min_clearance": (float(np.min(clearance)) if np.all(np.isfinite(clearance))
                          and len(clearance) else nan),
        "max_momentum": momentum})
    return metrics


def save_spatial_run(result: SpatialRunResult, scenario: SpatialScenario, out_dir) -> Path:
    """logs.npz, scenario.yaml and run.json in out_dir, each replaced atomically."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    with replaced_atomically(out / "logs.npz") as path, open(path, "wb") as f:
        np.savez_compressed(f, **result.logs)
    with replaced_atomically(out / "scenario.yaml") as path:
        save_spatial_scenario(scenario, path)
    meta = {"controller": result.controller, "status": result.status,
            "reason": result.reason,
            "final_time": result.final_time, "wall_time": result.wall_time,
            "metrics": result.metrics}
    with replaced_atomically(out / "run.json") as path:
        path.write_text(json.dumps(meta, indent=2))
    return out


def load_spatial_run(run_dir, controller: str = None):
    """(logs, scenario, run.json) of a run saved by save_spatial_run; with
    ``controller``, a ConfigError unless the run is of that controller."""
    run_dir = Path(run_dir)
    for name in ("scenario.yaml", "logs.npz", "run.json"):
        if not (run_dir / name).is_file():
            raise ConfigError(f"{run_dir}: {name} is missing; allowed: a run directory "
                              "saved by dacph spatial")
    meta = json.loads((run_dir / "run.json").read_text())
    if controller is not None and meta.get("controller", "model-based") != controller:
        raise ConfigError(f"{run_dir}: a {meta.get('controller', 'model-based')} run; "
                          f"allowed: a {controller} run (dacph spatial --controller "
                          f"{controller})")
    with np.load(run_dir / "logs.npz") as data:
        logs = {k: data[k] for k in data.files}
    return logs, load_spatial_scenario(run_dir / "scenario.yaml"), meta
