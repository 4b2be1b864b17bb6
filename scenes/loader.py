"""Load and check scene files: schema first, then geometry a person would get wrong.

Why a separate geometric pass: pydantic can say a pose is three numbers, but only the room
polygons can say that a person standing at (40, 2) is outside the building.  Both kinds of error
point at the line of the offending key.
"""

from __future__ import annotations

import difflib
from collections.abc import Sequence
from dataclasses import dataclass
from datetime import date
from pathlib import Path
from typing import Protocol

import math

import numpy as np
import shapely
import shapely.ops

from scenes.clock import parse_clock
from scenes.days import day_number, scene_dates
from scenes.geometry import posed_polygon

from scenes.model import PersonSpec, Pose, Room, Scene
from scenes.occupancy import OccupancyMap, load_occupancy
from scenes.raster import cells_in_polygon
from scenes.yamlio import KeyPath, LocatedYaml, SourceError, load_located_file, validate_located

SCENES_DIR = Path(__file__).resolve().parent


@dataclass
class LoadedScene:
    """A validated scene plus where it came from (agenda files resolve relative to it) and where
    each of its keys is in the file (so checks made later, by the world model, are located too)."""

    scene: Scene
    path: Path
    located: LocatedYaml

    def resolve(self, relative: str) -> Path:
        candidate = Path(relative)
        return candidate if candidate.is_absolute() else (self.path.parent / candidate)

    def error(self, key: tuple[str | int, ...], message: str) -> SourceError:
        """An error at ``key``'s line in the scene file."""
        return self.located.error(key, message)


def resolve_scene_path(name_or_path: str | Path) -> Path:
    """Accept a path or a bare scene name shipped in ``scenes/`` (``icra_usecase``)."""
    path = Path(name_or_path)
    if path.exists():
        return path
    for candidate in (SCENES_DIR / path, SCENES_DIR / f"{path}.yaml"):
        if candidate.exists():
            return candidate
    raise SourceError(str(path), 1, 1, "", "no such scene file")


# A person's body, as the social map blocks it (agents/lib/socialmap/grid.py GridParams.person_radius_m).
PERSON_BODY_RADIUS_M = 0.25
# How far a door's centre may lie from each of its rooms' outlines.
DOOR_ON_WALL_TOLERANCE_M = 0.1


class _Named(Protocol):
    """Any named item of a scene (room, object, person, door)."""

    @property
    def name(self) -> str: ...


@dataclass(frozen=True)
class _Names:
    """The names a scene declares, by kind: what its references may point at."""

    rooms: set[str]
    objects: set[str]
    people: set[str]
    doors: set[str]

    @classmethod
    def of(cls, scene: Scene) -> _Names:
        return cls(rooms={r.name for r in scene.rooms}, objects={o.name for o in scene.objects},
                   people={p.name for p in scene.people}, doors={d.name for d in scene.doors})


def _unknown(kind: str, value: str, known: set[str]) -> str:
    """The message for a reference to no known name: the closest name, then all of that kind."""
    close = difflib.get_close_matches(value, sorted(known), n=1)
    hint = f"did you mean {close[0]!r}? " if close else ""
    return f"no {kind} named {value!r}; {hint}{kind}s: {', '.join(sorted(known)) or 'none'}"


def _check_references(scene: Scene, located: LocatedYaml) -> None:
    """Names unique, references resolved: located at the key that is wrong, not at the file's start."""
    _check_unique_names(scene, located)
    names = _Names.of(scene)
    _check_door_references(scene, located, names)
    for i, person in enumerate(scene.people):
        _check_waypoint_order(i, person, located)
        _check_person_references(i, person, located, names)
    _check_mission_references(scene, located, names)
    _check_change_days(scene, located)


def _check_change_days(scene: Scene, located: LocatedYaml) -> None:
    """A scripted change names a day of the scene (1 to clock.days, or a date among them)."""
    first, days = scene.clock.date, scene.clock.days
    named: list[tuple[str, list[date | int | None]]] = [
        ("agenda_changes", [c.day for c in scene.agenda_changes]), ("door_changes", [c.day for c in scene.door_changes])]
    for section, changes in named:
        for i, day in enumerate(changes):
            number = day_number(day, first)
            if not 1 <= number <= days:
                last = scene_dates(first, days)[-1]
                raise located.error((section, i, "day"), f"day {day} is not a day of this scene: it spans "
                                    f"{days} day{'s' if days > 1 else ''}, {first.isoformat()} to "
                                    f"{last.isoformat()} (set clock.days, or name a day 1 to {days})")


