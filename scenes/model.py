"""The scene file schema: the world a chronav run starts from.

Why pydantic models with ``extra="forbid"``: a typo such as ``radiuss:`` in a scene must be an
error naming the key and line, never a silently ignored value that changes a robot's clearance.
All lengths are metres, angles radians (theta measured from +x, counter-clockwise), clock times
``"HH:MM"`` (or ``"HH:MM:SS"``) local to the scene's time zone.
"""

from __future__ import annotations

import math
import datetime as dt
from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, PlainSerializer, PlainValidator, field_validator, model_validator

from scenes.clock import ClockTime, parse_clock
from scenes.geometry import Circle, Rectangle, Trapezoid, shape_from_spec, shape_to_dict
from scenes.geometry import Shape as GeometryShape


class Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


Point = tuple[float, float]


class Pose(Strict):
    x: float
    y: float
    theta: float = 0.0

    @model_validator(mode="before")
    @classmethod
    def _from_list(cls, value: Any) -> Any:
        """Accept the compact ``[x, y, theta]`` / ``[x, y]`` form used in scene files."""
        if isinstance(value, (list, tuple)):
            if len(value) not in (2, 3):
                raise ValueError("a pose is [x, y] or [x, y, theta]")
            return dict(zip(("x", "y", "theta"), value, strict=False))
        return value

    @field_validator("x", "y", "theta")
    @classmethod
    def _finite(cls, value: float) -> float:
        if not math.isfinite(value):
            raise ValueError("must be a finite number")
        return value


class Clock(Strict):
    date: dt.date = dt.date(2026, 11, 25)
    timezone: str = "Europe/Madrid"
    start: ClockTime = "09:00"
    end: ClockTime = "14:00"
    rate: float = Field(60.0, gt=0, description="sim seconds per wall second")
    skip_idle: bool = Field(True, description="jump the clock to the next mission when the robot is idle")


    @field_validator("timezone")
    @classmethod
    def _tz(cls, value: str) -> str:
        from zoneinfo import ZoneInfo, ZoneInfoNotFoundError

        try:
            ZoneInfo(value)
        except (ZoneInfoNotFoundError, ValueError):
            raise ValueError(f"unknown time zone {value!r}") from None
        return value

    @model_validator(mode="after")
    def _order(self) -> Clock:
        if parse_clock(self.end) <= parse_clock(self.start):
            raise ValueError("clock.end must be after clock.start")
        return self

    @property
    def start_s(self) -> float:
        return parse_clock(self.start)

    @property
    def end_s(self) -> float:
        return parse_clock(self.end)


class Room(Strict):
    name: str
    polygon: list[Point] = Field(min_length=3)


class Door(Strict):
    name: str
    between: tuple[str, str]
    position: Point
    width: float = Field(1.0, gt=0)


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
    name: str
    kind: str = Field(description="tv, table, round_table, stretcher, bed, poster, ...")
    pose: Pose
    footprint: Shape
    interaction: Shape
    forbidden_while_active: bool = False


class Waypoint(Strict):
    time: ClockTime
    pose: Pose



class PersonSpec(Strict):
    name: str
    role: Literal["resident", "new_resident", "staff", "therapist", "visitor"] = "resident"
    pose: Pose
    waypoints: list[Waypoint] = []
    interacting_with: list[str] = Field(default_factory=list,
                                        description="people this one is in conversation with (all day); "
                                                    "interactions with objects come from the agenda")

    @model_validator(mode="after")
    def _waypoints_in_order(self) -> PersonSpec:
        times = [parse_clock(w.time) for w in self.waypoints]
        if any(b <= a for a, b in zip(times, times[1:], strict=False)):
            raise ValueError("waypoints must be in strictly increasing time order")
        return self


class RobotSpec(Strict):
    name: str = "robot"
    pose: Pose
    radius: float = Field(0.3, gt=0)
    kinematics: Literal["differential", "omnidirectional"] = "differential"
    max_speed: float = Field(0.6, gt=0, description="m/s")
    max_angular_speed: float = Field(1.2, gt=0, description="rad/s")
    max_acceleration: float = Field(0.8, gt=0, description="m/s^2")
    laser_range: float = Field(5.0, gt=0)
    laser_rays: int = Field(91, ge=3)


class PoseGoal(Strict):
    pose: Pose


class RoomGoal(Strict):
    room: str


class ObjectGoal(Strict):
    object: str


class PersonGoal(Strict):
    person: str


class GroupGoal(Strict):
    group: list[str] = Field(min_length=2, description="people the robot faces together (takeTheAttention)")


