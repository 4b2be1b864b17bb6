"""Agenda activities from iCalendar (.ics) files, the format staff calendars already export.

Why parse with ``icalendar`` and expand with ``dateutil.rrule`` ourselves: icalendar resolves
time zones (IANA TZIDs, Windows names and the file's own VTIMEZONE blocks) but does not expand
recurrences; dateutil does RRULE arithmetic but knows nothing of EXDATE in other zones or of
RECURRENCE-ID overrides.  Recurrences are expanded in the *wall-clock time of the event's own
zone*, so a daily 10:00 therapy in Europe/Madrid stays at 10:00 across a DST change.

Conventions (docs/agenda.md):
- object: ``X-CHRONAV-OBJECT``, else ``LOCATION`` (the object's name in the scene);
- room: ``X-CHRONAV-ROOM``; kind: ``X-CHRONAV-KIND``, else the first ``CATEGORIES``;
- participants: ``X-CHRONAV-PARTICIPANTS`` (comma-separated), else each ``ATTENDEE``'s CN;
- name: ``SUMMARY`` (else the object's name); ``STATUS:CANCELLED`` -> a cancelled activity;
- floating times and all-day (DATE) events are in the centre's time zone.
"""

from __future__ import annotations

import datetime as dt
import re
from collections.abc import Iterable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import icalendar

from scenes.yamlio import SourceError
from dateutil import rrule

from agents.lib.agenda.model import AgendaSourceError, local_midnight, problem

UTC = dt.timezone.utc
_UNESCAPED_COMMA = re.compile(r"(?<!\\),")

Moment = dt.date | dt.datetime  # DATE, floating (naive) or zoned (aware) date-time


@dataclass(frozen=True)
class IcsEvent:
    """One VEVENT, checked at load time so that expansion cannot fail later."""

    file: str
    line: int | None
    uid: str
    name: str | None
    object: str | None
    room: str | None
    participants: tuple[str, ...] | None  # None: not given (an override inherits its series')
    kind: str | None
    start: Moment
    duration: dt.timedelta
    nominal: bool  # DATE events: durations in calendar days, not in seconds
    rrules: tuple[str, ...]  # RRULE bodies with UNTIL rewritten to the start's wall-clock frame
    rdates: tuple[tuple[Moment, Moment | None], ...]
    exdates: tuple[Moment, ...]
    recurrence_id: Moment | None
    cancelled: bool

    @property
    def source(self) -> str:
        where = f"{self.file}:{self.line}" if self.line is not None else self.file
        return f"{where} UID={self.uid}"


@dataclass(frozen=True)
class IcsOccurrence:
    """One occurrence of an event as aware instants, ready to be put on the sim clock."""

    uid: str
    name: str
    object: str
    room: str | None
    participants: tuple[str, ...]
    kind: str | None
    start: dt.datetime
    end: dt.datetime
    exact: bool  # the duration is in real seconds (False for all-day events)
    cancelled: bool
    source: str


def _key(moment: Moment) -> tuple[str, object]:
    """Identity of an instance start, comparable across zones (for EXDATE and RECURRENCE-ID)."""
    if not isinstance(moment, dt.datetime):
        return ("date", moment)
    if moment.tzinfo is None:
        return ("float", moment)
    return ("utc", moment.astimezone(UTC).replace(tzinfo=None))


def _naive(moment: Moment) -> dt.datetime:
    if isinstance(moment, dt.datetime):
        return moment.replace(tzinfo=None)
    return dt.datetime.combine(moment, dt.time(0, 0))


def _frame(event: IcsEvent, centre: dt.tzinfo) -> dt.tzinfo:
    """The zone whose wall clock the event's recurrences follow."""
    start = event.start
    if isinstance(start, dt.datetime) and start.tzinfo is not None:
        return start.tzinfo
    return centre  # floating and all-day events happen in the centre's local time


def _to_frame(moment: Moment, frame: dt.tzinfo) -> dt.datetime:
    if isinstance(moment, dt.datetime) and moment.tzinfo is not None:
        return moment.astimezone(frame).replace(tzinfo=None)
    return _naive(moment)