def _check_unique_names(scene: Scene, located: LocatedYaml) -> None:
    """No two rooms, objects, people or doors share a name."""
    named: tuple[tuple[str, str, Sequence[_Named]], ...] = (
        ("room", "rooms", scene.rooms), ("object", "objects", scene.objects),
        ("person", "people", scene.people), ("door", "doors", scene.doors))
    for kind, section, items in named:
        seen: dict[str, int] = {}
        for index, item in enumerate(items):
            if item.name in seen:
                line, _ = located.where((section, seen[item.name], "name"))
                raise located.error((section, index, "name"), f"duplicate {kind} name {item.name!r} (first on line "
                                    f"{line}); give each {kind} its own name")
            seen[item.name] = index


def _check_door_references(scene: Scene, located: LocatedYaml, names: _Names) -> None:
    """Each door joins two different known rooms; each door change names a known door."""
    for i, door in enumerate(scene.doors):
        for j, room in enumerate(door.between):
            if room not in names.rooms:
                raise located.error(("doors", i, "between", j), _unknown("room", room, names.rooms))
        if door.between[0] == door.between[1]:
            raise located.error(("doors", i, "between", 1), f"door {door.name!r} joins room {door.between[0]!r} "
                                "to itself; name the two rooms it connects")
    for i, change in enumerate(scene.door_changes):
        if change.door not in names.doors:
            raise located.error(("door_changes", i, "door"), _unknown("door", change.door, names.doors))


def _check_waypoint_order(i: int, person: PersonSpec, located: LocatedYaml) -> None:
    """A person's waypoints go in strictly increasing time."""
    times = [parse_clock(w.time) for w in person.waypoints]
    for j in range(1, len(times)):
        if times[j] <= times[j - 1]:
            raise located.error(("people", i, "waypoints", j, "time"),
                                f"{person.waypoints[j].time} is not after the previous waypoint's "
                                f"{person.waypoints[j - 1].time}; waypoints go in time order")


def _check_person_references(i: int, person: PersonSpec, located: LocatedYaml, names: _Names) -> None:
    """A person's home and rooms are known rooms; whom they visit or interact with, known other people."""
    people = names.people
    if person.home is not None and person.home not in names.rooms:
        raise located.error(("people", i, "home"), _unknown("room", person.home, names.rooms))
    for j, room in enumerate(person.rooms):
        if room not in names.rooms:
            raise located.error(("people", i, "rooms", j), _unknown("room", room, names.rooms))
    if person.visits is not None:
        if person.visits == person.name:
            raise located.error(("people", i, "visits"), f"{person.name!r} cannot visit themself")
        if person.visits not in people:
            raise located.error(("people", i, "visits"), _unknown("person", person.visits, people))
    for j, other in enumerate(person.interacting_with):
        key: KeyPath = ("people", i, "interacting_with", j)
        if other in names.objects:
            raise located.error(key, f"{other!r} is an object; links to objects come from the agenda: add "
                                f"an activity on it with {person.name!r} among its participants")
        if other == person.name:
            raise located.error(key, f"{person.name!r} cannot interact with themself")
        if other not in people:
            raise located.error(key, _unknown("person", other, people))


def _check_mission_references(scene: Scene, located: LocatedYaml, names: _Names) -> None:
    """Mission ids unique; each goal names a known room, object or person, a group known people once each."""
    seen_ids: dict[str, int] = {}
    for i, mission in enumerate(scene.missions):
        if mission.id in seen_ids:
            line, _ = located.where(("missions", seen_ids[mission.id], "id"))
            raise located.error(("missions", i, "id"), f"duplicate mission id {mission.id!r} (first on line {line})")
        seen_ids[mission.id] = i
        goal = mission.goal
        for kind, known in (("room", names.rooms), ("object", names.objects), ("person", names.people)):
            target = getattr(goal, kind, None)
            if isinstance(target, str) and target not in known:
                raise located.error(("missions", i, "goal", kind), _unknown(kind, target, known))
        members = getattr(goal, "group", None) or []
        for j, member in enumerate(members):
            if member not in names.people:
                raise located.error(("missions", i, "goal", "group", j), _unknown("person", member, names.people))
            if member in members[:j]:
                raise located.error(("missions", i, "goal", "group", j), f"{member!r} is named twice in the group")



