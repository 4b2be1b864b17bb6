"""Expand agenda sources (YAML specs, .ics calendars) into the activities of one sim day.

Why one function for every source: the agenda agent and `chronav agenda load` both need "the
activities on this date in this zone, checked against the objects that exist", whatever the
staff wrote them in.  Recurrences, time zones and ids are settled here, once a day.

DST rule: ``start_s`` is the wall-clock time of the start; ``end_s`` is the wall-clock time of
the end, but never less than ``start_s`` plus the real duration (on the night the clocks go back
an activity from 02:30 CEST to 02:30 CET lasts one hour, not zero).
"""

from __future__ import annotations

import datetime as dt
import re
from collections.abc import Collection, Iterable
from dataclasses import dataclass
from typing import cast
from zoneinfo import ZoneInfo

from agents.lib.agenda.ics_source import IcsAgenda, IcsOccurrence
from agents.lib.agenda.model import (SECONDS_PER_DAY, Activity, ActivitySpec, ActivityState, AgendaDay,
                                 AgendaError, load_zone, parse_when, wall_seconds)
from agents.lib.agenda.validate import ActivityLike, validate_activities
from scenes.days import on_day as on_date

AgendaSource = ActivitySpec | IcsAgenda
UTC = dt.UTC


@dataclass(frozen=True)
class Draft:
    """An activity placed on the day but not yet given its final id (satisfies ActivityLike)."""

    id: str | None
    name: str
    object: str
    room: str | None
    start_s: float
    end_s: float
    participants: tuple[str, ...]
    kind: str | None
    source: str
    cancelled: bool = False

    def to_activity(self) -> Activity:
        if self.id is None:
            raise AgendaError(f"internal: activity from {self.source} has no id yet")
        return Activity(id=self.id, name=self.name, object=self.object, room=self.room,
                        start_s=self.start_s, end_s=self.end_s, participants=self.participants,
                        kind=self.kind, source=self.source,
                        state=ActivityState.CANCELLED if self.cancelled else ActivityState.SCHEDULED)


def _span(start: dt.datetime, end: dt.datetime, exact: bool, day: dt.date,
          zone: dt.tzinfo) -> tuple[float, float]:
    """Aware instants -> (start_s, end_s) on the day's wall clock, with the DST rule above."""
    start_s = wall_seconds(start, day, zone)
    end_s = wall_seconds(end, day, zone)
    real = (end.astimezone(UTC) - start.astimezone(UTC)).total_seconds()
    if exact and real > 0:
        end_s = max(end_s, start_s + real)
    return start_s, end_s


def resolve_spec(spec: ActivitySpec, day: dt.date, zone: dt.tzinfo) -> Draft | None:
    """Place a YAML/CLI spec on ``day``; None if its ISO date-times, or its ``weekdays``/``dates``
    (scenes/days.py), put it on another day."""
    if not on_date(spec.weekdays, spec.dates, day):
        return None
    start, end = parse_when(spec.start), parse_when(spec.end)
    moments: list[float | dt.datetime] = []
    for value in (start, end):
        if isinstance(value, dt.datetime) and value.tzinfo is None:
            value = value.replace(tzinfo=zone)  # no offset: local time of the centre
        moments.append(value)
    first, last = moments
    if isinstance(first, dt.datetime) and isinstance(last, dt.datetime):
        start_s, end_s = _span(first, last, True, day, zone)
    else:
        start_s = first if isinstance(first, float) else wall_seconds(first, day, zone)
        end_s = last if isinstance(last, float) else wall_seconds(last, day, zone)
    on_day = start_s < SECONDS_PER_DAY and end_s > 0.0
    if start_s < end_s and not on_day:
        return None  # a well-formed activity of another date; a bad interval is kept to be reported
    return Draft(id=spec.id, name=spec.name, object=spec.object, room=spec.room, start_s=start_s,
                 end_s=end_s, participants=tuple(spec.participants), kind=spec.kind,
                 source=spec.source or "(no source)")


