"""The scene file schema: the world a chronav run starts from.

Why pydantic models with ``extra="forbid"``: a typo such as ``radiuss:`` in a scene must be an
error naming the key and line, never a silently ignored value that changes a robot's clearance.
All lengths are metres, angles radians (theta measured from +x, counter-clockwise), clock times
``"HH:MM"`` (or ``"HH:MM:SS"``) local to the scene's time zone.
"""

from __future__ import annotations

import math
import datetime as dt
from collections.abc import Sequence
from typing import Annotated, Any, Literal

from pydantic import (AfterValidator, BaseModel, BeforeValidator, ConfigDict, Discriminator, Field, PlainSerializer,
                      PlainValidator, PrivateAttr, Tag, ValidationInfo, field_validator, model_validator)

from scenes.clock import ClockTime, parse_clock
from scenes.days import MAX_DAYS, DateItem, Weekday
from scenes.geometry import Circle, Rectangle, Trapezoid, shape_from_spec, shape_to_dict
from scenes.geometry import Shape as GeometryShape
from scenes.names import Name
from scenes.yamlio import as_date


# A slower clock would never reach the day's first mission (1e-300 sim s per wall s was accepted).
MIN_CLOCK_RATE = 0.01
# Finer cells are not a floor plan any more (5e-324 overflowed the grid's cell count).
MIN_RESOLUTION_M = 0.001
# The simulated day: a calendar date a care home could plan for (9999-12-31 overflowed the agenda).
MIN_DATE, MAX_DATE = dt.date(1900, 1, 1), dt.date(2999, 12, 31)


class Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


def _number(value: Any) -> Any:
    """YAML's ``true``/``false`` are not numbers, although Python counts them as 1 and 0."""
    if isinstance(value, bool):
        raise ValueError(f"expected a number, got {'true' if value else 'false'}")
    return value


def _finite(value: float) -> float:
    if not math.isfinite(value):
        raise ValueError(f"must be a finite number, got {value}")
    return value


# Every number of a scene: a real number, never a boolean, never .inf or .nan.
Real = Annotated[float, BeforeValidator(_number), AfterValidator(_finite)]
WholeNumber = Annotated[int, BeforeValidator(_number)]


Point = tuple[Real, Real]


class Pose(Strict):
    x: Real
    y: Real
    theta: Real = 0.0

    @model_validator(mode="before")
    @classmethod
    def _from_list(cls, value: Any) -> Any:
        """Accept the compact ``[x, y, theta]`` / ``[x, y]`` form used in scene files."""
        if isinstance(value, (list, tuple)):
            if len(value) not in (2, 3):
                raise ValueError(f"a pose is [x, y] or [x, y, theta] (metres, radians), got {len(value)} values")
            return dict(zip(("x", "y", "theta"), value, strict=False))
        if not isinstance(value, dict | Pose):
            raise ValueError("a pose is [x, y] or [x, y, theta] (metres, radians), e.g. [1.5, 2.0, 0]")
        return value


class Clock(Strict):
    date: Annotated[dt.date, PlainValidator(as_date), PlainSerializer(lambda d: d.isoformat())] = dt.date(2026, 11, 25)
    timezone: str = "Europe/Madrid"
    start: ClockTime = "09:00"
    end: ClockTime = "14:00"
    rate: Real = Field(60.0, ge=MIN_CLOCK_RATE, le=1_000_000, description="sim seconds per wall second")
    skip_idle: bool = Field(True, description="jump the clock to the next mission when the robot is idle")
    days: int = Field(1, ge=1, le=MAX_DAYS, strict=True,
                      description="days the run spans, from date on (docs/long_runs.md); each day start-end")


    @field_validator("date")
    @classmethod
    def _date_range(cls, value: dt.date) -> dt.date:
        if not MIN_DATE <= value <= MAX_DATE:   # the agenda expands days around it; 9999-12-31 overflowed
            raise ValueError(f"the simulated day {value.isoformat()} is outside {MIN_DATE.year}-{MAX_DATE.year}")
        return value

    @field_validator("timezone")
    @classmethod
    def _tz(cls, value: str) -> str:
        from zoneinfo import ZoneInfo, ZoneInfoNotFoundError

        try:
            ZoneInfo(value)
        except (ZoneInfoNotFoundError, ValueError):
            raise ValueError(f"unknown time zone {value!r}") from None
        return value

    @field_validator("end")
    @classmethod
    def _order(cls, value: str, info: ValidationInfo) -> str:
        start = info.data.get("start")
        if start is not None and parse_clock(value) <= parse_clock(start):
            raise ValueError(f"the day's end {value!r} must be after its start {start!r}")
        return value

    @property
    def start_s(self) -> float:
        return parse_clock(self.start)

    @property
    def end_s(self) -> float:
        return parse_clock(self.end)