class WaitGoal(Strict):
    wait: str = Field(min_length=1, description="agenda activity id: the mission ends when that activity has")


Goal = PoseGoal | RoomGoal | ObjectGoal | PersonGoal | GroupGoal | WaitGoal


class Mission(Strict):
    id: str
    time: ClockTime
    goal: Goal
    description: str = ""


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
    op: Literal["add", "cancel", "move"]
    activity: dict[str, Any] | None = None
    id: str | None = None
    start: str | None = Field(None, description="new start (move): HH:MM or an ISO date-time")
    end: str | None = Field(None, description="new end (move): HH:MM or an ISO date-time")


class DoorChange(Strict):
    """A door opened or closed at a sim time (a world event the simulator carries out)."""

    at: ClockTime
    door: str
    open: bool



class Scene(Strict):
    name: str
    description: str = ""
    resolution: float = Field(0.05, gt=0, le=1.0, description="cost grid cell size (m)")
    clock: Clock = Clock()
    walls: list[list[Point]] = Field(min_length=1, description="polylines")
    rooms: list[Room] = Field(min_length=1)
    doors: list[Door] = []
    objects: list[SceneObject] = []
    people: list[PersonSpec] = []
    robot: RobotSpec
    agenda: list[dict[str, Any]] = Field(default_factory=list, description="activities, see docs/agenda.md")
    agenda_file: str | None = Field(None, description=".yaml or .ics, relative to the scene file")
    agenda_changes: list[AgendaChange] = []
    door_changes: list[DoorChange] = []
    missions: list[Mission] = []

    @model_validator(mode="after")
    def _references(self) -> Scene:
        """Cross-references by name, so a misspelt room or object fails here and not mid-run."""
        for kind, items in (("room", self.rooms), ("object", self.objects), ("person", self.people),
                            ("door", self.doors)):
            seen: set[str] = set()
            for item in items:
                if item.name in seen:
                    raise ValueError(f"duplicate {kind} name {item.name!r}")
                seen.add(item.name)
        rooms = {r.name for r in self.rooms}
        objects = {o.name for o in self.objects}
        people = {p.name for p in self.people}
        for door in self.doors:
            for room in door.between:
                if room not in rooms:
                    raise ValueError(f"door {door.name!r} names unknown room {room!r}")
        doors = {d.name for d in self.doors}
        for change in self.door_changes:
            if change.door not in doors:
                raise ValueError(f"door_changes names unknown door {change.door!r}")
        for person in self.people:
            for other in person.interacting_with:
                if other in objects:
                    raise ValueError(f"person {person.name!r}: interacting_with names the object {other!r}; "
                                     "links to objects come from the agenda: add an activity on it with "
                                     f"{person.name!r} among its participants")
                if other not in people or other == person.name:
                    raise ValueError(f"person {person.name!r} interacts with unknown person {other!r}")
        for mission in self.missions:
            goal = mission.goal
            if isinstance(goal, RoomGoal) and goal.room not in rooms:
                raise ValueError(f"mission {mission.id!r} targets unknown room {goal.room!r}")
            if isinstance(goal, ObjectGoal) and goal.object not in objects:
                raise ValueError(f"mission {mission.id!r} targets unknown object {goal.object!r}")
            if isinstance(goal, PersonGoal) and goal.person not in people:
                raise ValueError(f"mission {mission.id!r} targets unknown person {goal.person!r}")
            if isinstance(goal, GroupGoal):
                unknown = [p for p in goal.group if p not in people]
                if unknown:
                    raise ValueError(f"mission {mission.id!r}: group names unknown person {unknown[0]!r}")
                if len(set(goal.group)) != len(goal.group):
                    raise ValueError(f"mission {mission.id!r}: group names someone twice")
        ids = [m.id for m in self.missions]
        if len(ids) != len(set(ids)):
            raise ValueError("mission ids must be unique")
        return self

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """(xmin, ymin, xmax, ymax) of walls and rooms."""
        xs = [p[0] for wall in self.walls for p in wall] + [p[0] for r in self.rooms for p in r.polygon]
        ys = [p[1] for wall in self.walls for p in wall] + [p[1] for r in self.rooms for p in r.polygon]
        return (min(xs), min(ys), max(xs), max(ys))

    def room_at(self, x: float, y: float) -> str | None:
        """Name of the room containing (x, y) (first match), or None."""
        import shapely

        for room in self.rooms:
            if shapely.Polygon(room.polygon).covers(shapely.Point(x, y)):
                return room.name
        return None
