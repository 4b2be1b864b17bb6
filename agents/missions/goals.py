"""Turn symbolic targets (a room, an object, a person) into a pose the robot can drive to.

Why geometry here and not in the grammar: rules speak of "near the TV" or "facing senior_1";
the navigation agent needs (x, y, theta).  A care-home robot must also pick a *polite* pose:
not inside a running activity's interaction space, not in anyone's personal space, clear of
walls by its radius, and the reachable candidate closest to where it stands.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import shapely
from shapely.ops import nearest_points
from shapely.geometry.base import BaseGeometry

from scenes.geometry import posed_polygon
from agents.lib.socialmap.types import Person, SocialObject
from agents.world.building import FreeArea
from agents.world.navigation import PLANNING_MARGIN_M
from scenes.model import Scene

SOCIAL_DISTANCE_M = 1.3      # approachPerson: in front of the person, outside the personal zone
OBJECT_CLEARANCE_M = 0.35    # goToObject: gap between the robot's body and the object's footprint
PERSON_KEEP_OUT_M = 0.9      # no candidate pose closer than this to anyone else


class GoalError(ValueError):
    """The target exists but no polite, free pose near it could be found."""


@dataclass(frozen=True)
class GoalPose:
    x: float
    y: float
    theta: float | None  # None: any final heading is fine

    def as_attrs(self) -> dict[str, float | bool]:
        return {"goal_x": self.x, "goal_y": self.y, "goal_theta": self.theta if self.theta is not None else 0.0,
                "goal_has_theta": self.theta is not None}


class FreeSpace:
    """Where the robot's centre may stand: inside the building, clear of walls and footprints."""

    def __init__(self, scene: Scene, objects: Sequence[SocialObject]) -> None:
        # The planner's inflation (body + margin) plus a cell, so a chosen goal is always traversable.
        clearance = scene.robot.radius + PLANNING_MARGIN_M + scene.resolution
        # The building's walls (polylines and a map's wall cells) come from the world model.
        self.area = FreeArea(scene, [posed_polygon(o.footprint, o.x, o.y, o.theta) for o in objects], clearance)

    def ok(self, x: float, y: float, people: Iterable[Person], ignore: str | None = None) -> bool:
        if not self.area.contains(x, y):
            return False
        return all(math.hypot(p.x - x, p.y - y) >= PERSON_KEEP_OUT_M for p in people if p.name != ignore)


def _nearest(candidates: list[tuple[float, float, float | None]], robot_xy: tuple[float, float]) -> GoalPose:
    if not candidates:
        raise GoalError("no free pose")
    x, y, theta = min(candidates, key=lambda c: math.hypot(c[0] - robot_xy[0], c[1] - robot_xy[1]))
    return GoalPose(x, y, theta)


def pose_near_object(obj: SocialObject, free: FreeSpace, people: Sequence[Person], busy_spaces: Sequence[BaseGeometry],
                     robot_xy: tuple[float, float], robot_radius: float) -> GoalPose:
    """A pose facing the object, just clear of its footprint, outside running activities' spaces."""
    footprint = posed_polygon(obj.footprint, obj.x, obj.y, obj.theta)
    ring = footprint.buffer(robot_radius + OBJECT_CLEARANCE_M).exterior
    candidates: list[tuple[float, float, float | None]] = []
    for i in range(72):
        point = ring.interpolate(i / 72, normalized=True)
        if any(space.contains(point) for space in busy_spaces):
            continue
        if free.ok(point.x, point.y, people):
            nearest = nearest_points(footprint, point)[0]
            candidates.append((point.x, point.y, math.atan2(nearest.y - point.y, nearest.x - point.x)))
    try:
        return _nearest(candidates, robot_xy)
    except GoalError:
        raise GoalError(f"no free pose near object {obj.name!r}") from None


def pose_facing_person(person: Person, free: FreeSpace, people: Sequence[Person],
                       robot_xy: tuple[float, float]) -> GoalPose:
    """In front of the person at social distance, facing them; swing sideways if the front is taken,
    and round to her side or back only if nothing in front is free (a walker heading for a wall or
    a table has no free front for a moment: better approached from the side than not at all)."""
    candidates: list[tuple[float, float, float | None]] = []
    for swing_deg in (0, 20, -20, 40, -40, 60, -60, 80, -80, 100, -100, 120, -120, 140, -140, 160, -160, 180):
        angle = person.theta + math.radians(swing_deg)
        x = person.x + SOCIAL_DISTANCE_M * math.cos(angle)
        y = person.y + SOCIAL_DISTANCE_M * math.sin(angle)
        if free.ok(x, y, people, ignore=person.name):
            candidates.append((x, y, math.atan2(person.y - y, person.x - x)))
            break  # the most frontal free pose wins: people expect to be approached from the front
    try:
        return _nearest(candidates, robot_xy)
    except GoalError:
        raise GoalError(f"no free pose around {person.name!r} at {SOCIAL_DISTANCE_M:g} m") from None