class Room(Strict):
    name: Name
    polygon: list[Point] = Field(min_length=3)


class Door(Strict):
    name: Name
    between: tuple[Name, Name]
    position: Point
    width: Real = Field(1.0, gt=0, le=20.0)


def _shape(value: Any) -> GeometryShape:
    """A shape mapping as written in the scene (``{shape: circle, radius: 1.5}``)."""
    if isinstance(value, Rectangle | Circle | Trapezoid):
        return value
    if not isinstance(value, dict):
        raise ValueError("a shape is a mapping such as {shape: circle, radius: 1.5}; "
                         "kinds: rectangle (length, width, offset), circle (radius), "
                         "trapezoid (height, near_width, far_width)")
    return shape_from_spec(value, where=str(value.get("shape", "shape")))


# The one shape definition (scenes/geometry.py), read from and written back to the scene's mapping form.
Shape = Annotated[GeometryShape, PlainValidator(_shape), PlainSerializer(shape_to_dict)]


class SceneObject(Strict):
    name: Name
    kind: Name = Field(description="tv, table, round_table, stretcher, bed, poster, ...")
    pose: Pose
    footprint: Shape
    interaction: Shape
    forbidden_while_active: bool = False


class Waypoint(Strict):
    time: ClockTime
    pose: Pose



# Walking speeds people have (m/s): a resident with a walker ~0.5, a brisk nurse ~1.3 (Bohannon 1997
# measured 0.6-1.5 m/s comfortable gait speeds from the 70s to the 20s).
MIN_WALK_SPEED_MPS = 0.4
MAX_WALK_SPEED_MPS = 1.5

Routine = Literal["stay", "wander", "staff", "visitor", "replay"]
#: how a ``routine: replay`` person follows their record (docs/crowds.md): ``exact`` walks it whatever the
#: robot does (SocNavBench); ``reactive`` starts on it and heads along it to its end, avoiding the robot (ORCA)
Replay = Literal["exact", "reactive"]