def _room_areas(scene: Scene) -> dict[str, shapely.geometry.base.BaseGeometry]:
    """Each room's floor as ``Scene.room_at`` resolves it: its polygon less the rooms listed before
    it.  Why: a corridor drawn around rooms (``scene from-map`` lists the rooms inside a loop
    first) has doors on its inner walls, which its outline alone does not show.  A room the earlier
    ones cover whole keeps its polygon (an empty floor has no boundary to measure a door against)."""
    areas: dict[str, shapely.geometry.base.BaseGeometry] = {}
    taken = shapely.Polygon()
    for room in scene.rooms:
        polygon = shapely.Polygon(room.polygon)
        floor = polygon.difference(taken) if taken.intersects(polygon) else polygon
        areas[room.name] = polygon if floor.is_empty else floor
        taken = taken.union(polygon)
    return areas


class _Solids:
    """The scene's building (rooms' union), walls and object footprints, and the two questions the
    geometry checks ask of a point: inside the building? clear of walls and objects?"""

    def __init__(self, scene: Scene, located: LocatedYaml) -> None:
        self.located = located
        self.building = shapely.union_all([shapely.Polygon(r.polygon) for r in scene.rooms])
        self.walls = shapely.MultiLineString([wall for wall in scene.walls if len(wall) >= 2])
        self.footprints = [(obj.name, posed_polygon(obj.footprint, obj.pose.x, obj.pose.y, obj.pose.theta))
                           for obj in scene.objects]

    def inside(self, key: tuple[str | int, ...], x: float, y: float, what: str) -> None:
        if not self.building.covers(shapely.Point(x, y)):
            raise self.located.error(key, f"{what} at ({x:g}, {y:g}) is outside every room")

    def clear(self, key: tuple[str | int, ...], x: float, y: float, what: str, radius: float,
              body: str) -> None:
        """Nothing solid within ``radius`` of (x, y): not on a wall, not in an object's footprint."""
        point = shapely.Point(x, y)
        walls = self.walls
        if not walls.is_empty and walls.distance(point) < radius:
            near = shapely.ops.nearest_points(walls, point)[0]
            raise self.located.error(key, f"{what} at ({x:g}, {y:g}) is on a wall: the wall at ({near.x:.2f}, "
                                     f"{near.y:.2f}) is {walls.distance(point):.2f} m away, closer than {body} "
                                     f"({radius:g} m); move it into the room")
        for name, footprint in self.footprints:
            if footprint.distance(point) < radius or footprint.covers(point):
                raise self.located.error(key, f"{what} at ({x:g}, {y:g}) is inside object {name!r} (its "
                                         f"footprint is {footprint.distance(point):.2f} m away, closer than "
                                         f"{body}, {radius:g} m); move one of them")


def _check_geometry(scene: Scene, located: LocatedYaml) -> None:
    for index, room in enumerate(scene.rooms):  # before the union: GEOS fails on invalid polygons
        if not shapely.Polygon(room.polygon).is_valid:
            raise located.error(("rooms", index, "polygon"), f"room {room.name!r} polygon self-intersects")
    solids = _Solids(scene, located)
    _check_placements(scene, solids)
    _check_bodies_apart(scene, located)
    _check_routes_clear_of_walls(scene, located, solids.walls)
    _check_doors_on_walls(scene, located, solids)
    _check_goal_poses(scene, solids)


def _check_placements(scene: Scene, solids: _Solids) -> None:
    """The robot, objects, people and waypoints inside the building; bodies clear of walls and objects."""
    robot = scene.robot
    solids.inside(("robot", "pose"), robot.pose.x, robot.pose.y, "robot")
    solids.clear(("robot", "pose"), robot.pose.x, robot.pose.y, "robot", robot.radius, "its radius")
    for i, obj in enumerate(scene.objects):
        solids.inside(("objects", i, "pose"), obj.pose.x, obj.pose.y, f"object {obj.name!r}")
    for i, person in enumerate(scene.people):
        solids.inside(("people", i, "pose"), person.pose.x, person.pose.y, f"person {person.name!r}")
        solids.clear(("people", i, "pose"), person.pose.x, person.pose.y, f"person {person.name!r}",
                     PERSON_BODY_RADIUS_M, "a person's body")
        for j, waypoint in enumerate(person.waypoints):
            key: KeyPath = ("people", i, "waypoints", j, "pose")
            solids.inside(key, waypoint.pose.x, waypoint.pose.y, f"waypoint of {person.name!r}")
            solids.clear(key, waypoint.pose.x, waypoint.pose.y, f"waypoint of {person.name!r}",
                         PERSON_BODY_RADIUS_M, "a person's body")


