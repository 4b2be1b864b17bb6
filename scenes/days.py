"""Scenes that span days: which date each day is, what happens on it, and one day's own scene.

Why days are run one at a time, each on its own single-day scene: every consumer of a scene (the
agenda's expansion and R(t), the simulator's clock and its idle skips, the executive's missions,
recordings, metrics, the offline commands) counts time as seconds since local midnight of the
scene's date.  A week is therefore N single-day scenes, written by :func:`day_scene_data`, each
with its own date; nothing below the week runner (tools/week.py) has to know about weeks, and a
single-day scene behaves exactly as before.

Time across days (index.json, result.json, the progress line): *week seconds*, seconds since local
midnight of the first date, so day 2 at 09:00 is ``86400 + 32400``
(:func:`week_seconds`).  Within a day, everything stays on that day's clock.

What belongs to which day:
- agenda activities (YAML) and missions: ``weekdays: [mon, wed]`` and/or ``dates: [2026-11-30]``;
  with neither, every day; with both, a day matching either;
- ``.ics`` activities: their own recurrences, expanded over each date by the agenda;
- scripted ``agenda_changes`` and ``door_changes``: ``day: 2`` (1-based) or ``day: 2026-11-26``;
  without ``day``, the first day (what a single-day scene always meant).
"""

from __future__ import annotations

import datetime as dt
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Annotated, Any

from pydantic import AfterValidator, BeforeValidator

SECONDS_PER_DAY = 86400.0
WEEKDAYS: tuple[str, ...] = ("mon", "tue", "wed", "thu", "fri", "sat", "sun")
_FULL = ("monday", "tuesday", "wednesday", "thursday", "friday", "saturday", "sunday")
#: a scene spans at most a year of days (a run of a year still rotates its recording per day)
MAX_DAYS = 366
#: the id of the mission that takes the robot back to its dock at the end of each day of a run of days
DOCK_MISSION = "dock"


def parse_weekday(value: object) -> str:
    """``mon``/``Monday``/``MON`` -> ``"mon"``; anything else is refused with the accepted forms."""
    text = str(value).strip().lower() if isinstance(value, str) else ""
    if text in WEEKDAYS:
        return text
    if text in _FULL:
        return WEEKDAYS[_FULL.index(text)]
    raise ValueError(f"{value!r} is not a day of the week; use {', '.join(WEEKDAYS)} (or the full English name)")


def _checked_weekday(value: str) -> str:
    return parse_weekday(value)


def _as_date_item(value: Any) -> Any:
    from scenes.yamlio import as_date

    return as_date(value)


# A day of the week as scene and agenda files write it, normalised to its three-letter form.
Weekday = Annotated[str, AfterValidator(_checked_weekday)]
# A calendar date as scene and agenda files write it (2026-11-25).
DateItem = Annotated[dt.date, BeforeValidator(_as_date_item)]


def weekday_of(date: dt.date) -> str:
    return WEEKDAYS[date.weekday()]


def on_day(weekdays: Iterable[str], dates: Iterable[dt.date], date: dt.date) -> bool:
    """Whether an item limited to ``weekdays`` and/or ``dates`` happens on ``date`` (neither: every day)."""
    weekdays, dates = tuple(weekdays), tuple(dates)
    if not weekdays and not dates:
        return True
    return weekday_of(date) in weekdays or date in dates


def scene_dates(first: dt.date, days: int) -> list[dt.date]:
    """The calendar dates of a run of ``days`` days starting on ``first``."""
    return [first + dt.timedelta(days=index) for index in range(days)]


def week_seconds(day_index: int, clock_s: float) -> float:
    """Seconds since midnight of the first date: day 2 (index 1) at 09:00 is 86400 + 32400."""
    return day_index * SECONDS_PER_DAY + clock_s


def day_number(value: int | dt.date | None, first: dt.date) -> int:
    """A ``day:`` key -> its 1-based day number (None: day 1; a date: its place after ``first``)."""
    if value is None:
        return 1
    if isinstance(value, dt.date):
        return (value - first).days + 1
    return int(value)