class PersonSpec(Strict):
    """One person of the scene and how they spend the day.

    ``routine``: ``stay`` (default) keeps the pose, or walks the timed ``waypoints``, and ignores the
    agenda (the shipped single-scenario scenes); ``wander`` (a resident: moves between rooms with
    dwell times, sits, chats), ``staff`` (crosses rooms briskly, fetches residents marked
    ``escort`` to their activities) and ``visitor`` (keeps company with ``visits``) walk by
    themselves, and every one of them goes to the activities they take part in."""

    name: Name
    role: Literal["resident", "new_resident", "staff", "therapist", "visitor"] = "resident"
    pose: Pose
    waypoints: list[Waypoint] = []
    interacting_with: list[Name] = Field(default_factory=list,
                                         description="people this one is in conversation with (all day); "
                                                     "interactions with objects come from the agenda")
    routine: Routine = "stay"
    home: Name | None = Field(None, description="the room the person returns to most (default: the room of pose)")
    rooms: list[Name] = Field(default_factory=list, description="rooms the routine goes to (default: all)")
    speed: Real | None = Field(None, ge=MIN_WALK_SPEED_MPS, le=MAX_WALK_SPEED_MPS,
                               description="walking speed, m/s (default by role; 0.5 with a walker)")
    walker: bool = Field(False, description="walks with a walking frame: slower, and wider")
    escort: bool = Field(False, description="staff fetch this person to their activities")
    dwell: tuple[Real, Real] | None = Field(None, description="min and max seconds spent at one place")
    visits: Name | None = Field(None, description="visitor: the person they keep company with")
    track: WholeNumber | None = Field(None, ge=0, description="replay: the person's id in the recording")
    recording: Name | None = Field(None, description="replay: which of the scene's recordings (default: the only one)")
    replay: Replay | None = Field(None, description="replay: exact or reactive (default: the crowd's)")
    hours: tuple[ClockTime, ClockTime] | None = Field(
        None, description="in the building from the first time to the second (a shift, a visit): they come in at "
                          "their pose, walk back there at the end and leave (default: all day)")

    @model_validator(mode="after")
    def _routine_fields(self) -> PersonSpec:
        moving = self.routine != "stay"
        if self.routine == "replay" and self.track is None:
            raise ValueError("routine 'replay' needs 'track': the person's id in the scene's recording")
        if self.routine != "replay" and (self.track is not None or self.recording or self.replay):
            raise ValueError("track, recording and replay belong to routine 'replay'")
        if moving and self.waypoints:
            raise ValueError(f"routine {self.routine!r} walks by itself: timed waypoints go with routine 'stay'")
        if self.visits is not None and self.routine != "visitor":
            raise ValueError("'visits' belongs to routine 'visitor'")
        if self.routine == "visitor" and self.visits is None:
            raise ValueError("routine 'visitor' needs 'visits': the person they come to see")
        if self.dwell is not None and not 0 < self.dwell[0] <= self.dwell[1]:
            raise ValueError(f"dwell [{self.dwell[0]:g}, {self.dwell[1]:g}] s: the minimum must be above 0 and "
                             "not above the maximum")
        if self.hours is not None and self.routine in ("stay", "replay"):
            raise ValueError(f"hours belong to a routine that walks (wander, staff or visitor); routine "
                             f"{self.routine!r} keeps its {'pose or waypoints' if self.routine == 'stay' else 'record'}")
        if self.hours is not None and parse_clock(self.hours[1]) <= parse_clock(self.hours[0]):
            raise ValueError(f"hours [{self.hours[0]}, {self.hours[1]}]: the time they leave must be after the time "
                             "they arrive")
        if not moving and (self.rooms or self.home or self.speed is not None or self.dwell or self.escort):
            raise ValueError("home, rooms, speed, dwell and escort describe a routine that walks; "
                             "this person has routine 'stay' (add routine: wander, staff or visitor)")
        return self


# Bounds a real robot meets; a value beyond them is a typo (radius: 50), not a robot.
MAX_ROBOT_RADIUS_M = 2.0
MAX_SPEED_MPS = 5.0


class RobotSpec(Strict):
    name: Name = "robot"
    pose: Pose
    radius: Real = Field(0.3, gt=0, le=MAX_ROBOT_RADIUS_M, description="m")
    kinematics: Literal["differential", "omnidirectional"] = "differential"
    max_speed: Real = Field(0.6, gt=0, le=MAX_SPEED_MPS, description="m/s")
    max_angular_speed: Real = Field(1.2, gt=0, le=20.0, description="rad/s")
    max_acceleration: Real = Field(0.8, gt=0, le=20.0, description="m/s^2")
    laser_range: Real = Field(5.0, gt=0, le=100.0, description="m")
    laser_rays: WholeNumber = Field(91, ge=3, le=4096)


class PoseGoal(Strict):
    pose: Pose


class RoomGoal(Strict):
    room: Name


class ObjectGoal(Strict):
    object: Name


class PersonGoal(Strict):
    person: Name


class GroupGoal(Strict):
    group: list[Name] = Field(min_length=2, description="people the robot faces together (takeTheAttention)")


class WaitGoal(Strict):
    wait: Name = Field(description="agenda activity id: the mission ends when that activity has")


_GOAL_KINDS = ("pose", "room", "object", "person", "group", "wait")
_GOALS = (PoseGoal, RoomGoal, ObjectGoal, PersonGoal, GroupGoal, WaitGoal)


def _goal_kind(value: Any) -> str | None:
    """Which goal a mapping is, by its key; None lets pydantic report "not one of them"."""
    if isinstance(value, _GOALS):
        return next(k for k in _GOAL_KINDS if hasattr(value, k))
    if isinstance(value, dict):
        kinds = [k for k in _GOAL_KINDS if k in value]
        return kinds[0] if len(kinds) == 1 else None
    return None