def _check_routes_clear_of_walls(scene: Scene, located: LocatedYaml, walls: shapely.MultiLineString) -> None:
    """No person's straight walk from one waypoint to the next crosses a wall."""
    for i, person in enumerate(scene.people):
        route = [person.pose, *(w.pose for w in person.waypoints)]
        for j, (a, b) in enumerate(zip(route, route[1:], strict=False)):
            if (a.x, a.y) != (b.x, b.y) and shapely.LineString([(a.x, a.y), (b.x, b.y)]).crosses(walls):
                raise located.error(("people", i, "waypoints", j), f"{person.name!r} would walk through a "
                                    f"wall from ({a.x:g}, {a.y:g}) to ({b.x:g}, {b.y:g}); add a waypoint at the door")


def _check_doors_on_walls(scene: Scene, located: LocatedYaml, solids: _Solids) -> None:
    """Each door inside the building, on the outline of both its rooms, and in a gap of the walls."""
    walls = solids.walls
    areas = _room_areas(scene)
    for i, door in enumerate(scene.doors):
        x, y = door.position
        key = ("doors", i, "position")
        solids.inside(key, x, y, f"door {door.name!r}")
        point = shapely.Point(x, y)
        for room_name in door.between:
            gap = areas[room_name].boundary.distance(point)
            if gap > DOOR_ON_WALL_TOLERANCE_M:
                raise located.error(key, f"door {door.name!r} at ({x:g}, {y:g}) is not on the outline of room "
                                    f"{room_name!r} ({gap:.2f} m from it); a door sits on the wall between its two "
                                    f"rooms {door.between[0]!r} and {door.between[1]!r}")
        clearance = min(door.width / 2, scene.robot.radius) - 0.01
        if not walls.is_empty and walls.distance(point) < clearance:
            raise located.error(key, f"door {door.name!r} at ({x:g}, {y:g}) is on solid wall: a wall passes "
                                f"{walls.distance(point):.2f} m from its centre; leave a gap of the door's width "
                                f"({door.width:g} m) in the wall there")


def _check_goal_poses(scene: Scene, solids: _Solids) -> None:
    """A mission's goal pose inside the building and clear for the robot's body."""
    for i, mission in enumerate(scene.missions):
        pose = getattr(mission.goal, "pose", None)
        if pose is not None:
            key = ("missions", i, "goal", "pose")
            what = f"goal of mission {mission.id!r}"
            solids.inside(key, pose.x, pose.y, what)
            solids.clear(key, pose.x, pose.y, what, scene.robot.radius, "the robot's radius")


def _check_bodies_apart(scene: Scene, located: LocatedYaml) -> None:
    """No two people, and not the robot and a person, start where their bodies overlap: two people
    on one spot, or a robot started on a resident, is a typing mistake (``path`` then says the
    robot's start is blocked), not a scene.  Replayed people (``routine: replay``) are left out:
    their pose is where their record starts, at its own time, and the record decides."""
    robot = scene.robot
    people = [(i, p) for i, p in enumerate(scene.people) if p.routine != "replay"]
    for _, person in people:
        gap = math.hypot(person.pose.x - robot.pose.x, person.pose.y - robot.pose.y)
        if gap < robot.radius + PERSON_BODY_RADIUS_M:
            raise located.error(("robot", "pose"), f"robot at ({robot.pose.x:g}, {robot.pose.y:g}) starts on person "
                                f"{person.name!r} at ({person.pose.x:g}, {person.pose.y:g}): {gap:.2f} m apart, closer "
                                f"than the robot's radius plus a person's body ({robot.radius + PERSON_BODY_RADIUS_M:g} m); "
                                "move one of them")
    for k, (i, person) in enumerate(people):
        for _, other in people[:k]:
            gap = math.hypot(person.pose.x - other.pose.x, person.pose.y - other.pose.y)
            if gap < 2 * PERSON_BODY_RADIUS_M:
                raise located.error(("people", i, "pose"), f"person {person.name!r} at ({person.pose.x:g}, "
                                    f"{person.pose.y:g}) stands on person {other.name!r} at ({other.pose.x:g}, "
                                    f"{other.pose.y:g}): {gap:.2f} m apart, closer than two bodies "
                                    f"({2 * PERSON_BODY_RADIUS_M:g} m); move one of them")


ROOM_SAMPLES = 4_000           # cell centres sampled per room to measure how much of it is wall
ROOM_MAX_BLOCKED = 0.5         # a room more than half on walls was drawn over the wrong part of the map


