"""A scene with its agenda resolved and its scripted events checked: what every run starts from.

Why a layer above ``scenes/``: a scene file is only data (schema and geometry, ``scenes/``); its
agenda needs the agenda library to be placed on the sim date, and its scripted agenda changes can
only be checked by applying them.  Agents, the launcher and every offline command load a scene
through :func:`load_world`, so a scene that one of them accepts, all of them accept, and a bad
scripted change fails at ``chronav scene check`` instead of minutes into a run.
"""

from __future__ import annotations

import datetime as dt
import json
import re
from dataclasses import dataclass
from pathlib import Path

import shapely

from agents.lib.agenda import (AgendaChangeError, AgendaDay, AgendaError, AgendaSourceError, AgendaValidationError,
                               apply_change, expand_day, parse_change, validate_day)
from agents.lib.agenda.yaml_source import scene_agenda
from agents.lib.socialmap.grid import grid_shape
from agents.lib.socialmap.types import SocialMapInputError
from agents.world.building import PLANNING_MARGIN_M
from agents.world.crowd_scene import check_people
from agents.world.vocabulary import activity_id_of
from scenes.clock import parse_clock
from scenes.days import day_number, on_day, weekday_of
from scenes.loader import LoadedScene, load_scene
from scenes.model import PoseGoal, RoomGoal, Scene, WaitGoal
from scenes.yamlio import SourceError


@dataclass(frozen=True)
class ScriptedChange:
    """One of the scene's ``agenda_changes``: applied once when the sim clock reaches ``at_s``.

    ``key`` ("scene#<index>") marks it applied in the DSR's agenda log (restart-safe); ``text`` is
    the change in the wire form of ``chronav agenda`` (agents/lib/agenda/changes.py)."""

    index: int
    at_s: float
    text: str

    @property
    def key(self) -> str:
        return f"scene#{self.index}"


@dataclass(frozen=True)
class SceneWorld:
    """A loaded scene, the day's agenda as planned, and the scripted changes in the order they apply."""

    loaded: LoadedScene
    agenda: AgendaDay
    scripted: tuple[ScriptedChange, ...]
    notes: tuple[str, ...] = ()  # what staff usually want to know but is allowed (overlapping activities)

    @property
    def scene(self) -> Scene:
        return self.loaded.scene

    @property
    def path(self) -> Path:
        return self.loaded.path

    @property
    def object_names(self) -> frozenset[str]:
        return frozenset(o.name for o in self.scene.objects)

    @property
    def room_names(self) -> frozenset[str]:
        return frozenset(r.name for r in self.scene.rooms)

    @property
    def person_names(self) -> frozenset[str]:
        return frozenset(p.name for p in self.scene.people)

    def apply(self, day: AgendaDay, change: ScriptedChange) -> AgendaDay:
        """``change`` applied to ``day`` exactly as the agenda agent applies it."""
        return apply_change(day, parse_change(change.text), known_objects=self.object_names,
                            known_rooms=self.room_names, known_people=self.person_names)


def scripted_changes(scene: Scene) -> tuple[ScriptedChange, ...]:
    """The scene's ``agenda_changes`` in the order they take effect: by time, then as written."""
    out = []
    for index, change in enumerate(scene.agenda_changes):
        payload = {k: v for k, v in change.model_dump().items() if k not in ("at", "day") and v is not None}
        out.append(ScriptedChange(index, parse_clock(change.at), json.dumps(payload)))
    return tuple(sorted(out, key=lambda c: (c.at_s, c.index)))


def _agenda_error(exc: Exception, loaded: LoadedScene) -> SourceError:
    """Agenda errors name "file:line" in their findings; keep that position for the scene check."""
    scene_file = str(loaded.path)
    if isinstance(exc, AgendaSourceError):
        return exc.problems[0]
    if isinstance(exc, AgendaValidationError) and exc.report.errors:
        finding = exc.report.errors[0]
        where = re.match(r"^(.*):(\d+)(?: .*)?$", finding.source)
        if where:
            return SourceError(where[1], int(where[2]), None, "agenda", finding.message)
        return SourceError(scene_file, None, None, "agenda", finding.message)
    return SourceError(scene_file, None, None, "agenda", str(exc))


