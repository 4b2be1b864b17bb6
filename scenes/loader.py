"""Load and check scene files: schema first, then geometry a person would get wrong.

Why a separate geometric pass: pydantic can say a pose is three numbers, but only the room
polygons can say that a person standing at (40, 2) is outside the building.  Both kinds of error
point at the line of the offending key.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import shapely

from scenes.model import Scene
from scenes.yamlio import LocatedYaml, SourceError, load_located_file, validate_located

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


def _check_geometry(scene: Scene, located: LocatedYaml) -> None:
    for index, room in enumerate(scene.rooms):  # before the union: GEOS fails on invalid polygons
        if not shapely.Polygon(room.polygon).is_valid:
            raise located.error(("rooms", index, "polygon"), f"room {room.name!r} polygon self-intersects")
    building = shapely.union_all([shapely.Polygon(r.polygon) for r in scene.rooms])

    def inside(key: tuple[str | int, ...], x: float, y: float, what: str) -> None:
        if not building.covers(shapely.Point(x, y)):
            raise located.error(key, f"{what} at ({x:g}, {y:g}) is outside every room")

    inside(("robot", "pose"), scene.robot.pose.x, scene.robot.pose.y, "robot")
    for i, obj in enumerate(scene.objects):
        inside(("objects", i, "pose"), obj.pose.x, obj.pose.y, f"object {obj.name!r}")
    for i, person in enumerate(scene.people):
        inside(("people", i, "pose"), person.pose.x, person.pose.y, f"person {person.name!r}")
        for j, waypoint in enumerate(person.waypoints):
            inside(("people", i, "waypoints", j, "pose"), waypoint.pose.x, waypoint.pose.y,
                   f"waypoint of {person.name!r}")
    walls = shapely.MultiLineString([wall for wall in scene.walls if len(wall) >= 2])
    for i, person in enumerate(scene.people):
        route = [person.pose, *(w.pose for w in person.waypoints)]
        for j, (a, b) in enumerate(zip(route, route[1:], strict=False)):
            if (a.x, a.y) != (b.x, b.y) and shapely.LineString([(a.x, a.y), (b.x, b.y)]).crosses(walls):
                raise located.error(("people", i, "waypoints", j), f"{person.name!r} would walk through a "
                                    f"wall from ({a.x:g}, {a.y:g}) to ({b.x:g}, {b.y:g}); add a waypoint at the door")
    for i, door in enumerate(scene.doors):
        inside(("doors", i, "position"), door.position[0], door.position[1], f"door {door.name!r}")
    for i, mission in enumerate(scene.missions):
        pose = getattr(mission.goal, "pose", None)
        if pose is not None:
            inside(("missions", i, "goal", "pose"), pose.x, pose.y, f"goal of mission {mission.id!r}")


def load_scene(name_or_path: str | Path) -> LoadedScene:
    """Read, validate and geometry-check a scene; raise SourceError (file:line:col: key: msg)."""
    path = resolve_scene_path(name_or_path)
    located = load_located_file(path)
    if not isinstance(located.data, dict):
        raise SourceError(str(path), 1, 1, "", "a scene file must be a YAML mapping")
    scene = validate_located(Scene, located)
    _check_geometry(scene, located)
    loaded = LoadedScene(scene=scene, path=path, located=located)
    if scene.agenda_file is not None and not loaded.resolve(scene.agenda_file).exists():
        raise located.error(("agenda_file",), f"agenda file {scene.agenda_file!r} not found")
    return loaded