def _load_map(scene: Scene, located: LocatedYaml, path: Path) -> Scene:
    """The scene standing on its map: the map read (errors name the map's file and key), the grid
    resolution taken from it."""
    assert scene.map is not None
    key: KeyPath = ("map", "file") if isinstance(located.data.get("map"), dict) else ("map",)
    map_path = Path(scene.map.file)
    if not map_path.is_absolute():
        map_path = path.parent / map_path
    if map_path.suffix.lower() not in (".yaml", ".yml"):
        raise located.error(key, f"{scene.map.file!r} is not a map_server .yaml: name the map's yaml file "
                                 "(it names the image and gives its resolution and origin)")
    if not map_path.is_file():
        raise located.error(key, f"map file {scene.map.file!r} not found (paths are relative to the scene file)")
    occupancy = load_occupancy(map_path)
    if occupancy.resolution > 1.0:
        raise located.error(key, f"the map's resolution is {occupancy.resolution:g} m per pixel; chronav plans on "
                                 "cells of at most 1 m")
    if "resolution" in scene.model_fields_set and not math.isclose(scene.resolution, occupancy.resolution,
                                                                    rel_tol=1e-9):
        raise located.error(("resolution",), f"a scene on a map plans on the map's own cells: resolution must be "
                                             f"{occupancy.resolution:g} (the map's) or left out")
    return scene.with_occupancy(occupancy)


class _MapCells:
    """A scene's occupancy map as its checks read it: which cells block, why a cell does, and
    whether a point stands on free floor of the map."""

    def __init__(self, scene: Scene, located: LocatedYaml) -> None:
        occupancy: OccupancyMap = scene.occupancy
        assert scene.map is not None
        self.located = located
        self.occupancy = occupancy
        self.blocked = occupancy.blocked(scene.map.unknown == "wall")
        self.xmin, self.ymin, self.xmax, self.ymax = occupancy.extent
        self.res = occupancy.resolution
        self.name = Path(scene.map.file).name

    def extent_text(self) -> str:
        return f"(x {self.xmin:g}..{self.xmax:g}, y {self.ymin:g}..{self.ymax:g})"

    def why(self, row: int, col: int) -> str:
        kind = "an unknown" if self.occupancy.values[row, col] < 0 else "an occupied"
        hint = (" (unknown cells are walls; write map: {file: ..., unknown: free} to treat them as floor)"
                if kind == "an unknown" else "")
        return f"{kind} cell of the map: {self.occupancy.describe_cell(row, col)}{hint}"

    def free_at(self, key: KeyPath, x: float, y: float, what: str) -> None:
        cell = self.occupancy.cell_of(x, y)
        if cell is None:
            raise self.located.error(key, f"{what} at ({x:g}, {y:g}) is outside the map {self.name} "
                                          f"{self.extent_text()}")
        if self.blocked[cell]:
            raise self.located.error(key, f"{what} at ({x:g}, {y:g}) is on {self.why(*cell)}")

    def first_blocked(self, a: Pose, b: Pose) -> tuple[int, int] | None:
        """The first blocked cell on the straight walk from ``a`` to ``b`` (sampled every quarter
        cell; off-map samples skipped), or None."""
        res = self.res
        steps = max(1, math.ceil(math.hypot(b.x - a.x, b.y - a.y) / (res / 4)))
        f = np.linspace(0.0, 1.0, steps + 1)
        cols = np.floor((a.x + f * (b.x - a.x) - self.xmin) / res).astype(np.int64)
        rows = np.floor((a.y + f * (b.y - a.y) - self.ymin) / res).astype(np.int64)
        on_map = (rows >= 0) & (rows < self.occupancy.rows) & (cols >= 0) & (cols < self.occupancy.cols)
        hits = np.nonzero(self.blocked[rows[on_map], cols[on_map]])[0]
        if len(hits):
            return int(rows[on_map][hits[0]]), int(cols[on_map][hits[0]])
        return None


def _check_on_map(scene: Scene, located: LocatedYaml) -> None:
    """Rooms lie on the map and mostly on its floor; nobody stands or walks on its walls."""
    cells = _MapCells(scene, located)
    for i, room in enumerate(scene.rooms):
        _check_room_on_map(i, room, cells)
    cells.free_at(("robot", "pose"), scene.robot.pose.x, scene.robot.pose.y, "robot")
    for i, person in enumerate(scene.people):
        _check_person_on_map(i, person, cells)
    for i, door in enumerate(scene.doors):
        cells.free_at(("doors", i, "position"), door.position[0], door.position[1], f"door {door.name!r}")
    for i, mission in enumerate(scene.missions):
        pose = getattr(mission.goal, "pose", None)
        if pose is not None:
            cells.free_at(("missions", i, "goal", "pose"), pose.x, pose.y, f"goal of mission {mission.id!r}")


