"""Rerun views of bodies, in two layers that are never mixed.

* **world** (``world/truth/...``, logged by the simulator): the robot's true pose, heading,
  laser and driven trail, and every person's true position - what was, at each instant.
* **belief** (``world/belief/...``, logged by the human observer): the people as tracked (short
  ids, velocities, recent tracks) and where the social map predicts the walkers go.

Why apart: a researcher must tell "the observer lagged" from "the robot ignored someone".  The
true positions are small white dots drawn over the belief's orange discs: when the two agree a
person is an orange disc with a white centre; a white dot away from its disc is belief gone
stale (its age is printed in the decision layer's stamp, agents/runtime/drawing/social_map.py).

Why these colours: the robot is the one green body, larger, drawn on top of everything with a
white heading arrow, so it is found at a glance; its trail keeps only the last minutes, thin
and faint, so old loops never read as zones (zones are red / purple / blue outlines).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

from agents.runtime.drawing.labels import declutter, short_ids

ROBOT_RGB = (0, 230, 90)
ROBOT_TRAIL_RGBA = (0, 230, 90, 110)
HEADING_RGB = (255, 255, 255)
PEOPLE_RGB = (240, 160, 40)
TRUTH_RGB = (245, 245, 245)
LASER_RGB = (255, 60, 60)
VELOCITY_RGB = (250, 90, 200)
TRACK_RGBA = (200, 140, 60, 140)
PREDICTED_RGBA = (250, 90, 200, 120)
ROBOT_TRAIL_S = 180.0     # sim seconds of driven trail shown behind the robot
TRAIL_EVERY = 5           # the trail strip is re-logged every TRAIL_EVERY poses (it grows)

# Draw order (higher on top): map image < zones < objects < tracks < people < truth < robot.
ORDER_TRAIL, ORDER_TRACKS, ORDER_PEOPLE, ORDER_TRUTH, ORDER_LASER, ORDER_ROBOT = 5.0, 8.0, 30.0, 40.0, 45.0, 100.0


def _heading(x: float, y: float, theta: float, length: float) -> list[list[float]]:
    return [[x, y], [x + length * math.cos(theta), y + length * math.sin(theta)]]


def log_robot(rec: Any, name: str, radius: float, pose: tuple[float, float, float], speed_mps: float,
              laser_points: Any, trail: Sequence[Sequence[float]], trail_times: Sequence[float] = (),
              now_s: float | None = None) -> None:
    """The robot's true state at the recorder's current sim time (world layer).  ``trail_times``
    (sim s per trail point) and ``now_s`` cut the trail to the last ROBOT_TRAIL_S before now."""
    if not rec.enabled:
        return
    import rerun as rr

    x, y, theta = pose
    # A white halo under the green disc: the robot stands out on any floor, zone or person.
    rec.log("world/truth/robot/halo", rr.Points2D([[x, y]], radii=max(radius, 0.2) + 0.07, colors=[HEADING_RGB],
                                                   draw_order=ORDER_ROBOT - 1))
    rec.log("world/truth/robot/body", rr.Points2D([[x, y]], radii=max(radius, 0.2), colors=[ROBOT_RGB],
                                                   labels=[name], show_labels=False, draw_order=ORDER_ROBOT))
    rec.log("world/truth/robot/heading", rr.Arrows2D(origins=[[x, y]], vectors=[[0.8 * math.cos(theta),
                                                                                  0.8 * math.sin(theta)]],
                                                       colors=[HEADING_RGB], radii=0.06,
                                                       draw_order=ORDER_ROBOT + 1))
    rec.log("world/truth/robot/laser", rr.Points2D(laser_points, radii=0.03, colors=[LASER_RGB],
                                                    draw_order=ORDER_LASER))
    rec.scalar("metrics/robot/speed_m_s", speed_mps)
    recent = list(trail)
    if trail_times and len(trail_times) == len(trail):
        cut = (now_s if now_s is not None else trail_times[-1]) - ROBOT_TRAIL_S
        recent = [p for p, t in zip(trail, trail_times, strict=True) if t >= cut]
    # Re-logged as it grows (every TRAIL_EVERY poses, however many frames were not drawn between:
    # agents/runtime/recording.FramePacer), when it was cut, and once when it has aged out entirely.
    shown = getattr(rec, "_trail_shown", 0)
    grown = len(trail) - shown
    if len(recent) >= 2 and (shown == 0 or grown >= TRAIL_EVERY or grown < 0):
        rec.log("world/truth/robot/trail", rr.LineStrips2D([list(map(list, recent))], colors=[ROBOT_TRAIL_RGBA],
                                                           radii=0.02, draw_order=ORDER_TRAIL))
        rec._trail_shown = len(trail)
    elif len(recent) < 2 and shown:
        rec.log("world/truth/robot/trail", rr.Clear(recursive=False))
        rec._trail_shown = 0


def log_true_people(rec: Any, names: Sequence[str], xy: Sequence[Sequence[float]]) -> None:
    """Where every person truly is (world layer): small white dots, names on hover only."""
    if not rec.enabled:
        return
    import rerun as rr

    rec.log("world/truth/people", rr.Points2D([list(p) for p in xy], radii=0.09, colors=[TRUTH_RGB],
                                              labels=list(names), show_labels=False, draw_order=ORDER_TRUTH))


def log_people(rec: Any, tracks: Mapping[str, tuple[float, float, float]],
               velocities: Mapping[str, tuple[float, float]] | None = None,
               trails: Mapping[str, Sequence[Sequence[float]]] | None = None,
               predictions: Sequence[Any] = ()) -> None:
    """Tracked people (belief layer): positions with short decluttered ids, where they face,
    their estimated velocity (an arrow of the distance walked in one second), the track behind
    each and the positions the social map predicts for the walkers (fading with the time)."""
    if not rec.enabled or not tracks:
        return
    import rerun as rr

    names = sorted(tracks)
    xy = [[tracks[n][0], tracks[n][1]] for n in names]
    labels = declutter(short_ids(names), xy)
    rec.log("world/belief/people/positions", rr.Points2D(xy, radii=0.25, colors=[PEOPLE_RGB], labels=labels,
                                                          draw_order=ORDER_PEOPLE))
    heads = [_heading(*tracks[n], 0.45) for n in names]
    rec.log("world/belief/people/headings", rr.LineStrips2D(heads, colors=[PEOPLE_RGB], radii=0.03,
                                                             draw_order=ORDER_PEOPLE))
    if velocities is not None:
        moving = [n for n in names if math.hypot(*velocities.get(n, (0.0, 0.0))) > 0.05]
        rec.log("world/belief/people/velocities", rr.Arrows2D(origins=[xy[names.index(n)] for n in moving],
                                                                vectors=[list(velocities[n]) for n in moving],
                                                                colors=[VELOCITY_RGB], radii=0.03,
                                                                draw_order=ORDER_PEOPLE))
    if trails is not None:
        strips = [list(map(list, trail)) for trail in trails.values() if len(trail) >= 2]
        rec.log("world/belief/people/tracks", rr.LineStrips2D(strips, colors=[TRACK_RGBA], radii=0.015,
                                                               draw_order=ORDER_TRACKS))
    points, radii = [], []
    for prediction in predictions:
        for (x, y), w in zip(prediction.points, prediction.weights, strict=True):
            points.append([float(x), float(y)])
            radii.append(0.05 + 0.2 * float(w))
    rec.log("world/belief/people/predicted", rr.Points2D(points, radii=radii, colors=[PREDICTED_RGBA],
                                                          draw_order=ORDER_TRACKS))