def _from_occurrence(occurrence: IcsOccurrence, day: dt.date, zone: dt.tzinfo) -> Draft:
    start_s, end_s = _span(occurrence.start, occurrence.end, occurrence.exact, day, zone)
    return Draft(id=None, name=occurrence.name, object=occurrence.object, room=occurrence.room,
                 start_s=start_s, end_s=end_s, participants=occurrence.participants,
                 kind=occurrence.kind, source=occurrence.source, cancelled=occurrence.cancelled)


def _slug(text: str) -> str:
    slug = re.sub(r"[^a-z0-9_]+", "-", text.lower()).strip("-")
    return slug or "activity"


def derive_id(object_name: str, start_s: float, taken: Collection[str]) -> str:
    """``<object>-<HHMM>`` (e.g. ``tv-1100``), then ``-2``, ``-3``... if taken; stable across reloads.

    Times on the previous/next day get a ``p``/``n`` prefix (``tv-p2330``).
    """
    minutes = int(start_s // 60)
    prefix = ""
    if minutes < 0:
        prefix, minutes = "p", minutes + 1440
    elif minutes >= 1440:
        prefix, minutes = "n", minutes - 1440
    base = f"{_slug(object_name)}-{prefix}{minutes // 60:02d}{minutes % 60:02d}"
    candidate, number = base, 2
    while candidate in taken:
        candidate, number = f"{base}-{number}", number + 1
    return candidate


def with_ids(drafts: list[Draft]) -> list[ActivityLike]:
    """``drafts`` as validation reads them, once ``assign_ids`` has given each its id (checked)."""
    missing = [d.source for d in drafts if d.id is None]
    if missing:
        raise ValueError(f"drafts without an id (call assign_ids first): {missing}")
    return cast("list[ActivityLike]", drafts)


def assign_ids(drafts: Iterable[Draft], taken: Collection[str] = ()) -> list[Draft]:
    """Give every draft without an id a derived one, in a deterministic order."""
    items = list(drafts)
    used = set(taken) | {d.id for d in items if d.id is not None}
    result: list[Draft] = []
    for draft in sorted(items, key=lambda d: (d.start_s, d.object, d.name, d.source)):
        if draft.id is None:
            new_id = derive_id(draft.object, draft.start_s, used)
            used.add(new_id)
            draft = Draft(**{**draft.__dict__, "id": new_id})
        result.append(draft)
    return result


def zone_name(tz: str | ZoneInfo) -> str:
    """The IANA name stored in an AgendaDay."""
    if isinstance(tz, str):
        load_zone(tz)
        return tz
    if isinstance(tz, ZoneInfo):
        return tz.key
    raise AgendaError(f"time zone must be an IANA name or a ZoneInfo, got {tz!r}")


def drafts_for_day(sources: Iterable[AgendaSource], day: dt.date, zone: dt.tzinfo) -> list[Draft]:
    """Every source's activities on ``day``, ids not yet assigned."""
    drafts: list[Draft] = []
    for source in sources:
        if isinstance(source, ActivitySpec):
            draft = resolve_spec(source, day, zone)
            if draft is not None:
                drafts.append(draft)
        elif isinstance(source, IcsAgenda):
            drafts.extend(_from_occurrence(o, day, zone) for o in source.occurrences(day, zone))
        else:
            raise AgendaError(f"not an agenda source: {type(source).__name__} (expected ActivitySpec "
                              "or IcsAgenda)")
    return drafts


def expand_day(sources: Iterable[AgendaSource], day: dt.date, tz: str | ZoneInfo,
               known_objects: Collection[str] | None, *,
               known_rooms: Collection[str] | None = None,
               known_people: Collection[str] | None = None) -> AgendaDay:
    """The validated agenda of ``day`` in the centre's zone ``tz``.

    ``known_objects``: the scene's object names (None skips that check, e.g. to lint a file
    alone); likewise ``known_rooms`` and ``known_people`` (participants).  Raises AgendaValidationError listing every error (unknown object, end not after
    start, duplicate id); overlaps are only infos, see ``validate_day``.
    """
    name = zone_name(tz)
    zone = load_zone(name)
    drafts = assign_ids(drafts_for_day(sources, day, zone))
    validate_activities(with_ids(drafts), known_objects, known_rooms, known_people).raise_if_errors()
    return AgendaDay(date=day, tz=name, activities=tuple(d.to_activity() for d in drafts))
