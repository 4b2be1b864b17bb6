"""Rerun views of bodies: the robot (pose, heading, laser, trail, speed) and the tracked people."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

ROBOT_RGB = (30, 120, 255)
PEOPLE_RGB = (240, 160, 40)
LASER_RGB = (255, 60, 60)
VELOCITY_RGB = (250, 90, 200)
TRACK_RGB = (200, 140, 60)
PREDICTED_RGB = (250, 90, 200, 120)


def _heading(x: float, y: float, theta: float, length: float) -> list[list[float]]:
    return [[x, y], [x + length * math.cos(theta), y + length * math.sin(theta)]]


def log_robot(rec: Any, name: str, radius: float, pose: tuple[float, float, float], speed_mps: float,
              laser_points: Any, trail: Sequence[Sequence[float]]) -> None:
    """The robot at the recorder's current sim time; the trail only every 10 samples (it grows)."""
    if not rec.enabled:
        return
    import rerun as rr

    x, y, theta = pose
    rec.log("world/robot/pose", rr.Points2D([[x, y]], radii=radius, colors=[ROBOT_RGB], labels=[name]))
    rec.log("world/robot/heading", rr.LineStrips2D([_heading(x, y, theta, 0.5)], colors=[ROBOT_RGB], radii=0.03))
    rec.log("world/robot/laser", rr.Points2D(laser_points, radii=0.03, colors=[LASER_RGB]))
    rec.scalar("metrics/robot/speed_m_s", speed_mps)
    if trail and len(trail) % 10 == 0:
        rec.line_strip("world/robot/trajectory", trail, color=ROBOT_RGB, radius=0.02)


def log_people(rec: Any, tracks: Mapping[str, tuple[float, float, float]],
               velocities: Mapping[str, tuple[float, float]] | None = None,
               trails: Mapping[str, Sequence[Sequence[float]]] | None = None,
               predictions: Sequence[Any] = ()) -> None:
    """Tracked people: positions with their names, where they face, their estimated velocity (an
    arrow of the distance walked in one second), the track behind each (last minute) and the
    positions the social map predicts for the walkers (fading with the prediction time)."""
    if not rec.enabled or not tracks:
        return
    import rerun as rr

    names = sorted(tracks)
    xy = [[tracks[n][0], tracks[n][1]] for n in names]
    rec.log("world/people/positions", rr.Points2D(xy, radii=0.25, colors=[PEOPLE_RGB], labels=names))
    heads = [_heading(*tracks[n], 0.45) for n in names]
    rec.log("world/people/headings", rr.LineStrips2D(heads, colors=[PEOPLE_RGB], radii=0.03))
    if velocities is not None:
        moving = [n for n in names if math.hypot(*velocities.get(n, (0.0, 0.0))) > 0.05]
        rec.log("world/people/velocities", rr.Arrows2D(origins=[xy[names.index(n)] for n in moving],
                                                         vectors=[list(velocities[n]) for n in moving],
                                                         colors=[VELOCITY_RGB], radii=0.03))
    if trails is not None:
        strips = [list(map(list, trail)) for trail in trails.values() if len(trail) >= 2]
        rec.log("world/people/tracks", rr.LineStrips2D(strips, colors=[TRACK_RGB], radii=0.015))
    points, radii = [], []
    for prediction in predictions:
        for (x, y), w in zip(prediction.points, prediction.weights, strict=True):
            points.append([float(x), float(y)])
            radii.append(0.05 + 0.2 * float(w))
    rec.log("world/people/predicted", rr.Points2D(points, radii=radii, colors=[PREDICTED_RGB]))
