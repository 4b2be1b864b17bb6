"""Where the scene's people truly are: the one definition the simulator and the offline world share.

A scene's people are one ``Crowd`` (agents/lib/crowd): the ``stay`` people where the scene puts
them or walking their timed waypoints (motion.py), the others living their routine and the agenda.
The simulator owns the live crowd (its laser and bumper see it, and it hands the truth to the
human observer through the DSR); the offline commands replay the same crowd from the start of the
day (``people_at``).  Both feed it the same world at each step:

- the agenda: the scene's agenda with its scripted changes applied when due (timeline.py), plus,
  live, the changes staff made with ``chronav agenda`` (read from the DSR's agenda log);
- the doors: the scene's scripted openings and closings;
- the robot: only while it drives (``None`` otherwise: nobody reacts to a robot at rest).

So offline and live agree exactly as long as the robot has not driven near anyone and nobody
changed the agenda by hand; what can differ is listed in docs/people.md.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from collections.abc import Mapping
from dataclasses import dataclass

from agents.lib.agenda import AgendaChangeError, AgendaDay, apply_change, parse_change
from agents.lib.crowd.crowd import Crowd
from agents.lib.crowd.model import Agenda, Appointment, PersonTruth, RobotBody
from agents.world.crowd_scene import building_of, scene_recordings, walker_of
from agents.world.scene_world import SceneWorld
from agents.world.timeline import agenda_at, doors_at
from scenes.clock import parse_clock

SNAPSHOT_EVERY_S = 1800.0   # offline: a copy of the crowd every half hour, to go back in time cheaply
MEMO_WORLDS = 4             # offline: how many scenes' days are kept


def new_crowd(world: SceneWorld) -> Crowd:
    scene = world.scene
    recordings = scene_recordings(world.loaded) if scene.recordings else None
    return Crowd(building_of(scene), [walker_of(scene, p, recordings) for p in scene.people], seed=scene.crowd.seed,
                 start_s=scene.clock.start_s, robot_radius_m=scene.robot.radius)


def resting_robot(world: SceneWorld) -> RobotBody:
    """The robot as the offline commands have it: at rest at the scene's pose (they never drive it)."""
    robot = world.scene.robot
    return RobotBody(robot.pose.x, robot.pose.y, 0.0, 0.0, robot.radius)


def appointments(day: AgendaDay) -> tuple[Appointment, ...]:
    """The day's activities as people live them (a cancelled activity draws nobody)."""
    return tuple(Appointment(a.id, a.object, a.start_s, a.end_s, tuple(a.participants))
                 for a in day.activities if not a.cancelled)


@dataclass
class WorldFeed:
    """The agenda and doors the crowd lives by at each step: the scene's script, plus (live) the
    changes accepted from ``chronav agenda``, applied after the scripted ones due by then."""

    world: SceneWorld
    manual: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        scene = self.world.scene
        self._change_times = sorted({c.at_s for c in self.world.scripted}
                                    | {parse_clock(c.at) for c in scene.door_changes})
        self._cache: dict[tuple[int, tuple[str, ...]], Agenda] = {}
        self._last: tuple[float, Agenda] | None = None

    def __call__(self, t_s: float) -> Agenda:
        last = self._last
        if last is not None and last[0] <= t_s < last[1].next_change_s:
            return last[1]          # the crowd asks every step: nothing changes between scripted events
        epoch = sum(1 for at in self._change_times if at <= t_s)
        key = (epoch, self.manual)
        if key not in self._cache:
            self._cache[key] = self._agenda(t_s, epoch)
        agenda = self._cache[key]
        start = max([at for at in self._change_times if at <= t_s], default=-math.inf)
        self._last = (start, agenda)
        return agenda

    def _agenda(self, t_s: float, epoch: int) -> Agenda:
        day = self.world.agenda
        for change in self.world.scripted:
            if change.at_s > t_s:
                break
            try:
                day = self.world.apply(day, change)
            except AgendaChangeError:
                continue
        for text in self.manual:
            try:
                day = apply_change(day, parse_change(text), known_objects=self.world.object_names,
                                   known_rooms=self.world.room_names, known_people=self.world.person_names)
            except AgendaChangeError:
                continue
        closed = frozenset(name for name, is_open in doors_at(self.world.scene, t_s).items() if not is_open)
        later = [at for at in self._change_times if at > t_s]
        return Agenda((epoch, self.manual), appointments(day), closed, later[0] if later else math.inf)


def manual_changes(applied: Sequence[str], changes: Sequence[str], world: SceneWorld) -> tuple[str, ...]:
    """The changes of the DSR's agenda log that staff made (the log also holds the scripted ones,
    which ``WorldFeed`` applies at their own times): the log less one copy of each applied
    scripted change's text."""
    scripted = {c.key: c.text for c in world.scripted}
    remaining = list(changes)
    for key in applied:
        text = scripted.get(key)
        if text is not None and text in remaining:
            remaining.remove(text)
    return tuple(remaining)


class _Day:
    """One scene's day replayed offline, with a snapshot every ``SNAPSHOT_EVERY_S`` to go back."""

    def __init__(self, world: SceneWorld) -> None:
        self.world = world
        self.feed = WorldFeed(world)
        self.robot = resting_robot(world)
        self.crowd = new_crowd(world)
        self.snapshots: list[Crowd] = [self.crowd.clone()]

    def at(self, t_s: float) -> tuple[PersonTruth, ...]:
        crowd = self.crowd
        if t_s < crowd.t_s - crowd.step_s:
            base = max((s for s in self.snapshots if s.t_s <= t_s), key=lambda s: s.t_s, default=self.snapshots[0])
            crowd = self.crowd = base.clone()
        start = crowd.start_s
        while crowd.t_s < t_s - 1e-9:
            boundary = start + (math.floor((crowd.t_s - start) / SNAPSHOT_EVERY_S) + 1) * SNAPSHOT_EVERY_S
            crowd.advance(min(t_s, boundary), self.feed, self.robot)
            if crowd.t_s >= boundary and crowd.t_s > self.snapshots[-1].t_s:
                self.snapshots.append(crowd.clone())
        return crowd.at(t_s)


_DAYS: dict[str, _Day] = {}


def _day_key(world: SceneWorld) -> str:
    """The same scene loaded twice replays one day (its content, not the Python object, is the key)."""
    return f"{world.path.resolve()}|{world.scene.model_dump_json()}"


def people_at(world: SceneWorld, t_s: float) -> tuple[PersonTruth, ...]:
    """Everyone at ``t_s`` as the simulated world would have them if the robot had not driven and
    nobody had changed the agenda by hand (the offline commands' people)."""
    key = _day_key(world)
    day = _DAYS.get(key)
    if day is None:
        if len(_DAYS) >= MEMO_WORLDS:
            _DAYS.pop(next(iter(_DAYS)))
        day = _DAYS[key] = _Day(world)
    return day.at(t_s)


@dataclass(frozen=True)
class WorldAt:
    """The scripted world at ``t_s``: doors, agenda and where everyone truly is."""

    world: SceneWorld
    t_s: float
    doors_open: Mapping[str, bool]
    agenda: AgendaDay
    people: tuple[PersonTruth, ...]


def world_at(world: SceneWorld, t_s: float) -> WorldAt:
    return WorldAt(world, t_s, doors_at(world.scene, t_s), agenda_at(world, t_s), people_at(world, t_s))