def _check_room_on_map(i: int, room: Room, cells: _MapCells) -> None:
    """A room within the map's extent, covering some of its cells, at most ROOM_MAX_BLOCKED of them
    walls (measured on up to ROOM_SAMPLES cell centres)."""
    occupancy, blocked, res = cells.occupancy, cells.blocked, cells.res
    xmin, ymin = cells.xmin, cells.ymin
    polygon = shapely.Polygon(room.polygon)
    rxmin, rymin, rxmax, rymax = polygon.bounds
    if rxmin < xmin - 1e-9 or rymin < ymin - 1e-9 or rxmax > cells.xmax + 1e-9 or rymax > cells.ymax + 1e-9:
        raise cells.located.error(("rooms", i, "polygon"), f"room {room.name!r} reaches beyond the map "
                                                          f"{cells.name} {cells.extent_text()}")
    c0, c1 = max(0, math.floor((rxmin - xmin) / res)), min(occupancy.cols, math.ceil((rxmax - xmin) / res))
    r0, r1 = max(0, math.floor((rymin - ymin) / res)), min(occupancy.rows, math.ceil((rymax - ymin) / res))
    stride = max(1, math.ceil(math.sqrt(max(1, (c1 - c0) * (r1 - r0)) / ROOM_SAMPLES)))
    cols, rows = np.arange(c0, c1, stride), np.arange(r0, r1, stride)
    inside = cells_in_polygon(polygon, xmin + (cols + 0.5) * res, ymin + (rows + 0.5) * res)
    walls = blocked[np.ix_(rows, cols)] & inside
    if not inside.any():
        raise cells.located.error(("rooms", i, "polygon"), f"room {room.name!r} covers no cell of the map")
    if walls.sum() > ROOM_MAX_BLOCKED * inside.sum():
        centre = polygon.representative_point()
        wr, wc = np.nonzero(walls)
        nearest = np.argmin((cols[wc] - (centre.x - xmin) / res) ** 2 + (rows[wr] - (centre.y - ymin) / res) ** 2)
        raise cells.located.error(("rooms", i, "polygon"), f"room {room.name!r} lies on walls of the map: "
                                  f"{100 * walls.sum() / inside.sum():.0f}% of its cells are, e.g. "
                                  f"{cells.why(int(rows[wr[nearest]]), int(cols[wc[nearest]]))}")


def _check_person_on_map(i: int, person: PersonSpec, cells: _MapCells) -> None:
    """A person and their waypoints on free cells, and no walk between them through a blocked one."""
    cells.free_at(("people", i, "pose"), person.pose.x, person.pose.y, f"person {person.name!r}")
    route = [person.pose, *(w.pose for w in person.waypoints)]
    for j, waypoint in enumerate(person.waypoints):
        cells.free_at(("people", i, "waypoints", j, "pose"), waypoint.pose.x, waypoint.pose.y,
                      f"waypoint of {person.name!r}")
    for j, (a, b) in enumerate(zip(route, route[1:], strict=False)):
        cell = cells.first_blocked(a, b)
        if cell is not None:
            raise cells.located.error(("people", i, "waypoints", j),
                                      f"{person.name!r} would walk through {cells.why(*cell)}, going from "
                                      f"({a.x:g}, {a.y:g}) to ({b.x:g}, {b.y:g}); add a waypoint around it")


def load_scene(name_or_path: str | Path) -> LoadedScene:
    """Read, validate and geometry-check a scene; raise SourceError (file:line:col: key: msg)."""
    path = resolve_scene_path(name_or_path)
    located = load_located_file(path)
    if not isinstance(located.data, dict):
        raise SourceError(str(path), 1, 1, "", "a scene file must be a YAML mapping")
    scene = validate_located(Scene, located)
    _check_references(scene, located)
    if scene.map is not None:
        scene = _load_map(scene, located, path)
    _check_geometry(scene, located)
    if scene.map is not None:
        _check_on_map(scene, located)
    loaded = LoadedScene(scene=scene, path=path, located=located)
    if scene.agenda_file is not None and not loaded.resolve(scene.agenda_file).exists():
        raise located.error(("agenda_file",), f"agenda file {scene.agenda_file!r} not found")
    return loaded
