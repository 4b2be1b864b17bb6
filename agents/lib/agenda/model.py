"""The centre's agenda as data: activities as staff write them, and as resolved for one sim day.

Why two models: staff write times as "11:00" or as ISO date-times in a file (``ActivitySpec``);
the rest of chronav wants plain numbers on the sim clock (``Activity.start_s``/``end_s``, seconds
since local midnight of the sim day).  Resolution needs the date and the centre's time zone, so
it happens once per day in :mod:`agents.lib.agenda.expand`, never inside the agents' hot loops.

Time convention: ``start_s``/``end_s`` are *wall-clock* seconds of the centre's local time since
midnight of the sim day (10:00 is 36000.0 even on the day the clocks go forward), because scenes,
missions and the sim clock all count time that way.  Times on the previous or next day are
negative or beyond 86400.  See docs/agenda.md for how DST days are handled.
"""

from __future__ import annotations

import builtins
import datetime as dt
import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Annotated
from zoneinfo import ZoneInfo, ZoneInfoNotFoundError

from pydantic import (AfterValidator, BaseModel, ConfigDict, Field, StringConstraints, ValidationInfo,
                      field_validator, model_validator)

from agents.lib.states import ActivityState  # the one definition; re-exported (the vocabulary's too)
from scenes.clock import CLOCK_PATTERN, format_clock, parse_clock
from scenes.days import DateItem, Weekday
from scenes.names import check_name, shown
from scenes.yamlio import SourceError

SECONDS_PER_DAY = 86400.0


def _one_word(value: str) -> str:
    if any(ch.isspace() for ch in value):
        raise ValueError(f"an id is one word without spaces, got {shown(value, 60)!r}")
    return value


# Names and ids staff type: bounded, printable (scenes/names.py); an id is also one word.
NonEmptyStr = Annotated[str, StringConstraints(strip_whitespace=True), AfterValidator(check_name)]
ActivityId = Annotated[str, StringConstraints(strip_whitespace=True), AfterValidator(check_name),
                       AfterValidator(_one_word)]


# ---------------------------------------------------------------------------------------------
# Errors shared by every module of the package.
# ---------------------------------------------------------------------------------------------

class AgendaError(Exception):
    """Base of every agenda error, so an agent can refuse bad input without crashing."""


def problem(file: str, line: int | None, message: str, key: str = "", column: int | None = None) -> SourceError:
    """One located problem of an agenda file: the same SourceError every input file uses."""
    return SourceError(file, line, column, key, message)


class AgendaSourceError(AgendaError, ValueError):
    """An agenda file (YAML or .ics) could not be read; lists *every* problem found, one a line.

    Each problem is a :class:`scenes.yamlio.SourceError` (file, line, column, key, message)."""

    def __init__(self, problems: list[SourceError]) -> None:
        if not problems:
            raise ValueError("AgendaSourceError needs at least one problem")
        self.problems: tuple[SourceError, ...] = tuple(problems)
        super().__init__("\n".join(str(p) for p in self.problems))


class UnknownActivityError(AgendaError, LookupError):
    """An activity id that is not in the day's agenda."""

    def __init__(self, activity_id: str, known: list[str]) -> None:
        self.activity_id = activity_id
        listed = ", ".join(known) if known else "none"
        super().__init__(f"no activity with id {activity_id!r} today (ids: {listed})")

    def __str__(self) -> str:  # LookupError would quote the message like a key
        return str(self.args[0])


# ---------------------------------------------------------------------------------------------
# Time helpers.
# ---------------------------------------------------------------------------------------------

def parse_when(text: str) -> float | dt.datetime:
    """A spec time: clock time -> seconds since midnight, ISO date-time -> datetime (maybe naive)."""
    stripped = text.strip()
    if CLOCK_PATTERN.match(stripped):
        return parse_clock(stripped)
    try:
        moment = dt.datetime.fromisoformat(stripped)
    except ValueError:
        raise ValueError(f"{text!r} is not a time: use HH:MM (e.g. \"11:00\") or an ISO date-time "
                         "(e.g. \"2026-11-25T11:00\" or \"2026-11-25T10:00Z\")") from None
    if "T" not in stripped and " " not in stripped:
        raise ValueError(f"{text!r} is a date without a time of day; add one, e.g. \"{stripped}T11:00\"")
    return moment


def load_zone(tz: str | dt.tzinfo) -> dt.tzinfo:
    """An IANA zone name (or a tzinfo, passed through) -> tzinfo; unknown names get a clear error."""
    if isinstance(tz, dt.tzinfo):
        return tz
    try:
        return ZoneInfo(tz)
    except (ZoneInfoNotFoundError, ValueError):
        raise AgendaError(f"unknown time zone {tz!r}: use an IANA name such as 'Europe/Madrid' "
                          "or 'UTC'") from None