@dataclass(frozen=True)
class IcsAgenda:
    """A parsed .ics file: its events, and their expansion for one day of the centre."""

    source: str
    events: tuple[IcsEvent, ...]

    def occurrences(self, day: dt.date, centre: dt.tzinfo) -> list[IcsOccurrence]:
        """Every occurrence that overlaps ``day`` (local midnight to midnight in ``centre``)."""
        day_start = local_midnight(day, centre)
        day_end = local_midnight(day + dt.timedelta(days=1), centre)
        masters = {e.uid: e for e in self.events if e.recurrence_id is None}
        changes: dict[str, list[Moment]] = {}
        found: list[IcsOccurrence] = []
        for event in self.events:
            if event.recurrence_id is not None:
                changes.setdefault(event.uid, []).append(event.recurrence_id)
                frame = _frame(event, centre)
                own = _occurrence(_inherit(event, masters.get(event.uid)),
                                  _to_frame(event.start, frame), None, frame)
                if own.start < day_end and own.end > day_start:
                    found.append(own)
        for event in masters.values():
            frame = _frame(event, centre)
            skip_starts, skip_days = _excluded(event, changes.get(event.uid, []), frame)
            for naive_start, own_end in _instance_starts(event, frame, day_start, day_end):
                if naive_start in skip_starts or naive_start.date() in skip_days:
                    continue
                occurrence = _occurrence(event, naive_start, own_end, frame)
                if occurrence.start < day_end and occurrence.end > day_start:
                    found.append(occurrence)
        return found


def _excluded(event: IcsEvent, changed: list[Moment],
              frame: dt.tzinfo) -> tuple[set[dt.datetime], set[dt.date]]:
    """Instance starts (naive, in the series' frame) removed by EXDATE or replaced by an override.

    Compared as wall-clock times of the series' own zone, so an EXDATE written in UTC still
    removes the Madrid occurrence it names.  A DATE value removes that day's instances.
    """
    starts: set[dt.datetime] = set()
    days: set[dt.date] = set()
    for moment in (*event.exdates, *changed):
        if isinstance(moment, dt.datetime):
            starts.add(_to_frame(moment, frame))
        else:
            days.add(moment)
    return starts, days


def _instance_starts(event: IcsEvent, frame: dt.tzinfo, day_start: dt.datetime,
                     day_end: dt.datetime) -> list[tuple[dt.datetime, dt.datetime | None]]:
    """Naive wall-clock starts (in the event's frame) that may touch the day, with RDATE ends."""
    first = _naive(event.start)
    if not event.rrules and not event.rdates:
        return [(first, None)]
    own_ends: dict[dt.datetime, dt.datetime | None] = {}
    rules = rrule.rruleset()
    rules.rdate(first)
    for body in event.rrules:
        rules.rrule(rrule.rrulestr(body, dtstart=first))
    for rdate, rdate_end in event.rdates:
        start = _to_frame(rdate, frame)
        rules.rdate(start)
        if rdate_end is not None:
            own_ends[start] = _to_frame(rdate_end, frame)
    slack = max(event.duration, dt.timedelta(0)) + dt.timedelta(days=1)
    low = day_start.astimezone(frame).replace(tzinfo=None) - slack
    high = day_end.astimezone(frame).replace(tzinfo=None) + dt.timedelta(days=1)
    return [(start, own_ends.get(start)) for start in rules.between(low, high, inc=True)]


def _occurrence(event: IcsEvent, naive_start: dt.datetime, own_end: dt.datetime | None,
                frame: dt.tzinfo) -> IcsOccurrence:
    start = naive_start.replace(tzinfo=frame)
    if own_end is not None:  # an RDATE period brings its own end
        end, exact = own_end.replace(tzinfo=frame), True
    elif event.nominal:
        end, exact = (naive_start + event.duration).replace(tzinfo=frame), False
    else:  # exact duration: add real seconds, so a 1 h event across a DST change lasts 1 h
        end, exact = (start.astimezone(UTC) + event.duration).astimezone(frame), True
    assert event.object is not None  # guaranteed by parse_ics
    return IcsOccurrence(uid=event.uid, name=event.name or event.object, object=event.object,
                         room=event.room, participants=event.participants or (), kind=event.kind,
                         start=start, end=end, exact=exact, cancelled=event.cancelled,
                         source=event.source)