def _items_on_day(items: object, date: dt.date) -> list[Any]:
    """The mappings of a YAML list kept on ``date``, their ``weekdays``/``dates`` keys dropped."""
    kept: list[Any] = []
    for item in items if isinstance(items, list) else []:
        if not isinstance(item, Mapping):
            kept.append(item)
            continue
        weekdays = [parse_weekday(w) for w in item.get("weekdays") or []]
        dates = [_as_date_item(d) for d in item.get("dates") or []]
        if on_day(weekdays, dates, date):
            kept.append({k: v for k, v in item.items() if k not in ("weekdays", "dates")})
    return kept


def _changes_on_day(items: object, number: int, first: dt.date) -> list[Any]:
    """The scripted changes of day ``number``, their ``day`` key dropped."""
    kept: list[Any] = []
    for item in items if isinstance(items, list) else []:
        if isinstance(item, Mapping):
            raw = item.get("day")
            value = _as_date_item(raw) if isinstance(raw, (str, dt.date)) else raw
            if day_number(value, first) == number:
                kept.append({k: v for k, v in item.items() if k != "day"})
    return kept


def day_scene_data(data: Mapping[str, Any], number: int, scene_dir: Path, *, first: dt.date,
                   seed_offset: int = 0) -> dict[str, Any]:
    """The single-day scene of day ``number`` (1-based) of a multi-day scene, as a YAML mapping.

    Its date is ``first`` + number - 1 and ``days`` 1; activities and missions keep those of that
    date; scripted changes those naming that day; relative files (``agenda_file``, ``map``) become
    absolute (the day's scene is written elsewhere); the crowd's seed moves by ``seed_offset`` so
    days differ but a week is reproducible; the name says the day.  Everything else is as written:
    the robot starts the day at its pose (its dock), the people at theirs, and a day with missions
    ends with the robot driving back there (:func:`dock_mission`)."""
    date = first + dt.timedelta(days=number - 1)
    out = dict(data)
    clock = dict(out.get("clock") or {})
    clock.pop("days", None)
    clock["date"] = date
    out["clock"] = clock
    out["name"] = f"{data.get('name', 'scene')}-day{number}"
    out["agenda"] = _items_on_day(data.get("agenda"), date)
    out["missions"] = _items_on_day(data.get("missions"), date)
    dock = dock_mission(out)
    if dock is not None:
        out["missions"].append(dock)
    out["agenda_changes"] = _changes_on_day(data.get("agenda_changes"), number, first)
    out["door_changes"] = _changes_on_day(data.get("door_changes"), number, first)
    if isinstance(out.get("agenda_file"), str):
        out["agenda_file"] = str((scene_dir / out["agenda_file"]).resolve())
    if isinstance(out.get("map"), str):
        out["map"] = str((scene_dir / out["map"]).resolve())
    elif isinstance(out.get("map"), Mapping) and isinstance(out["map"].get("file"), str):
        out["map"] = {**out["map"], "file": str((scene_dir / out["map"]["file"]).resolve())}
    if seed_offset:
        crowd = dict(out.get("crowd") or {})
        crowd["seed"] = (int(crowd.get("seed", 0)) + seed_offset) % (2**31 - 1)
        out["crowd"] = crowd
    return out


def dock_mission(day: Mapping[str, Any]) -> dict[str, Any] | None:
    """The day's last mission: the robot back to its dock (the scene's robot pose) for the night.

    Why a mission: the executive then plans, drives and reports it like any other (result.json
    counts it, a blocked dock fails it with the reason), and the day ends once it is over, so the
    next day's start at the dock is where the robot really is.  It is due one second after the
    day's last mission (missions run one at a time, in the order they are due), so it waits for
    that one to end.  None for a day without missions (the robot never left the dock), a scene
    without a robot pose, or mission times that are not clock times (the scene's check says why);
    a scene that already has a mission ``dock`` that day keeps it as its own."""
    from scenes.clock import format_clock, parse_clock

    missions = [m for m in day.get("missions") or [] if isinstance(m, Mapping)]
    robot = day.get("robot")
    pose = robot.get("pose") if isinstance(robot, Mapping) else None
    if not missions or pose is None or any(m.get("id") == DOCK_MISSION for m in missions):
        return None
    try:
        last = max(parse_clock(str(m.get("time"))) for m in missions)
    except ValueError:
        return None
    return {"id": DOCK_MISSION, "time": format_clock(last + 1.0), "goal": {"pose": pose},
            "description": "back to the dock for the night"}
