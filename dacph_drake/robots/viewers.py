"""The arm in Meshcat: ArmViewer draws a plant state; write_animation replays a run's logs
into a self-contained HTML file."""
import html
import json
import logging
from pathlib import Path
from typing import Callable, Dict, Optional, Union

import numpy as np
from pydrake.geometry import (Box, Meshcat, MeshcatVisualizer,
                              MeshcatVisualizerParams, Rgba)
from pydrake.common.eigen_geometry import Quaternion
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.plant import MultibodyPlant
from pydrake.systems.framework import Context, DiagramBuilder

from dacph_drake.robots.description import AddRobotFromDescription
from dacph_drake.scenario.errors import ConfigError, require_positive
from dacph_drake.atomic_files import prepare_out_dir
from dacph_drake.log_layout import AttitudeLog, LhsLog
from dacph_drake.dynamics.plant import (BASE_COLOR, END_EFFECTOR, LINK_COLORS,
                               AddFreeFloatingArm, ArmCoordinates)
from dacph_drake.scenario import DescribedArm, Scenario

DESIRED_PATH = "/desired_orientation"
MEASURED_PATH = "/measured_orientation"
BAR_LENGTH = 0.15          # [m] of the bars showing alpha_d and alpha
DESIRED_COLOR = (0.85, 0.1, 0.1, 0.9)
DESIRED_TRIAD, MEASURED_TRIAD = "/desired_attitude", "/measured_attitude"
TRIADS = {DESIRED_TRIAD: (0.25, 0.03, 0.35),      # length, width [m], opacity
          MEASURED_TRIAD: (0.2, 0.008, 1.0)}
MEASURED_COLOR = (0.1, 0.1, 0.1, 0.9)
OVERLAY_BACKGROUND = "#fffbe6"


def playback_speedup(duration: float, max_playback: float) -> float:
    """Simulated seconds per playback second: 1 unless the run exceeds max_playback.

    Args:
        duration: The run's simulated duration [s].
        max_playback: The longest replay [s]."""
    return max(1.0, duration / max_playback)


class _RobotViewer:
    """A plant's geometry in Meshcat, drawn one state at a time (live or recorded)."""

    def __init__(self, meshcat: Meshcat, fps: float, add_plant):
        self.meshcat = meshcat
        builder = DiagramBuilder()
        self._plant, scene_graph = add_plant(builder)
        self.visualizer = MeshcatVisualizer.AddToBuilder(
            builder, scene_graph, meshcat,
            MeshcatVisualizerParams(publish_period=1.0 / fps))
        self._context = builder.Build().CreateDefaultContext()
        self._plant_context = self._plant.GetMyContextFromRoot(self._context)
        self._visualizer_context = self.visualizer.GetMyContextFromRoot(self._context)
        self._end_effector = self._plant.GetFrameByName(END_EFFECTOR)

    @property
    def num_joints(self) -> int:
        return self._plant.num_actuators()

    def _Publish(self, x: np.ndarray, time: float) -> RigidTransform:
        """Draws plant state ``x`` (at playback ``time``; None: live); returns X_WE."""
        self._context.SetTime(time or 0.0)
        self._plant.SetPositions(self._plant_context, x[:self._plant.num_positions()])
        self.visualizer.ForcedPublish(self._visualizer_context)
        return self._end_effector.CalcPoseInWorld(self._plant_context)

    def _Place(self, path: str, pose: RigidTransform, time: float) -> None:
        if time is None:
            self.meshcat.SetTransform(path, pose)
        else:
            self.meshcat.SetTransform(path, pose, time)