def _inherit(override: IcsEvent, master: IcsEvent | None) -> IcsEvent:
    """An override repeats only what changed; the rest comes from its series."""
    if master is None:
        return override
    return replace(override,
                   name=override.name or master.name,
                   object=override.object or master.object,
                   room=override.room or master.room,
                   participants=override.participants if override.participants is not None
                   else master.participants,
                   kind=override.kind or master.kind)


# ---------------------------------------------------------------------------------------------
# Parsing.
# ---------------------------------------------------------------------------------------------

_ESCAPE = re.compile(r"\\([\\;,nN])")


def _unescape(raw: str) -> str:
    """RFC 5545 TEXT unescaping; icalendar leaves X- properties raw."""
    return _ESCAPE.sub(lambda m: "\n" if m[1] in "nN" else m[1], raw)


def _text(value: Any) -> str | None:
    """Property value -> text; known TEXT properties arrive unescaped, X- ones raw."""
    if isinstance(value, list):
        value = value[0] if value else None
    if value is None:
        return None
    text = str(value) if isinstance(value, icalendar.vText) else _unescape(str(value))
    return text.strip() or None


def _split_list(value: Any) -> tuple[str, ...]:
    raw = value[0] if isinstance(value, list) else value
    names = (_unescape(part).strip() for part in _UNESCAPED_COMMA.split(str(raw)))
    return tuple(name for name in names if name)


def _participants(event: icalendar.Event) -> tuple[str, ...] | None:
    explicit = event.get("X-CHRONAV-PARTICIPANTS")
    if explicit is not None:
        return _split_list(explicit)
    attendees = event.get("ATTENDEE")
    if attendees is None:
        return None
    if not isinstance(attendees, list):
        attendees = [attendees]
    names = []
    for attendee in attendees:
        name = attendee.params.get("CN") or re.sub(r"(?i)^mailto:", "", str(attendee))
        if name.strip():
            names.append(name.strip())
    return tuple(names)


def _kind(event: icalendar.Event) -> str | None:
    explicit = _text(event.get("X-CHRONAV-KIND"))
    if explicit:
        return explicit
    categories = event.get("CATEGORIES")
    if categories is None:
        return None
    if not isinstance(categories, list):
        categories = [categories]
    for group in categories:
        for category in group.cats:
            if str(category).strip():
                return str(category).strip()
    return None


def _zoned(prop: Any, name: str, problems: list[str]) -> Moment | None:
    """A DATE/DATE-TIME property value; a TZID that resolved to nothing is an error, not floating."""
    value = prop.dt
    if isinstance(value, dt.datetime) and value.tzinfo is None and prop.params.get("TZID"):
        problems.append(f"{name}: unknown time zone {prop.params['TZID']!r}; use an IANA name such as "
                        "'Europe/Madrid' or include its VTIMEZONE block")
        return None
    return value


def _until_in_frame(body: icalendar.vRecur, start: Moment) -> str:
    """RRULE text whose UNTIL is naive wall-clock time of the start's frame (what dateutil needs)."""
    rule = icalendar.vRecur(body)
    untils = rule.get("UNTIL")
    if untils:
        until = untils[0]
        if not isinstance(until, dt.datetime):
            until = dt.datetime.combine(until, dt.time(23, 59, 59))  # a DATE UNTIL includes that day
        elif until.tzinfo is not None:
            frame = start.tzinfo if isinstance(start, dt.datetime) and start.tzinfo else UTC
            until = until.astimezone(frame)
        rule["UNTIL"] = [until.replace(tzinfo=None)]
    return rule.to_ical().decode()