Goal = Annotated[Annotated[PoseGoal, Tag("pose")] | Annotated[RoomGoal, Tag("room")]
                 | Annotated[ObjectGoal, Tag("object")] | Annotated[PersonGoal, Tag("person")]
                 | Annotated[GroupGoal, Tag("group")] | Annotated[WaitGoal, Tag("wait")],
                 Discriminator(_goal_kind, custom_error_type="goal_kind",
                               custom_error_message="a goal is one of {pose: [x, y, theta]}, {room: NAME}, "
                                                    "{object: NAME}, {person: NAME}, {group: [P1, P2, ...]} "
                                                    "or {wait: ACTIVITY}")]


# The day of a scripted change in a multi-day scene: 1-based (``day: 2``) or a date; None: the first day.
DayRef = Annotated[int, Field(ge=1, le=MAX_DAYS, strict=True)] | DateItem | None


class Mission(Strict):
    id: Name
    time: ClockTime
    goal: Goal
    description: str = ""
    weekdays: list[Weekday] = Field(default_factory=list, description="days of the week it is given (default: every day)")
    dates: list[DateItem] = Field(default_factory=list, description="dates it is given (default: every day)")


    def goal_text(self) -> str:
        """The mission string of the executive (`room:X`, `object:X`, `person:X`, `group:P1+P2`,
        `wait:ACTIVITY`, `pose:x,y,theta`; agents/missions/kinds.py)."""
        goal = self.goal
        if isinstance(goal, PoseGoal):
            return f"pose:{goal.pose.x},{goal.pose.y},{goal.pose.theta}"
        if isinstance(goal, RoomGoal):
            return f"room:{goal.room}"
        if isinstance(goal, ObjectGoal):
            return f"object:{goal.object}"
        if isinstance(goal, GroupGoal):
            return "group:" + "+".join(goal.group)
        if isinstance(goal, WaitGoal):
            return f"wait:{goal.wait}"
        return f"person:{goal.person}"


class AgendaChange(Strict):
    """A staff edit scripted at a sim time (as if typed with `chronav agenda` during the run)."""

    at: ClockTime
    day: DayRef = Field(None, description="the day it happens on: 1-based or a date (default: the first)")
    op: Literal["add", "cancel", "move"]
    activity: dict[str, Any] | None = None
    id: str | None = None
    start: str | None = Field(None, description="new start (move): HH:MM or an ISO date-time")
    end: str | None = Field(None, description="new end (move): HH:MM or an ISO date-time")


class DoorChange(Strict):
    """A door opened or closed at a sim time (a world event the simulator carries out)."""

    at: ClockTime
    day: DayRef = Field(None, description="the day it happens on: 1-based or a date (default: the first)")
    door: Name
    open: bool



class CrowdSpec(Strict):
    """How the people with a walking routine are simulated (agents/lib/crowd)."""

    seed: WholeNumber = Field(0, ge=0, le=2**31 - 1, description="one seed gives one day, exactly")
    replay: Replay = Field("exact", description="how routine 'replay' people follow their record, "
                                                 "unless they say otherwise")


class RecordingSpec(Strict):
    """Recorded pedestrians (ETH/UCY text ``frame id x y``, scenes/crowd_recording.py) that the
    scene's ``routine: replay`` people walk; the file is relative to the scene."""

    name: Name
    file: str = Field(min_length=1, description="ETH/UCY text file, relative to the scene file")
    dt: Real = Field(0.4, gt=0, le=10.0, description="seconds between two annotated frames")
    start: ClockTime | None = Field(None, description="clock time of the file's first frame (default: the day's start)")


class MapRef(Strict):
    """A building map in the ROS map_server format (scenes/occupancy.py), relative to the scene."""

    file: str = Field(min_length=1, description="map_server .yaml naming a .pgm/.png image")
    unknown: Literal["wall", "free"] = Field("wall", description="what the map's unknown cells are")

    @model_validator(mode="before")
    @classmethod
    def _from_path(cls, value: Any) -> Any:
        """Accept the short form ``map: building.yaml``."""
        return {"file": value} if isinstance(value, str) else value


