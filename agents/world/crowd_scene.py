"""A scene's people as the crowd simulates them: each person with their role's and routine's
defaults, the building as walls, rooms, objects and door leaves, and the checks `chronav scene check`
makes of who walks where.

Why apart from people.py: the scene check (agents/world/scene_world.py) needs these before any
agenda exists, and people.py needs a resolved world.
"""

from __future__ import annotations

import numpy as np
import shapely

from agents.lib.crowd.model import ROLE_SPEED_MPS, ROUTINE_DWELL_S, WALKER_SPEED_MPS, Building, Thing, Walker
from agents.lib.crowd.routes import NoRoute, Router
from agents.world.building import door_segment
from agents.world.motion import person_at
from scenes.clock import parse_clock
from scenes.geometry import posed_polygon
from scenes.loader import LoadedScene
from scenes.model import PersonSpec, Scene, Trapezoid


def walker_of(scene: Scene, person: PersonSpec) -> Walker:
    """A scene person with the defaults of their role and routine applied."""
    pose = (person.pose.x, person.pose.y, person.pose.theta)
    if person.routine == "stay":
        moves = tuple(_moves(person))
        script = (lambda t, p=person: _pose(person_at(p, t))) if person.waypoints else None
        return Walker(person.name, person.role, "stay", pose, script=script, moves=moves)
    speed = person.speed if person.speed is not None else \
        (WALKER_SPEED_MPS if person.walker else ROLE_SPEED_MPS.get(person.role, 0.8))
    home = person.home or scene.room_at(person.pose.x, person.pose.y)
    dwell = tuple(person.dwell) if person.dwell is not None else ROUTINE_DWELL_S[person.routine]
    return Walker(person.name, person.role, person.routine, pose, home=home, rooms=tuple(person.rooms),
                  speed_mps=float(speed), walker=person.walker, escort=person.escort,
                  dwell_s=(float(dwell[0]), float(dwell[1])), visits=person.visits)


def _pose(state: object) -> tuple[float, float, float]:
    return (state.x, state.y, state.theta)  # type: ignore[attr-defined]


def _moves(person: PersonSpec) -> list[tuple[float, float]]:
    """The time intervals in which a scripted person's pose changes (walking or turning)."""
    out = []
    stops = [(parse_clock(w.time), w.pose) for w in person.waypoints]
    for (t0, a), (t1, b) in zip(stops, stops[1:], strict=False):
        if (a.x, a.y, a.theta) != (b.x, b.y, b.theta):
            out.append((t0, t1))
    return out


def building_of(scene: Scene) -> Building:
    rooms = {room.name: shapely.Polygon(room.polygon) for room in scene.rooms}
    things = {obj.name: Thing(obj.name, obj.pose.x, obj.pose.y, obj.pose.theta,
                              posed_polygon(obj.footprint, obj.pose.x, obj.pose.y, obj.pose.theta),
                              screen=isinstance(obj.interaction, Trapezoid))
              for obj in scene.objects}
    leaves = {door.name: door_segment(scene, door.name) for door in scene.doors}
    doors = {door.name: (float(door.position[0]), float(door.position[1])) for door in scene.doors}
    return Building(rooms, [list(map(tuple, wall)) for wall in scene.walls], things, leaves, doors)


def check_people(loaded: LoadedScene) -> None:
    """People who walk by themselves can: the scene's walls are polylines (a building map's wall
    cells are not walls for them yet), someone fetches those marked ``escort``, and each reaches
    every room of their routine from where they start (SourceError at the person's key)."""
    scene = loaded.scene
    walking = [(i, p) for i, p in enumerate(scene.people) if p.routine != "stay"]
    if not walking:
        return
    if scene.map is not None:
        i, person = walking[0]
        raise loaded.error(("people", i, "routine"), f"{person.name!r} walks by themself (routine "
                           f"{person.routine!r}), but this scene's walls come from a building map, which walking "
                           "people cannot see yet; use routine 'stay' (with waypoints) or walls drawn as polylines")
    if any(p.escort for _, p in walking) and not any(p.routine == "staff" for _, p in walking):
        i, person = next((i, p) for i, p in walking if p.escort)
        raise loaded.error(("people", i, "escort"), f"{person.name!r} is to be fetched to activities, but nobody "
                           "has routine 'staff' to fetch them; add a staff member or remove escort")
    building = building_of(scene)
    router = Router.build(shapely.union_all(list(building.rooms.values())), building.walls,
                          [t.footprint for t in building.things.values()])
    for i, person in walking:
        start = (person.pose.x, person.pose.y)
        for room in (person.rooms or [r.name for r in scene.rooms]):
            goal = _free_point(building.rooms[room], router)
            try:
                if goal is None:
                    raise NoRoute(room)
                router.route(start, goal)
            except NoRoute:
                key = ("people", i, "rooms") if person.rooms else ("people", i, "pose")
                raise loaded.error(key, f"{person.name!r} cannot walk from ({start[0]:g}, {start[1]:g}) to room "
                                   f"{room!r}: walls or furniture close the way (is a door missing or narrower "
                                   "than 0.6 m?)") from None


def _free_point(room: shapely.Polygon, router: Router) -> tuple[float, float] | None:
    """A place a person fits in ``room``: the free point of a 0.25 m lattice nearest its middle."""
    middle = room.representative_point()
    xmin, ymin, xmax, ymax = room.bounds
    xs, ys = np.meshgrid(np.arange(xmin + 0.125, xmax, 0.25), np.arange(ymin + 0.125, ymax, 0.25))
    candidates = sorted(zip(xs.ravel(), ys.ravel(), strict=True), key=lambda p: (p[0] - middle.x) ** 2 + (p[1] - middle.y) ** 2)
    for x, y in candidates:
        if shapely.contains_xy(room, x, y) and router.free(float(x), float(y)):
            return float(x), float(y)
    return None
