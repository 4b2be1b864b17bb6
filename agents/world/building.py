"""The building as the social map and the simulator see it: walls, rooms, doors, footprints.

Why one module: the simulator's laser and bumper, the social map's walls and the executive's free
space must agree on where a closed door's leaf is and what blocks; each used to derive it itself.
A scene on a building map (``map:``, scenes/occupancy.py) has walls of two kinds, the polylines and
the map's wall cells (:func:`scene_occupancy`); every consumer takes both from here.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from functools import lru_cache

import shapely
from shapely.geometry import Polygon

from agents.lib.socialmap.grid import GridSpec
from agents.lib.socialmap.occupancy import OccupancyLayer
from agents.lib.socialmap.types import Room, Wall
from scenes.geometry import posed_polygon
from scenes.model import Scene
from scenes.occupancy import OccupancyMap

DOOR_LEAF_OVERLAP_M = 0.05   # a closed leaf overlaps the wall on each side, so no gap is left
# Clearance the navigation keeps beyond the robot's body when planning (the controller cuts
# corners a little when following a path); goal poses chosen by the executive respect it too,
# and `chronav scene check` checks goals against it.
PLANNING_MARGIN_M = 0.15


def scene_walls(scene: Scene) -> list[Wall]:
    return [Wall(points=tuple((x, y) for x, y in wall), name=f"wall{i}") for i, wall in enumerate(scene.walls)]


def scene_rooms(scene: Scene) -> list[Room]:
    return [Room(name=room.name, polygon=tuple((x, y) for x, y in room.polygon)) for room in scene.rooms]


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


@lru_cache(maxsize=8)
def _occupancy_layer(occupancy: OccupancyMap, unknown_is_wall: bool) -> OccupancyLayer:
    """One layer per loaded map (its inflations are cached on it, so build it once per process)."""
    spec = GridSpec(x0=occupancy.x0, y0=occupancy.y0, resolution=occupancy.resolution,
                    rows=occupancy.rows, cols=occupancy.cols)
    return OccupancyLayer(spec, occupancy.blocked(unknown_is_wall), outside_blocked=unknown_is_wall,
                          name=occupancy.yaml_path.name)


def scene_occupancy(scene: Scene) -> OccupancyLayer | None:
    """The wall cells of the scene's building map (occupied, and unknown unless ``unknown: free``);
    None for a scene of polylines only."""
    occupancy = scene.occupancy
    if occupancy is None or scene.map is None:
        return None
    return _occupancy_layer(occupancy, scene.map.unknown == "wall")


class FreeArea:
    """Where the robot's centre may stand: inside the rooms, ``clearance`` away from every wall
    (polylines, and the map's wall cells inflated as the planner inflates them) and footprint."""

    def __init__(self, scene: Scene, footprints: Sequence[Polygon], clearance_m: float) -> None:
        building = shapely.union_all([shapely.Polygon(r.polygon) for r in scene.rooms])
        walls = [w for w in scene.walls if len(w) >= 2]
        if walls:
            building = building.difference(shapely.MultiLineString(walls).buffer(clearance_m))
        if footprints:
            building = building.difference(shapely.union_all(list(footprints)).buffer(clearance_m))
        self.region = building
        shapely.prepare(self.region)
        self.occupancy = scene_occupancy(scene)
        self.clearance_m = clearance_m

    def contains(self, x: float, y: float) -> bool:
        if not self.region.contains(shapely.Point(x, y)):
            return False
        return self.occupancy is None or not self.occupancy.inflated_at(x, y, self.clearance_m)