class ArmViewer(_RobotViewer):
    """The planar arm top-down, with alpha_d (wide red bar) and alpha (thin dark bar).

    Args:
        scenario: The scenario (its robot.truth is drawn).
        meshcat: The Meshcat to draw into.
        view: The half-width of the square shown [m].
        fps: The visualizer's publish rate [1/s]."""

    def __init__(self, scenario: Scenario, meshcat: Meshcat, view: float,
                 fps: float = 30.0):
        super().__init__(meshcat, fps,
                         lambda builder: AddFreeFloatingArm(builder, scenario.robot.truth))
        self._coordinates = ArmCoordinates.ForPlanarArm(scenario.robot.truth.num_links)
        meshcat.Set2dRenderMode(RigidTransform(RotationMatrix(
            np.array([[1.0, 0, 0], [0, 0, 1.0], [0, -1.0, 0]])), [0, 0, 1.0]),
            -view, view, -view, view)
        for path, color, width in ((DESIRED_PATH, DESIRED_COLOR, 0.018),
                                   (MEASURED_PATH, MEASURED_COLOR, 0.004)):
            meshcat.SetObject(path, Box(BAR_LENGTH, width, 0.008), Rgba(*color))

    @staticmethod
    def Reach(scenario: Scenario) -> float:
        """The distance [m] from the base's centre to the arm's stretched-out tip.

        Args:
            scenario: The scenario (its robot.truth)."""
        return (scenario.robot.truth.base.size / 2
                + sum(link.length for link in scenario.robot.truth.links))

    def Draw(self, x: np.ndarray, alpha_desired: float,
             time: Optional[float] = None) -> None:
        """Shows a plant state and alpha_d.

        Args:
            x: The plant state.
            alpha_desired: alpha_d [rad].
            time: The playback time [s] of the recording's frame (None: live)."""
        end = self._Publish(x, time).translation()
        base_pose, q, _, _ = self._coordinates.Split(x)
        for path, alpha, height in ((DESIRED_PATH, alpha_desired, 0.02),
                                    (MEASURED_PATH, base_pose[2] + q.sum(), 0.03)):
            direction = np.array([np.cos(alpha), np.sin(alpha), 0.0])
            self._Place(path, RigidTransform(
                RotationMatrix.MakeZRotation(alpha),
                end + 0.5 * BAR_LENGTH * direction + [0, 0, height]), time)


class LiveView:
    """Draws a loop's ground truth in Meshcat as it simulates, <= ``fps`` per sim s.

    Args:
        plant: The loop's ground-truth plant.
        meshcat: The Meshcat drawn into.
        draw: ``draw(root_context, x, t)`` draws plant state x at time t [s].
        fps: The most frames per simulated second."""

    def __init__(self, plant: MultibodyPlant, meshcat: Meshcat,
                 draw: Callable[[Context, np.ndarray, float], None], fps: float = 30.0):
        self._plant, self._meshcat, self._draw = plant, meshcat, draw
        self._period, self._next = 1.0 / fps, 0.0

    @staticmethod
    def ForPlanarLoop(loop: "ClosedLoop", meshcat: Meshcat, fps: float = 30.0
                      ) -> "LiveView":
        """A LiveView of a planar loop through an ArmViewer (alpha_d from lhs_log).

        Args:
            loop: The planar arm's closed loop.
            meshcat: The Meshcat drawn into.
            fps: The most frames per simulated second."""
        scenario = loop.scenario
        viewer = ArmViewer(scenario, meshcat, 1.5 * ArmViewer.Reach(scenario), fps)
        lhs_log = loop.loggers.get("lhs_log")
        column = LhsLog(scenario.robot.truth.num_links).alpha_desired
        coordinates = ArmCoordinates.FromPlant(loop.plant)

        def draw(root_context, x, t):
            if lhs_log is not None:
                alpha_desired = lhs_log.get_input_port().Eval(
                    lhs_log.GetMyContextFromRoot(root_context))[column]
            else:
                base_pose, q, _, _ = coordinates.Split(x)
                alpha_desired = base_pose[2] + q.sum()
            viewer.Draw(x, alpha_desired)
        return LiveView(loop.plant, meshcat, draw, fps)

    def Update(self, root_context: Context) -> None:
        """Draws the robot when its next frame is due (a Simulator monitor).

        Args:
            root_context: The loop diagram's context."""
        t = root_context.get_time()
        if t < self._next:
            return
        self._next = t + self._period
        x = self._plant.GetMyContextFromRoot(root_context).get_continuous_state_vector(
            ).CopyToVector()
        self._meshcat.SetSimulationTime(t)
        self._draw(root_context, x, t)


