"""The script of a ``stay`` person: their pose at a time along their timed waypoints.

Why here: a scripted person is part of the crowd (agents/world/people.py), which places them
exactly where this says; the crowd is what the simulator, the observer and the offline commands
share, so this is called only through it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from scenes.clock import parse_clock
from scenes.geometry import lerp_angle
from scenes.model import PersonSpec


@dataclass(frozen=True)
class PersonState:
    name: str
    role: str
    x: float
    y: float
    theta: float
    moving: bool


def person_at(person: PersonSpec, t_s: float) -> PersonState:
    """Pose at ``t_s`` (seconds since midnight): initial pose before the first waypoint, the last
    waypoint after the end, straight-line interpolation in between (walking, heading along)."""
    if not person.waypoints or t_s <= parse_clock(person.waypoints[0].time):
        pose = person.pose
        return PersonState(person.name, person.role, pose.x, pose.y, pose.theta, False)
    for before, after in zip(person.waypoints, person.waypoints[1:], strict=False):
        t0, t1 = parse_clock(before.time), parse_clock(after.time)
        if t0 <= t_s < t1:
            f = (t_s - t0) / (t1 - t0)
            a, b = before.pose, after.pose
            dx, dy = b.x - a.x, b.y - a.y
            if math.hypot(dx, dy) > 1e-6:
                # Walking: face the direction of travel, turning to the final heading at the end.
                heading = math.atan2(dy, dx) if f < 0.9 else lerp_angle(math.atan2(dy, dx), b.theta, (f - 0.9) / 0.1)
                return PersonState(person.name, person.role, a.x + f * dx, a.y + f * dy, heading, True)
            return PersonState(person.name, person.role, a.x, a.y, lerp_angle(a.theta, b.theta, f), False)
    last = person.waypoints[-1].pose
    return PersonState(person.name, person.role, last.x, last.y, last.theta, False)