def _show(moment: Moment) -> str:
    if isinstance(moment, dt.datetime):
        zone = f" {moment.tzinfo}" if moment.tzinfo is not None else ""
        return f"{moment:%Y-%m-%d %H:%M}{zone}"
    return moment.isoformat()


def _duration(event: icalendar.Event, start: Moment, problems: list[str]) -> dt.timedelta | None:
    dtend, length = event.get("DTEND"), event.get("DURATION")
    if dtend is not None:
        end = _zoned(dtend, "DTEND", problems)
        if end is None:
            return None
        if isinstance(start, dt.datetime) != isinstance(end, dt.datetime):
            problems.append("DTEND and DTSTART must both be dates or both date-times")
            return None
        if isinstance(start, dt.datetime) and isinstance(end, dt.datetime):
            if (start.tzinfo is None) != (end.tzinfo is None):
                problems.append("DTEND and DTSTART must both have a time zone or both be floating")
                return None
            if start.tzinfo is not None:
                return end.astimezone(UTC) - start.astimezone(UTC)
        return end - start  # type: ignore[operator]
    if length is not None:
        if not isinstance(length.dt, dt.timedelta):
            problems.append(f"DURATION: {length.to_ical().decode()!r} is not a duration such as PT1H30M")
            return None
        return length.dt
    if not isinstance(start, dt.datetime):
        return dt.timedelta(days=1)  # RFC 5545: an all-day event without an end lasts that day
    problems.append("no DTEND or DURATION: say when the activity ends")
    return None


_SINGLE_VALUED = ("DTSTART", "DTEND", "DURATION", "RECURRENCE-ID")


def _parse_event(event: icalendar.Event, file: str, line: int | None) -> tuple[IcsEvent | None, list[str]]:
    problems: list[str] = [f"{prop}: {message}" for prop, message in event.errors]
    # icalendar hands a repeated property over as a list; RFC 5545 allows these once per event.
    problems += [f"{name} appears {len(event[name])} times; an event has at most one"
                 for name in _SINGLE_VALUED if isinstance(event.get(name), list)]
    if problems:
        return None, problems
    start_prop = event.get("DTSTART")
    if start_prop is None:
        return None, ["no DTSTART: say when the activity starts"]
    start = _zoned(start_prop, "DTSTART", problems)
    recurrence_prop = event.get("RECURRENCE-ID")
    recurrence_id = None
    if recurrence_prop is not None:
        recurrence_id = _zoned(recurrence_prop, "RECURRENCE-ID", problems)
    if recurrence_prop is not None and str(recurrence_prop.params.get("RANGE", "")).upper() \
            == "THISANDFUTURE":
        problems.append("RECURRENCE-ID;RANGE=THISANDFUTURE is not supported: change the series itself "
                        "(or split it) instead")
    if start is None:
        return None, problems
    duration = _duration(event, start, problems)
    if duration is not None and duration <= dt.timedelta(0):
        problems.append(f"the end is not after the start ({_show(start)}); check DTEND or DURATION")
    rrules, rdates, exdates = [], [], []
    try:
        rrules = [_until_in_frame(body, start) for body in event.rrules]
        for body in rrules:
            rrule.rrulestr(body, dtstart=_naive(start))
        rdates = list(event.rdates)
        exdates = list(event.exdates)
    except (ValueError, TypeError, icalendar.error.BrokenCalendarProperty) as exc:
        problems.append(f"RRULE/RDATE/EXDATE: {exc}")
    object_name = _text(event.get("X-CHRONAV-OBJECT")) or _text(event.get("LOCATION"))
    if object_name is None and recurrence_id is None:
        problems.append("no object: set X-CHRONAV-OBJECT (or LOCATION) to the name of the object "
                        "the activity uses, e.g. X-CHRONAV-OBJECT:tv")
    if problems or duration is None:
        return None, problems
    uid = _text(event.get("UID")) or f"line-{line}"
    return IcsEvent(file=file, line=line, uid=uid, name=_text(event.get("SUMMARY")), object=object_name,
                    room=_text(event.get("X-CHRONAV-ROOM")), participants=_participants(event),
                    kind=_kind(event), start=start, duration=duration,
                    nominal=not isinstance(start, dt.datetime), rrules=tuple(rrules),
                    rdates=tuple(rdates), exdates=tuple(exdates), recurrence_id=recurrence_id,
                    cancelled=str(event.get("STATUS", "")).strip().upper() == "CANCELLED"), []