def write_animation(scenario: Scenario, logs: Dict[str, np.ndarray],
                    out_html: Union[str, Path], fps: float = 30.0,
                    max_playback: float = 60.0, meshcat: Optional[Meshcat] = None
                    ) -> Path:
    """Writes a planar run's replay as an HTML file; returns its path.

    Args:
        scenario: The scenario the run ran.
        logs: The run's logs (RunResult.logs).
        out_html: The HTML file to write (its folder is created).
        fps: The replay's frames per second.
        max_playback: The longest replay [s]: longer runs are sped up to fit.
        meshcat: The Meshcat to record in (None: a new QuietMeshcat).

    Raises:
        ConfigError: ``fps`` or ``max_playback`` is not positive.
        ValueError: The logs hold fewer than two samples."""
    t, x = _RequireReplayable(logs, fps, max_playback)
    alpha_desired = logs["lhs_log"][:, LhsLog(scenario.robot.truth.num_links).alpha_desired]
    meshcat = meshcat or QuietMeshcat()
    view = 1.2 * ArmViewer.Reach(scenario) + float(np.max(np.abs(x[:, :2])))
    viewer = ArmViewer(scenario, meshcat, view, fps)
    speedup = _Record(viewer.visualizer, t, fps, max_playback,
                      lambda row, time: viewer.Draw(x[row], alpha_desired[row], time))
    entries = [(BASE_COLOR, "base"),
               *[(LINK_COLORS[k % len(LINK_COLORS)], f"link {k + 1}")
                 for k in range(scenario.robot.truth.num_links)],
               (DESIRED_COLOR, "desired end-effector direction &alpha;<sub>d</sub>"),
               (MEASURED_COLOR, "measured end-effector direction &alpha;")]
    p = scenario.phases
    phases = [[0.0, p.linear_start, "Warm-up: B0, D0"],
              [p.linear_start, p.nonlinear_start, "Phase 1: linear uncertainty"],
              [p.nonlinear_start, p.disturbance_start, "Phase 2: + nonlinear"],
              [p.disturbance_start, float("inf"), "Phase 3: + disturbance d(t)"]]
    return _WritePage(meshcat, out_html, _overlay(entries, phases, t[0], speedup))


class SpatialViewer(_RobotViewer):
    """A described robot in Meshcat, R_d a thick translucent triad, the measured thin.

    Args:
        description: The robot, as AddRobotFromDescription takes it.
        meshcat: The Meshcat to draw into.
        fps: The visualizer's publish rate [1/s]."""

    def __init__(self, description: Union[str, Path, DescribedArm], meshcat: Meshcat,
                 fps: float = 30.0):
        super().__init__(meshcat, fps,
                         lambda builder: AddRobotFromDescription(builder, description))
        for path, (length, width, opacity) in TRIADS.items():
            for axis, unit in enumerate(np.eye(3)):
                child = f"{path}/{'xyz'[axis]}"
                meshcat.SetObject(child, Box(*(width + (length - width) * unit)),
                                  Rgba(*unit, opacity))
                meshcat.SetTransform(child, RigidTransform(0.5 * length * unit))

    def Draw(self, x: np.ndarray, R_d: RotationMatrix,
             time: Optional[float] = None) -> None:
        """Shows a plant state and R_d.

        Args:
            x: The plant state.
            R_d: The desired end-effector attitude.
            time: The playback time [s] of the recording's frame (None: live)."""
        X_WE = self._Publish(x, time)
        for path, R in ((DESIRED_TRIAD, R_d), (MEASURED_TRIAD, X_WE.rotation())):
            self._Place(path, RigidTransform(R, X_WE.translation()), time)


def write_spatial_animation(robot: DescribedArm, logs: Dict[str, np.ndarray],
                            out_html: Union[str, Path], fps: float = 30.0,
                            max_playback: float = 60.0, meshcat: Optional[Meshcat] = None,
                            log_name: str = "attitude_log") -> Path:
    """Writes a spatial run's replay as an HTML file; returns its path.

    Args:
        robot: The scenario's robot section (its description is drawn).
        logs: The run's logs (RunResult.logs).
        out_html: The HTML file to write (its folder is created).
        fps: The replay's frames per second.
        max_playback: The longest replay [s]: longer runs are sped up to fit.
        meshcat: The Meshcat to record in (None: a new QuietMeshcat).
        log_name: The task's log holding R_d (log_layout.AttitudeLog's columns).

    Raises:
        ConfigError: ``fps`` or ``max_playback`` is not positive.
        ValueError: The logs hold fewer than two samples."""
    t, x = _RequireReplayable(logs, fps, max_playback)
    desired = logs[log_name][:, AttitudeLog().desired]
    meshcat = meshcat or QuietMeshcat()
    viewer = SpatialViewer(robot, meshcat, fps)
    speedup = _Record(viewer.visualizer, t, fps, max_playback, lambda row, time: viewer.Draw(
        x[row], RotationMatrix(Quaternion(desired[row] / np.linalg.norm(desired[row]))),
        time))
    num_joints = viewer.num_joints
    odd_even = [", ".join(str(k + 1) for k in range(first, num_joints, 2))
                for first in (0, 1)]
    entries = [(BASE_COLOR, "base"), (LINK_COLORS[0], f"links {odd_even[0]}"),
               (LINK_COLORS[1], f"links {odd_even[1]}"),
               ((1.0, 0.0, 0.0, 0.35), "desired attitude R<sub>d</sub>: thick triad "
                "(x red, y green, z blue)"),
               ((1.0, 0.0, 0.0, 1.0), "measured end-effector attitude: thin triad")]
    return _WritePage(meshcat, out_html, _overlay(entries, None, t[0], speedup))


