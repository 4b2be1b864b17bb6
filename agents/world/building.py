"""The building as the social map and the simulator see it: walls, rooms, doors, footprints.

Why one module: the simulator's laser and bumper, the social map's walls and the executive's free
space must agree on where a closed door's leaf is and what blocks; each used to derive it itself.
"""

from __future__ import annotations

from collections.abc import Iterable

import shapely
from shapely.geometry import Polygon

from agents.lib.socialmap.types import Room, Wall
from scenes.geometry import posed_polygon
from scenes.model import Scene

DOOR_LEAF_OVERLAP_M = 0.05   # a closed leaf overlaps the wall on each side, so no gap is left
# Clearance the navigation keeps beyond the robot's body when planning (the controller cuts
# corners a little when following a path); goal poses chosen by the executive respect it too,
# and `chronav scene check` checks goals against it.
PLANNING_MARGIN_M = 0.15


def scene_walls(scene: Scene) -> list[Wall]:
    return [Wall(points=tuple(map(tuple, wall)), name=f"wall{i}") for i, wall in enumerate(scene.walls)]


def scene_rooms(scene: Scene) -> list[Room]:
    return [Room(name=room.name, polygon=tuple(map(tuple, room.polygon))) for room in scene.rooms]


def door_segment(scene: Scene, door_name: str) -> tuple[tuple[float, float], tuple[float, float]]:
    """The door leaf when closed: a segment across the opening, along the wall the two rooms share."""
    door = next(d for d in scene.doors if d.name == door_name)
    a, b = (shapely.Polygon(next(r.polygon for r in scene.rooms if r.name == name)) for name in door.between)
    shared = a.boundary.intersection(b.boundary)
    centre = shapely.Point(door.position)
    half = door.width / 2 + DOOR_LEAF_OVERLAP_M
    if shared.is_empty or shared.length == 0:
        return ((door.position[0] - half, door.position[1]), (door.position[0] + half, door.position[1]))
    along = shared.project(centre)
    p0 = shared.interpolate(max(0.0, along - 0.01))
    p1 = shared.interpolate(min(shared.length, along + 0.01))
    dx, dy = p1.x - p0.x, p1.y - p0.y
    norm = (dx * dx + dy * dy) ** 0.5 or 1.0
    ux, uy = dx / norm, dy / norm
    x, y = door.position
    return ((x - half * ux, y - half * uy), (x + half * ux, y + half * uy))


def closed_door_walls(scene: Scene, closed: Iterable[str]) -> list[Wall]:
    """The leaves of the closed doors, as walls (sorted by name: the static map's cache key)."""
    known = {d.name for d in scene.doors}
    return [Wall(points=door_segment(scene, name), name=f"door {name}") for name in sorted(set(closed)) if name in known]


def footprint_polygons(scene: Scene) -> list[Polygon]:
    return [posed_polygon(obj.footprint, obj.pose.x, obj.pose.y, obj.pose.theta) for obj in scene.objects]


def room_at(scene: Scene, x: float, y: float) -> str | None:
    """Name of the room containing (x, y) (first match), or None."""
    return scene.room_at(x, y)