def local_midnight(day: dt.date, zone: dt.tzinfo) -> dt.datetime:
    """The aware instant at which ``day`` starts in ``zone``."""
    return dt.datetime.combine(day, dt.time(0, 0), tzinfo=zone)


def wall_seconds(moment: dt.datetime, day: dt.date, zone: dt.tzinfo) -> float:
    """Wall-clock seconds of ``moment`` (aware) in ``zone``, counted from midnight of ``day``."""
    local = moment.astimezone(zone)
    days = (local.date() - day).days
    return (days * SECONDS_PER_DAY + local.hour * 3600 + local.minute * 60 + local.second
            + local.microsecond / 1e6)


# ---------------------------------------------------------------------------------------------
# Models.
# ---------------------------------------------------------------------------------------------

@dataclass(frozen=True, slots=True)
class ActivityWindow:
    """One scheduled use of an object, the input of R(t): ``object`` is the object's name, times in
    seconds since local midnight. A cancelled window is kept (for display) but has no effect."""

    object: str
    start_s: float
    end_s: float
    cancelled: bool = False

    def __post_init__(self) -> None:
        owner = f"activity on {self.object!r}"
        for name in ("start_s", "end_s"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise AgendaError(f"{owner}: {name} must be a finite number, got {value!r}")
            object.__setattr__(self, name, float(value))
        if self.end_s < self.start_s:
            raise AgendaError(f"{owner}: end_s ({self.end_s:g}) is before start_s ({self.start_s:g})")

    def running_at(self, t_s: float) -> bool:
        """The one rule for "is this activity running": [start, end), never when cancelled."""
        return not self.cancelled and self.start_s <= t_s < self.end_s


def _time_text(value: object) -> object:
    """Accept datetime/time objects from Python callers; refuse numbers (YAML reads 11:00 as 660)."""
    if isinstance(value, (bool, int, float)):
        raise ValueError(f"got the number {value!r}; write the time in quotes, e.g. \"11:00\" "
                         "(unquoted, YAML 1.1 reads 11:00 as the number 660)")
    if isinstance(value, dt.datetime):
        return value.isoformat()
    if isinstance(value, dt.time):
        return value.isoformat(timespec="seconds")
    return value


class ActivitySpec(BaseModel):
    """One activity as staff write it in YAML (or as `chronav agenda add` sends it).

    ``start``/``end``: ``"HH:MM"`` (on every sim day) or an ISO date-time (only on its date;
    without an offset it is local time of the centre).  ``id`` is derived when absent (see
    :func:`agents.lib.agenda.expand.derive_id`).  ``source`` is filled by the loaders (file:line).
    """

    model_config = ConfigDict(frozen=True, extra="forbid")

    id: ActivityId | None = None
    name: NonEmptyStr
    object: NonEmptyStr
    room: NonEmptyStr | None = None
    start: NonEmptyStr
    end: NonEmptyStr
    participants: tuple[NonEmptyStr, ...] = ()
    kind: NonEmptyStr | None = None
    weekdays: tuple[Weekday, ...] = Field((), description="days of the week it happens (default: every day)")
    dates: tuple[DateItem, ...] = Field((), description="dates it happens (default: every day)")
    source: str = Field("", description="where it was written (file:line); set by loaders")

    @field_validator("start", "end", mode="before")
    @classmethod
    def _coerce_time(cls, value: builtins.object) -> builtins.object:
        return _time_text(value)

    @field_validator("start")
    @classmethod
    def _check_start(cls, value: str) -> str:
        parse_when(value)
        return value

    @field_validator("end")
    @classmethod
    def _check_end(cls, value: str, info: ValidationInfo) -> str:
        """Catch end-before-start here when both are comparable, so YAML errors point at `end`."""
        end = parse_when(value)
        start_text = info.data.get("start")
        if start_text is None:
            return value
        start = parse_when(start_text)
        comparable = (isinstance(start, float) and isinstance(end, float)) or (
            isinstance(start, dt.datetime) and isinstance(end, dt.datetime)
            and (start.tzinfo is None) == (end.tzinfo is None))
        if comparable and end <= start:  # type: ignore[operator]  # `comparable`: both floats or both datetimes
            raise ValueError(f"end {value!r} is not after start {start_text!r}")
        return value

    @field_validator("participants", mode="before")
    @classmethod
    def _participants_list(cls, value: builtins.object) -> builtins.object:
        if isinstance(value, str):
            raise ValueError("participants must be a list, e.g. [ana, luis]")
        return value


class Activity(BaseModel):
    """One activity resolved for one sim day: what the agenda agent writes to the DSR."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    id: ActivityId
    name: NonEmptyStr
    object: NonEmptyStr
    room: str | None = None
    start_s: float
    end_s: float
    participants: tuple[NonEmptyStr, ...] = ()
    state: ActivityState = ActivityState.SCHEDULED
    source: str
    kind: str | None = None

    @model_validator(mode="after")
    def _interval(self) -> Activity:
        if not (math.isfinite(self.start_s) and math.isfinite(self.end_s)):
            raise ValueError(f"activity {self.id!r}: start_s and end_s must be finite")
        if self.end_s <= self.start_s:
            raise ValueError(f"activity {self.id!r}: end {format_clock(self.end_s)} is not after "
                             f"start {format_clock(self.start_s)}")
        return self

    @property
    def cancelled(self) -> bool:
        return self.state is ActivityState.CANCELLED

    def window(self) -> ActivityWindow:
        """(object, start_s, end_s, cancelled): what R(t) and "is it running" are computed from."""
        return ActivityWindow(object=self.object, start_s=self.start_s, end_s=self.end_s, cancelled=self.cancelled)

    def at(self, now_s: float, upcoming_window_s: float) -> Activity:
        """This activity with its state brought up to the sim clock (same object if unchanged)."""
        state = activity_state(self, now_s, upcoming_window_s)
        return self if state is self.state else self.model_copy(update={"state": state})


def activity_state(activity: Activity, now_s: float, upcoming_window_s: float) -> ActivityState:
    """State at ``now_s``: cancelled sticks; else scheduled -> upcoming -> running -> finished.

    ``upcoming`` starts ``upcoming_window_s`` before the start (the ramp of R(t) in the seed);
    running is ``[start_s, end_s)``.
    """
    if upcoming_window_s < 0:
        raise ValueError("upcoming_window_s must be >= 0")
    if activity.state is ActivityState.CANCELLED:
        return ActivityState.CANCELLED
    if now_s >= activity.end_s:
        return ActivityState.FINISHED
    if activity.window().running_at(now_s):
        return ActivityState.RUNNING
    if now_s >= activity.start_s - upcoming_window_s:
        return ActivityState.UPCOMING
    return ActivityState.SCHEDULED


class AgendaDay(BaseModel):
    """The agenda of one sim day: activities sorted by start, unique ids, one time zone."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    date: dt.date
    tz: str = Field(description="IANA time zone of the centre, e.g. Europe/Madrid")
    activities: tuple[Activity, ...] = ()

    @field_validator("tz")
    @classmethod
    def _known_zone(cls, value: str) -> str:
        try:
            load_zone(value)
        except AgendaError as exc:
            raise ValueError(str(exc)) from None
        return value

    @field_validator("activities")
    @classmethod
    def _sorted_unique(cls, value: tuple[Activity, ...]) -> tuple[Activity, ...]:
        seen: dict[str, str] = {}
        for activity in value:
            if activity.id in seen:
                raise ValueError(f"duplicate activity id {activity.id!r} ({seen[activity.id]} and "
                                 f"{activity.source})")
            seen[activity.id] = activity.source
        return tuple(sorted(value, key=lambda a: (a.start_s, a.object, a.id)))

    @property
    def zone(self) -> dt.tzinfo:
        return load_zone(self.tz)

    def ids(self) -> list[str]:
        return [a.id for a in self.activities]

    def find(self, activity_id: str) -> Activity | None:
        return next((a for a in self.activities if a.id == activity_id), None)

    def get(self, activity_id: str) -> Activity:
        """The activity with this id, or UnknownActivityError listing today's ids."""
        found = self.find(activity_id)
        if found is None:
            raise UnknownActivityError(activity_id, self.ids())
        return found

    def objects(self) -> frozenset[str]:
        return frozenset(a.object for a in self.activities)

    def on_object(self, object_name: str, *, include_cancelled: bool = True) -> tuple[Activity, ...]:
        return tuple(a for a in self.activities if a.object == object_name
                     and (include_cancelled or not a.cancelled))

    def windows(self) -> list[ActivityWindow]:
        """(object, start_s, end_s, cancelled) for every activity, the input of R(t)."""
        return [a.window() for a in self.activities]

    def at(self, now_s: float, upcoming_window_s: float) -> AgendaDay:
        """The same day with every state brought up to the sim clock."""
        return self.with_activities(a.at(now_s, upcoming_window_s) for a in self.activities)

    def with_activities(self, activities: Iterable[Activity]) -> AgendaDay:
        """A new day (same date and zone) holding ``activities`` (validated again)."""
        return AgendaDay(date=self.date, tz=self.tz, activities=tuple(activities))

    def seconds_of(self, moment: dt.datetime) -> float:
        """An aware instant -> wall-clock seconds since this day's local midnight."""
        if moment.tzinfo is None:
            raise ValueError("seconds_of needs an aware datetime")
        return wall_seconds(moment, self.date, self.zone)
