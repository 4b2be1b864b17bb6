"""The crowd's inputs and outputs as plain values: who walks how, the building, appointments, truth.

Why its own small types (and not the scene's pydantic models or the agenda's): the crowd is fed by
the world model (agents/world/people.py), which turns a scene and an agenda - from the scene's
script offline, from the DSR live - into these, so the simulation itself never depends on where
its inputs came from.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

from shapely.geometry.base import BaseGeometry

Pose = tuple[float, float, float]

# Default walking speeds (m/s) by role: older adults walk 0.8-1.0 m/s, with a walking frame about
# 0.5 (Bohannon 1997; Graham et al. 2008); nurses on their rounds about 1.3.
ROLE_SPEED_MPS: Mapping[str, float] = {"resident": 0.8, "new_resident": 0.7, "staff": 1.3, "therapist": 1.2,
                                       "visitor": 1.0}
WALKER_SPEED_MPS = 0.5
# How long people stay at one place (s), by routine: residents sit or stand a while, staff move on.
ROUTINE_DWELL_S: Mapping[str, tuple[float, float]] = {"wander": (180.0, 900.0), "staff": (30.0, 150.0),
                                                      "visitor": (120.0, 600.0)}
BODY_RADIUS_M = 0.25
WALKER_RADIUS_M = 0.35      # a walking frame is wider than its user


@dataclass(frozen=True)
class Walker:
    """One person as the crowd simulates them (defaults already applied)."""

    name: str
    role: str
    routine: str                         # stay | wander | staff | visitor
    pose: Pose                           # at the start of the day
    home: str | None = None
    rooms: tuple[str, ...] = ()
    speed_mps: float = 0.8
    walker: bool = False
    escort: bool = False
    dwell_s: tuple[float, float] = (180.0, 900.0)
    visits: str | None = None
    script: Callable[[float], Pose] | None = field(default=None, compare=False)   # stay: pose at t
    moves: tuple[tuple[float, float], ...] = ()   # stay: the [t0, t1) intervals the script walks
    # replay (replay.py): position and velocity (x, y, vx, vy) along the record at a clock time, the
    # [t0, t1] the person is in the scene, and whether they avoid the robot (reactive) or not (exact)
    record: Callable[[float], tuple[float, float, float, float]] | None = field(default=None, compare=False)
    present: tuple[float, float] | None = None
    reactive: bool = False
    # a walking routine's time in the building (clock seconds): they come in at ``pose`` at the first,
    # walk back there at the second and leave (crowd.py); None: there all day
    hours: tuple[float, float] | None = None

    @property
    def dynamic(self) -> bool:
        """Walks by itself (the behaviour decides); a ``stay`` person only follows their script, a
        ``replay`` one their record."""
        return self.routine not in ("stay", "replay")

    @property
    def radius_m(self) -> float:
        return WALKER_RADIUS_M if self.walker else BODY_RADIUS_M


@dataclass(frozen=True)
class Thing:
    """An object people gather at: pose, footprint, and whether it is a screen (viewed from in front)."""

    name: str
    x: float
    y: float
    theta: float
    footprint: BaseGeometry
    screen: bool = False


@dataclass(frozen=True)
class Building:
    """Rooms, walls, objects and the door leaves that close."""

    rooms: Mapping[str, BaseGeometry]
    walls: Sequence[Sequence[tuple[float, float]]]
    things: Mapping[str, Thing]
    door_leaves: Mapping[str, tuple[tuple[float, float], tuple[float, float]]]
    doors: Mapping[str, tuple[float, float]] = field(default_factory=dict)   # door centres


@dataclass(frozen=True)
class Appointment:
    """An activity as people live it: where, when, who (cancelled ones are simply absent)."""

    id: str
    object: str
    start_s: float
    end_s: float
    participants: tuple[str, ...]


@dataclass(frozen=True)
class Agenda:
    """What the crowd reads of the world at one time: the agenda's version (changes when anything in
    it changed) and appointments, the closed doors, and when the next scripted change of either is
    due (the crowd never jumps past it)."""

    version: object
    appointments: tuple[Appointment, ...]
    closed_doors: frozenset[str] = frozenset()
    next_change_s: float = float("inf")


@dataclass(frozen=True)
class PersonTruth:
    """Where a person truly is at a time, as the simulated world knows it (sensors add noise)."""

    name: str
    role: str
    x: float
    y: float
    theta: float
    vx: float = 0.0
    vy: float = 0.0
    group: str = ""        # "activity/<id>" or "chat/<n>" while standing in that formation
    goal: str = ""         # activity id a participant is walking to or attending

    @property
    def moving(self) -> bool:
        """Walking, however slowly (a scripted stroll across a room may take minutes)."""
        return self.vx * self.vx + self.vy * self.vy > 1e-12


@dataclass(frozen=True)
class RobotBody:
    """The robot as people avoid it: while it drives, a moving body; at rest (zero velocity), an
    obstacle they walk round and do not choose to stand at."""

    x: float
    y: float
    vx: float
    vy: float
    radius: float

    @property
    def driving(self) -> bool:
        return self.vx != 0.0 or self.vy != 0.0
