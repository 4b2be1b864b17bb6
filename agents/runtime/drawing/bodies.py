"""Rerun views of bodies: the robot (pose, heading, laser, trail, speed) and the tracked people."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

ROBOT_RGB = (30, 120, 255)
PEOPLE_RGB = (240, 160, 40)
LASER_RGB = (255, 60, 60)


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


def log_people(rec: Any, tracks: Mapping[str, tuple[float, float, float]]) -> None:
    """Tracked people: positions with their names, and where they face."""
    if not rec.enabled or not tracks:
        return
    import rerun as rr

    names = sorted(tracks)
    xy = [[tracks[n][0], tracks[n][1]] for n in names]
    rec.log("world/people/positions", rr.Points2D(xy, radii=0.25, colors=[PEOPLE_RGB], labels=names))
    heads = [_heading(*tracks[n], 0.45) for n in names]
    rec.log("world/people/headings", rr.LineStrips2D(heads, colors=[PEOPLE_RGB], radii=0.03))