def pose_facing_group(members: Sequence[Person], free: FreeSpace, people: Sequence[Person],
                      robot_xy: tuple[float, float]) -> GoalPose:
    """takeTheAttention: face the group's centre from outside it, on the side nearest the robot."""
    if not members:
        raise GoalError("empty group")
    cx = sum(p.x for p in members) / len(members)
    cy = sum(p.y for p in members) / len(members)
    spread = max(math.hypot(p.x - cx, p.y - cy) for p in members)
    candidates: list[tuple[float, float, float | None]] = []
    for i in range(36):
        angle = 2 * math.pi * i / 36
        x, y = cx + (spread + SOCIAL_DISTANCE_M) * math.cos(angle), cy + (spread + SOCIAL_DISTANCE_M) * math.sin(angle)
        if free.ok(x, y, people):
            candidates.append((x, y, math.atan2(cy - y, cx - x)))
    try:
        return _nearest(candidates, robot_xy)
    except GoalError:
        names = ", ".join(p.name for p in members)
        raise GoalError(f"no free pose facing the group ({names})") from None


def pose_in_room(room_name: str, scene: Scene, free: FreeSpace, people: Sequence[Person],
                 busy_spaces: Sequence[BaseGeometry], robot_xy: tuple[float, float]) -> GoalPose:
    """A free spot in the room, away from running activities, as near its centre as possible."""
    room = next((r for r in scene.rooms if r.name == room_name), None)
    if room is None:
        raise GoalError(f"unknown room {room_name!r}")
    polygon = shapely.Polygon(room.polygon)
    centre = polygon.centroid if polygon.contains(polygon.centroid) else polygon.point_on_surface()
    xmin, ymin, xmax, ymax = polygon.bounds
    step = 0.25
    candidates: list[tuple[float, float, float | None]] = []
    y = ymin + step / 2
    while y < ymax:
        x = xmin + step / 2
        while x < xmax:
            point = shapely.Point(x, y)
            if polygon.contains(point) and free.ok(x, y, people) and not any(s.contains(point) for s in busy_spaces):
                candidates.append((x, y, None))
            x += step
        y += step
    if not candidates:
        raise GoalError(f"no free pose in room {room_name!r}")
    x, y, _ = min(candidates, key=lambda c: math.hypot(c[0] - centre.x, c[1] - centre.y))
    del robot_xy  # the room's centre, not the nearest corner: "go to the dining room" means into it
    return GoalPose(x, y, None)


def pose_past_door(door_name: str, room_name: str, scene: Scene, free: FreeSpace, people: Sequence[Person],
                   past_m: float = 0.7) -> GoalPose:
    """changeRoom: a point just inside ``room_name`` beyond the door, to pass through (no heading)."""
    door = next((d for d in scene.doors if d.name == door_name), None)
    room = next((r for r in scene.rooms if r.name == room_name), None)
    if door is None or room is None:
        raise GoalError(f"unknown door {door_name!r} or room {room_name!r}")
    polygon = shapely.Polygon(room.polygon)
    dx, dy = door.position
    candidates: list[tuple[float, float, float | None]] = []
    for distance in (past_m, past_m + 0.4, past_m + 0.8):
        for i in range(16):
            angle = 2 * math.pi * i / 16
            x, y = dx + distance * math.cos(angle), dy + distance * math.sin(angle)
            if polygon.contains(shapely.Point(x, y)) and free.ok(x, y, people):
                candidates.append((x, y, None))
        if candidates:
            break
    if not candidates:
        raise GoalError(f"no free spot past door {door_name!r} in {room_name!r}")
    # The spot straightest through the door: farthest from the door's own room boundary.
    x, y, _ = max(candidates, key=lambda c: polygon.exterior.distance(shapely.Point(c[0], c[1])))
    return GoalPose(x, y, None)