def _RequireReplayable(logs, fps: float, max_playback: float):
    require_positive("fps", fps, "frames per second")
    require_positive("max_playback", max_playback, "s")
    t, x = logs["time"], logs["state"]
    if len(t) < 2:
        raise ValueError("the run has fewer than two logged samples to animate")
    return t, x


def QuietMeshcat() -> Meshcat:
    """A Meshcat without Drake's "listening for connections" message."""
    drake_logger = logging.getLogger("drake")
    level = drake_logger.level
    drake_logger.setLevel(logging.WARNING)
    try:
        return Meshcat()
    finally:
        drake_logger.setLevel(level)


def _Record(visualizer, t: np.ndarray, fps: float, max_playback: float, draw) -> float:
    """Records ``draw`` into ``visualizer``'s recording; returns the speed-up."""
    speedup = playback_speedup(t[-1] - t[0], max_playback)
    frames = np.arange(t[0], t[-1] + 1e-12, speedup / fps)
    rows = np.minimum(np.searchsorted(t, frames), len(t) - 1)
    visualizer.StartRecording(set_transforms_while_recording=False)
    for row in rows:
        draw(row, (t[row] - t[0]) / speedup)
    visualizer.StopRecording()
    visualizer.PublishRecording()
    return speedup


def _WritePage(meshcat: Meshcat, out_html, overlay: str) -> Path:
    out = Path(out_html)
    if out.is_dir():
        raise ConfigError(f"--out = {str(out)!r} is a directory; allowed: an HTML file")
    prepare_out_dir(out.parent)
    try:
        out.write_text(meshcat.StaticHtml().replace("</body>", overlay + "</body>", 1))
    except OSError as e:
        raise ConfigError(f"--out = {str(out)!r} cannot be written ({e.strerror}); "
                          "allowed: a writable HTML file") from e
    return out


def _swatch(rgba) -> str:
    r, g, b = (int(round(255 * c)) for c in rgba[:3])
    return (f'<span style="display:inline-block;width:22px;height:8px;margin-right:6px;'
            f'background:rgba({r},{g},{b},{rgba[3]:g})"></span>')


def _overlay(entries, phases, start: float, speedup: float) -> str:
    """Legend, time and phase label over the viewer; t = start + speedup * playback time."""
    legend = "".join(f"<div>{_swatch(rgba)}{label}</div>" for rgba, label in entries)
    phases = phases or [[float("-inf"), float("inf"), ""]]
    speed = "" if speedup == 1.0 else f" &times;{speedup:.3g} speed"
    bounded = [[max(a, -1e300), min(b, 1e300), c] for a, b, c in phases]
    return f"""
<div id="dacph-overlay" style="position:fixed;top:10px;left:10px;z-index:10;
  font:13px sans-serif;background:{OVERLAY_BACKGROUND};border:1px solid #888;
  padding:8px 10px;line-height:1.5">
  <div style="font-weight:bold;font-size:15px"><span id="dacph-time">t = 0.00 s</span>
    <span style="font-weight:normal;font-size:12px">{speed}</span></div>
  <div id="dacph-phase">{html.escape(phases[0][2])}</div>
  <hr style="border:none;border-top:1px solid #ccc;margin:4px 0">{legend}
</div>
<script>
(function() {{
  const start = {float(start)!r}, speedup = {float(speedup)!r};
  const phases = {json.dumps(bounded)};
  function show() {{
    const t = start + speedup * viewer.animator.time;
    document.getElementById("dacph-time").textContent = "t = " + t.toFixed(2) + " s";
    const phase = phases.find(([a, b]) => t >= a && t < b) || phases[phases.length - 1];
    document.getElementById("dacph-phase").textContent = phase[2];
  }}
  setInterval(show, 50);
}})();
</script>
"""