def _vevent_lines(text: str) -> list[int]:
    """1-based line of each ``BEGIN:VEVENT``, in file order (icalendar keeps no positions)."""
    return [number for number, line in enumerate(text.splitlines(), start=1)
            if line.strip().upper() == "BEGIN:VEVENT"]


def _check_series(events: Iterable[IcsEvent], problems: list[SourceError]) -> None:
    seen: dict[tuple[str, object], IcsEvent] = {}
    masters = {e.uid for e in events if e.recurrence_id is None}
    for event in events:
        key = (event.uid, None if event.recurrence_id is None else _key(event.recurrence_id))
        if key in seen:
            what = ("event" if event.recurrence_id is None
                    else f"change to the {event.recurrence_id} occurrence")
            problems.append(problem(event.file, event.line, f"UID={event.uid}: a second {what} with "
                                          f"this UID (first at line {seen[key].line}); give each event its "
                                          "own UID"))
        else:
            seen[key] = event
        if event.recurrence_id is not None and event.object is None and event.uid not in masters:
            problems.append(problem(event.file, event.line, f"UID={event.uid}: no object: set "
                                          "X-CHRONAV-OBJECT (or LOCATION)"))


def parse_ics(data: bytes | str, source: str) -> IcsAgenda:
    """Parse iCalendar text; every problem is reported at once, each with its line and UID."""
    if isinstance(data, bytes):
        try:
            data = data.decode("utf-8-sig")
        except UnicodeDecodeError as exc:
            raise AgendaSourceError([problem(source, None, f"not UTF-8 text (byte {exc.start}); "
                                                   "iCalendar files are UTF-8: export it again")]) from None
    text = data.removeprefix("\ufeff")  # a byte-order mark, as some Windows exports write
    try:
        calendars = icalendar.Calendar.from_ical(text, multiple=True)
    except ValueError as exc:
        raise AgendaSourceError([problem(source, None, f"not a valid iCalendar file: {exc}")]) from None
    except (AttributeError, TypeError, KeyError, IndexError) as exc:
        # icalendar's own crashes on malformed input (icalendar 7: a VTIMEZONE with two TZIDs is
        # an AttributeError); still a file to fix, never an agent to kill.
        raise AgendaSourceError([problem(source, None, "not a valid iCalendar file (the parser failed: "
                                               f"{type(exc).__name__}: {exc}); check VTIMEZONE and "
                                               "repeated properties")]) from None
    vevents = [event for calendar in calendars for event in calendar.walk("VEVENT")]
    if not calendars:
        raise AgendaSourceError([problem(source, None, "no complete VCALENDAR found: is this an .ics "
                                               "file, and does it end with END:VCALENDAR?")])
    lines = _vevent_lines(text)
    if len(lines) != len(vevents):
        lines = [None] * len(vevents)  # type: ignore[list-item]
    events: list[IcsEvent] = []
    problems: list[SourceError] = []
    for vevent, line in zip(vevents, lines, strict=True):
        parsed, messages = _parse_event(vevent, source, line)
        uid = _text(vevent.get("UID")) or f"line-{line}"
        problems.extend(problem(source, line, f"UID={uid}: {message}") for message in messages)
        if parsed is not None:
            events.append(parsed)
    _check_series(events, problems)
    if problems:
        raise AgendaSourceError(problems)
    return IcsAgenda(source=source, events=tuple(events))


def load_ics_file(path: str | Path) -> IcsAgenda:
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise AgendaSourceError([problem(str(path), None,
                                               f"cannot read file: {exc.strerror}")]) from None
    return parse_ics(data, str(path))