def _check_navigable(loaded: LoadedScene) -> tuple[str, ...]:
    """The map the navigation will build: not too large, and every mission goal reachable from the
    robot's start (a goal on a wall or in a walled-off box would leave the mission "active" until
    the run times out).  Free space is the building less the walls grown by the robot's radius plus
    the planning margin, all doors open: what the navigation's static map blocks, as polygons
    (cheap, and without importing the planner into every agent that loads a scene)."""
    scene = loaded.scene
    try:
        grid_shape(scene.bounds, scene.resolution)
    except SocialMapInputError as exc:
        raise loaded.error(("resolution",), str(exc)) from None
    clearance = scene.robot.radius + PLANNING_MARGIN_M
    building = shapely.union_all([shapely.Polygon(r.polygon) for r in scene.rooms])
    walls = shapely.MultiLineString([wall for wall in scene.walls if len(wall) >= 2])
    free = building.difference(walls.buffer(clearance)) if not walls.is_empty else building
    robot = scene.robot.pose
    parts = list(getattr(free, "geoms", [free]))
    notes: list[str] = []
    here = shapely.Point(robot.x, robot.y)
    start = next((part for part in parts if part.covers(here)), None)
    if start is None and parts and not walls.is_empty and walls.distance(here) >= scene.robot.radius \
            and building.covers(here):
        # Docked: collision-free but inside the planning margin. The planner leaves the margin the
        # cheapest way (planning/plan.py dock_exit), as a robot backs off its charging dock.
        nearest = min(parts, key=lambda part: part.distance(here))
        if nearest.distance(here) <= PLANNING_MARGIN_M + scene.resolution:
            start = nearest
            notes.append(f"warning: robot.pose ({robot.x:g}, {robot.y:g}) is {walls.distance(here):.2f} m from a "
                         f"wall, inside the planning margin ({clearance:.2f} m = radius {scene.robot.radius:g} + "
                         f"margin {PLANNING_MARGIN_M:g}): allowed, as at a charging dock; the first plan leaves "
                         f"the margin by the cheapest way out ({nearest.distance(here):.2f} m)")
    if start is None:
        raise loaded.error(("robot", "pose"), f"the robot at ({robot.x:g}, {robot.y:g}) is within {clearance:.2f} m "
                           "(its radius plus the planning margin) of a wall or outside the rooms: the navigation "
                           "cannot start there; move it further into the room")
    for i, mission in enumerate(scene.missions):
        goal = mission.goal
        if isinstance(goal, PoseGoal):
            x, y = goal.pose.x, goal.pose.y
            point = shapely.Point(x, y)
            if not free.covers(point):
                raise loaded.error(("missions", i, "goal", "pose"), f"goal ({x:g}, {y:g}) of mission {mission.id!r} "
                                   f"is within {clearance:.2f} m (the robot's radius plus the planning margin) of "
                                   "a wall: the robot cannot stand there; move the goal into the room")
            if not start.covers(point):
                raise loaded.error(("missions", i, "goal", "pose"), f"goal ({x:g}, {y:g}) of mission {mission.id!r} "
                                   f"cannot be reached from the robot's start ({robot.x:g}, {robot.y:g}): walls "
                                   "close it off (is a door missing, or narrower than the robot?)")
        elif isinstance(goal, RoomGoal):
            room = next(r for r in scene.rooms if r.name == goal.room)
            if not start.intersects(shapely.Polygon(room.polygon).buffer(-1e-6)):
                raise loaded.error(("missions", i, "goal", "room"), f"room {goal.room!r} of mission {mission.id!r} "
                                   f"cannot be reached from the robot's start ({robot.x:g}, {robot.y:g}): no door "
                                   "wide enough for the robot leads there")
    return tuple(notes)


def resolve_world(loaded: LoadedScene, day_index: int = 1) -> SceneWorld:
    """The agenda of a loaded scene placed on its date, and its scripted changes checked by applying
    them in order (SourceError at the offending ``agenda_changes`` entry).

    ``day_index`` (1-based) places it on that day of a scene that spans days (scenes/days.py): that
    date's agenda, the scripted changes naming that day, the missions given on it.  The errors of
    a later day say which day they are about, and stay located in the scene file."""
    if day_index == 1:
        return _resolve_day(loaded, 1)
    try:
        return _resolve_day(loaded, day_index)
    except SourceError as exc:
        date = loaded.scene.clock.date + dt.timedelta(days=day_index - 1)
        raise SourceError(exc.file, exc.line, exc.column, exc.key,
                          f"{exc.message} (on day {day_index}, {weekday_of(date)} {date.isoformat()})") from None


def _resolve_day(loaded: LoadedScene, day_index: int) -> SceneWorld:
    scene = loaded.scene
    date = scene.clock.date + dt.timedelta(days=day_index - 1)
    dock_notes = _check_navigable(loaded) if day_index == 1 else ()
    if day_index == 1:
        check_people(loaded)
    if scene.agenda_file is not None and not loaded.resolve(scene.agenda_file).exists():
        raise loaded.error(("agenda_file",), f"agenda file {scene.agenda_file!r} not found")
    try:
        day = expand_day(scene_agenda(loaded.located, loaded.path.parent), date, scene.clock.timezone,
                         {o.name for o in scene.objects}, known_rooms={r.name for r in scene.rooms},
                         known_people={p.name for p in scene.people})
    except AgendaError as exc:
        raise _agenda_error(exc, loaded) from None
    notes = (*dock_notes, *(f.message for f in validate_day(day, None).infos))
    first = scene.clock.date
    todays = tuple(c for c in scripted_changes(scene)
                   if day_number(scene.agenda_changes[c.index].day, first) == day_index)
    world = SceneWorld(loaded, day, todays, notes)
    check = day
    for change in world.scripted:
        try:
            check = world.apply(check, change)
        except AgendaChangeError as exc:
            raise loaded.error(("agenda_changes", change.index), str(exc)) from None
    _check_wait_missions(loaded, {a.id for a in day.activities} | {a.id for a in check.activities}, date)
    return world


def _check_wait_missions(loaded: LoadedScene, activity_ids: set[str], date: dt.date) -> None:
    """A ``wait`` mission names an activity of its day (or one a scripted change adds)."""
    for index, mission in enumerate(loaded.scene.missions):
        if isinstance(mission.goal, WaitGoal) and on_day(mission.weekdays, mission.dates, date):
            wanted = activity_id_of(mission.goal.wait)
            if wanted not in activity_ids:
                known = ", ".join(sorted(activity_ids)) or "none"
                raise loaded.error(("missions", index, "goal", "wait"),
                                   f"mission {mission.id!r} waits for unknown activity {wanted!r}; activities: {known}")


def load_world(name_or_path: str | Path | LoadedScene) -> SceneWorld:
    """Read, validate and resolve a scene; SourceError (``file:line:col: key: message``) otherwise."""
    loaded = name_or_path if isinstance(name_or_path, LoadedScene) else load_scene(name_or_path)
    return resolve_world(loaded)
