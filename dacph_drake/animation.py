"""A self-contained HTML animation of a run: the ground-truth plant replayed in
Drake's Meshcat from the logged state, with the desired end-effector orientation
alpha_d drawn as a red bar at the end effector, viewed top-down (the robot's plane).
"""
from pathlib import Path

import numpy as np
from pydrake.geometry import (Box, Meshcat, MeshcatVisualizer,
                              MeshcatVisualizerParams, Rgba)
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.systems.framework import DiagramBuilder

from dacph_drake.errors import require_positive
from dacph_drake.log_layout import LhsLog
from dacph_drake.plant import END_EFFECTOR, AddFreeFloatingArm
from dacph_drake.scenario import Scenario

DESIRED_PATH = "/desired_orientation"
DESIRED_LENGTH = 0.15          # [m] of the bar showing alpha_d


def playback_speedup(duration: float, max_playback: float) -> float:
    """Simulated seconds per playback second: real time unless the run is longer
    than max_playback."""
    return max(1.0, duration / max_playback)


def write_animation(scenario: Scenario, logs, out_html, fps: float = 30.0,
                    max_playback: float = 60.0, meshcat: Meshcat = None) -> Path:
    """Replays logs["state"] (plant state, sampled at logs["time"]) and the logged
    alpha_d (lhs_log) into a Meshcat recording and writes meshcat.StaticHtml() to
    out_html. Runs longer than ``max_playback`` seconds are sped up to fit."""
    require_positive("fps", fps, "frames per second")
    require_positive("max_playback", max_playback, "s")
    t, x = logs["time"], logs["state"]
    if len(t) < 2:
        raise ValueError("the run has fewer than two logged samples to animate")
    n = scenario.robot.num_links
    alpha_desired = logs["lhs_log"][:, LhsLog(n).alpha_desired]
    meshcat = meshcat or Meshcat()
    builder = DiagramBuilder()
    plant, scene_graph = AddFreeFloatingArm(builder, scenario.robot)
    visualizer = MeshcatVisualizer.AddToBuilder(
        builder, scene_graph, meshcat, MeshcatVisualizerParams(publish_period=1.0 / fps))
    diagram = builder.Build()
    context = diagram.CreateDefaultContext()
    plant_context = plant.GetMyContextFromRoot(context)
    visualizer_context = visualizer.GetMyContextFromRoot(context)
    end_effector = plant.GetFrameByName(END_EFFECTOR)
    reach = scenario.robot.base.size / 2 + sum(link.length for link in scenario.robot.links)
    view = 1.2 * reach + float(np.max(np.abs(x[:, :2])))
    meshcat.Set2dRenderMode(RigidTransform(RotationMatrix(
        np.array([[1.0, 0, 0], [0, 0, 1.0], [0, -1.0, 0]])), [0, 0, 1.0]),
        -view, view, -view, view)
    meshcat.SetObject(DESIRED_PATH, Box(DESIRED_LENGTH, 0.008, 0.008),
                      Rgba(0.85, 0.1, 0.1, 0.9))

    speedup = playback_speedup(t[-1] - t[0], max_playback)
    frames = np.arange(t[0], t[-1] + 1e-12, speedup / fps)
    rows = np.minimum(np.searchsorted(t, frames), len(t) - 1)
    visualizer.StartRecording(set_transforms_while_recording=False)
    for row in rows:
        playback_time = (t[row] - t[0]) / speedup
        context.SetTime(playback_time)
        plant.SetPositions(plant_context, x[row, :plant.num_positions()])
        visualizer.ForcedPublish(visualizer_context)
        X_WE = end_effector.CalcPoseInWorld(plant_context)
        direction = np.array([np.cos(alpha_desired[row]), np.sin(alpha_desired[row]), 0])
        meshcat.SetTransform(
            DESIRED_PATH,
            RigidTransform(RotationMatrix.MakeZRotation(alpha_desired[row]),
                           X_WE.translation() + 0.5 * DESIRED_LENGTH * direction
                           + [0, 0, 0.02]),
            playback_time)
    visualizer.StopRecording()
    visualizer.PublishRecording()
    out = Path(out_html)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(meshcat.StaticHtml())
    return out