class Scene(Strict):
    name: Name
    description: str = ""
    resolution: Real = Field(0.05, ge=MIN_RESOLUTION_M, le=1.0, description="cost grid cell size (m)")
    clock: Clock = Clock()
    map: MapRef | None = Field(None, description="building map (ROS map_server format); its occupied cells are walls")
    walls: list[list[Point]] = Field(default_factory=list, description="polylines (at least one unless a map is given)")
    rooms: list[Room] = Field(min_length=1)
    doors: list[Door] = []
    objects: list[SceneObject] = []
    people: list[PersonSpec] = []
    crowd: CrowdSpec = CrowdSpec()
    recordings: list[RecordingSpec] = Field(default_factory=list, description="recorded pedestrians replayed "
                                                                               "by routine 'replay' people")
    robot: RobotSpec
    agenda: list[dict[str, Any]] = Field(default_factory=list, description="activities, see docs/agenda.md")
    agenda_file: str | None = Field(None, description=".yaml or .ics, relative to the scene file")
    agenda_changes: list[AgendaChange] = []
    door_changes: list[DoorChange] = []
    missions: list[Mission] = []
    # The map read from ``map.file`` (scenes/occupancy.OccupancyMap), attached by scenes/loader.py.
    _occupancy: Any = PrivateAttr(default=None)
    # The rooms as prepared shapely polygons, built once (room_at is asked for every person at every
    # tick); keyed by the rooms list, so a model_copy with other rooms builds its own.
    _room_shapes: Any = PrivateAttr(default=None)

    @model_validator(mode="after")
    def _walls_or_map(self) -> Scene:
        if not self.walls and self.map is None:
            raise ValueError("a scene needs walls (polylines) or a map (map: building.yaml)")
        return self

    def with_occupancy(self, occupancy: Any) -> Scene:
        """This scene standing on its loaded map: the grid takes the map's resolution, the bounds its extent."""
        scene = self.model_copy(update={"resolution": occupancy.resolution})
        scene._occupancy = occupancy
        return scene

    @property
    def occupancy(self) -> Any:
        """The scene's map (scenes/occupancy.OccupancyMap), or None for a scene of polylines only."""
        if self.map is not None and self._occupancy is None:
            raise RuntimeError(f"scene {self.name!r} has a map that was not loaded: load it with scenes.loader.load_scene")
        return self._occupancy

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """(xmin, ymin, xmax, ymax) of walls and rooms; the map's extent when the scene has a map
        (so the cost grid is the map's grid, cell for cell)."""
        if self.occupancy is not None:
            return self.occupancy.extent
        xs = [p[0] for wall in self.walls for p in wall] + [p[0] for r in self.rooms for p in r.polygon]
        ys = [p[1] for wall in self.walls for p in wall] + [p[1] for r in self.rooms for p in r.polygon]
        return (min(xs), min(ys), max(xs), max(ys))

    def room_at(self, x: float, y: float) -> str | None:
        """Name of the room containing (x, y) (first match), or None."""
        return self.rooms_at([x], [y])[0]

    def rooms_at(self, xs: Sequence[float], ys: Sequence[float]) -> list[str | None]:
        """``room_at`` of many points at once (one vectorised test per room: the observer asks for
        every person at every tick)."""
        import numpy as np
        import shapely

        if self._room_shapes is None or self._room_shapes[0] is not self.rooms:
            # one polygon at a time: rooms have different numbers of corners (a ragged array)
            shapes = np.array([shapely.Polygon(room.polygon) for room in self.rooms], dtype=object)
            shapely.prepare(shapes)
            self._room_shapes = (self.rooms, shapes)
        if not len(xs) or not self.rooms:
            return [None] * len(xs)
        # rooms x points; a point intersects = is covered
        inside = shapely.intersects_xy(self._room_shapes[1][:, np.newaxis], np.asarray(xs, dtype=np.float64),
                                       np.asarray(ys, dtype=np.float64))
        first = np.argmax(inside, axis=0).tolist()
        found = inside.any(axis=0).tolist()
        return [self.rooms[k].name if hit else None for k, hit in zip(first, found, strict=True)]
