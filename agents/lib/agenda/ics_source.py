"""Agenda activities from iCalendar (.ics) files, the format staff calendars already export.

Why ``icalendar`` plus ``recurring-ical-events``: icalendar resolves time zones (IANA TZIDs,
Windows names and the file's own VTIMEZONE blocks); recurring-ical-events expands RRULE, RDATE,
EXDATE and RECURRENCE-ID overrides over a time span, in the *wall-clock time of the event's own
zone*, so a daily 10:00 therapy in Europe/Madrid stays at 10:00 across a DST change.  We expand
only around the simulated day, and first bound the work a rule needs to get there
(``RECURRENCE_STEPS``, docs/limits.md): ``FREQ=SECONDLY`` without COUNT or UNTIL would otherwise
walk millions of steps and hang `scene check` or the live agenda agent.  What we add: each
event is checked at load time with its line (so expansion cannot fail later), an override
inherits what it does not repeat from its series, and durations are real seconds (a one-hour
event across the spring-forward gap ends at 03:30).

Conventions (docs/agenda.md):
- object: ``X-CHRONAV-OBJECT``, else ``LOCATION`` (the object's name in the scene);
- room: ``X-CHRONAV-ROOM``; kind: ``X-CHRONAV-KIND``, else the first ``CATEGORIES``;
- participants: ``X-CHRONAV-PARTICIPANTS`` (comma-separated), else each ``ATTENDEE``'s CN;
- name: ``SUMMARY`` (else the object's name); ``STATUS:CANCELLED`` -> a cancelled activity;
- floating times and all-day (DATE) events are in the centre's time zone.

icalendar, recurring-ical-events and dateutil are imported by the functions that parse or expand
a calendar (about 0.1 s): every scene loads this module through the agenda package, and most have
no .ics, so `chronav path` on them should not pay for it.
"""

from __future__ import annotations

import datetime as dt
import re
from collections.abc import Iterable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

from agents.lib.agenda.model import AgendaSourceError, local_midnight, problem
from scenes.limits import ICS_BYTES, RECURRENCE_DATES, RECURRENCE_STEPS
from scenes.files import read_bounded
from scenes.yamlio import SourceError

if TYPE_CHECKING:
    import icalendar

UTC = dt.UTC
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
    """A parsed .ics file: its events (checked, for messages and metadata), the calendars as read
    (what recurring-ical-events expands), and the expansion for one day of the centre."""

    source: str
    events: tuple[IcsEvent, ...]
    calendars: tuple[icalendar.Calendar, ...] = field(default=(), compare=False, repr=False)

    def occurrences(self, day: dt.date, centre: dt.tzinfo) -> list[IcsOccurrence]:
        """Every occurrence that overlaps ``day`` (local midnight to midnight in ``centre``).

        Only around the day is expanded (the longest event's length before it, for events that
        run into the day), with recurring-ical-events; a rule that would need more than
        RECURRENCE_STEPS steps to get there is refused first (AgendaSourceError at its line)."""
        if not dt.date(1, 1, 3) <= day <= dt.date.max - dt.timedelta(days=3):   # the expansion reaches a day further
            raise AgendaSourceError([problem(self.source, None, f"the simulated day {day.isoformat()} is outside "
                                             "the years a calendar can be expanded in")])
        day_start = local_midnight(day, centre)
        day_end = local_midnight(day + dt.timedelta(days=1), centre)
        longest = max([dt.timedelta(0), *(e.duration for e in self.events),
                       *(end - start for e in self.events for start, end in _rdate_periods(e))])
        low, high = day_start - longest - dt.timedelta(days=1), day_end + dt.timedelta(days=1)
        _check_steps(self.events, high, day)
        masters = {e.uid: e for e in self.events if e.recurrence_id is None}
        overrides = {(e.uid, _key(e.recurrence_id)): e for e in self.events if e.recurrence_id is not None}
        found: list[IcsOccurrence] = []
        # Each event's RDATE periods once, not once per occurrence (50,000 RDATEs took 274 s).
        periods: dict[tuple[str, dt.tzinfo], dict[dt.datetime, dt.datetime]] = {}
        for component in _expand(self.calendars, low, high, self.source):
                uid = _text(component.get("UID")) or ""
                rid = component.get("RECURRENCE-ID")
                override = overrides.get((uid, _key(rid.dt))) if rid is not None else None
                event = _inherit(override, masters.get(uid)) if override is not None else masters.get(uid)
                if event is None:  # an override whose series is not in the file
                    event = next((e for e in self.events if e.uid == uid), None)
                if event is None:
                    continue
                frame = _frame(event, centre)
                # DTSTART is a DATE or DATE-TIME (RFC 5545 3.8.2.4); icalendar types every property kind at once
                naive_start = _to_frame(component["DTSTART"].dt, frame)  # type: ignore[union-attr,arg-type]
                if override is None and (event.uid, frame) not in periods:
                    periods[(event.uid, frame)] = dict(_rdate_periods(event, frame))
                own_end = None if override is not None else periods[(event.uid, frame)].get(naive_start)
                occurrence = _occurrence(event, naive_start, own_end, frame)
                if occurrence.start < day_end and occurrence.end > day_start:
                    found.append(occurrence)
        return found


def _expand(calendars: Iterable[icalendar.Calendar], low: dt.datetime, high: dt.datetime,
            source: str) -> list[icalendar.Event]:
    """The VEVENT occurrences between ``low`` and ``high``, by recurring-ical-events."""
    import recurring_ical_events

    found: list[icalendar.Event] = []
    for calendar in calendars:
        try:
            found.extend(recurring_ical_events.of(calendar, components=["VEVENT"]).between(low, high))
        except Exception as exc:  # noqa: BLE001 - a file the library cannot expand is a file to fix
            raise AgendaSourceError([problem(source, None, "cannot expand the recurrences (recurring-ical-"
                                             f"events: {type(exc).__name__}: {str(exc)[:200]}); check RRULE, "
                                             "RDATE, EXDATE and RECURRENCE-ID")]) from None
    return found


def _rdate_periods(event: IcsEvent, frame: dt.tzinfo | None = None) -> list[tuple[dt.datetime, dt.datetime]]:
    """RDATE periods (start, end) of an event, naive in ``frame``: such an occurrence brings its own end."""
    periods = []
    for start, end in event.rdates:
        if end is not None:
            periods.append((_naive(start), _naive(end)) if frame is None
                           else (_to_frame(start, frame), _to_frame(end, frame)))
    return periods


_FREQ_SECONDS = {"SECONDLY": 1, "MINUTELY": 60, "HOURLY": 3600, "DAILY": 86400, "WEEKLY": 7 * 86400,
                 "MONTHLY": 28 * 86400, "YEARLY": 365 * 86400}
# BY* parts that multiply the occurrences of each period, for the frequencies coarser than theirs.
_EXPANDS = {"BYSECOND": 1, "BYMINUTE": 60, "BYHOUR": 3600, "BYDAY": 86400, "BYMONTHDAY": 86400,
            "BYYEARDAY": 86400, "BYWEEKNO": 7 * 86400, "BYMONTH": 28 * 86400}


def recurrence_steps(rule: icalendar.vRecur, start: Moment, horizon: dt.datetime) -> float:
    """An upper estimate of the steps a recurrence iterator takes from ``start`` to ``horizon``.

    Iterators (dateutil's, under recurring-ical-events) walk every period from DTSTART, so a
    ``FREQ=SECONDLY`` rule started a month before the simulated day takes millions of steps even
    if only a few of them fall on that day."""
    freq = str((rule.get("FREQ") or ["DAILY"])[0]).upper()
    unit = _FREQ_SECONDS.get(freq, 86400)
    interval = max(1, int((rule.get("INTERVAL") or [1])[0]))
    first = start if isinstance(start, dt.datetime) else dt.datetime.combine(start, dt.time(0, 0))
    first = first if first.tzinfo is not None else first.replace(tzinfo=horizon.tzinfo)
    untils = rule.get("UNTIL")
    if untils:
        until = untils[0]
        until = until if isinstance(until, dt.datetime) else dt.datetime.combine(until, dt.time(23, 59, 59))
        until = until if until.tzinfo is not None else until.replace(tzinfo=first.tzinfo)
        horizon = min(horizon, until)
    span = max(0.0, (horizon - first).total_seconds())
    steps = span / (unit * interval) + 1
    for part, part_unit in _EXPANDS.items():
        values = rule.get(part)
        if values and part_unit < unit:
            steps *= len(values) * (5 if part == "BYDAY" and freq == "MONTHLY" else
                                    53 if part == "BYDAY" and freq == "YEARLY" else 1)
    counts = rule.get("COUNT")
    if counts and not any(rule.get(part) for part in (*_EXPANDS, "BYSETPOS")):
        steps = min(steps, float(counts[0]))
    return steps


# BY* parts that choose days and mean the same in a YEARLY rule as in any finer one (BYDAY only
# without an ordinal such as 2MO, whose meaning depends on the frequency).
_DAY_PARTS = {"BYMONTH": "bymonth", "BYMONTHDAY": "bymonthday", "BYYEARDAY": "byyearday", "BYWEEKNO": "byweekno"}
_WEEKDAYS = ("MO", "TU", "WE", "TH", "FR", "SA", "SU")


def _rule_problems(rule: icalendar.vRecur) -> list[str]:
    """What makes a rule impossible to iterate in bounded time: INTERVAL=0 (the iterator never
    moves: 1.2 GB and still running after 180 s) and day parts that name no existing date
    (``BYMONTH=2;BYMONTHDAY=30``: the iterator walks day after day to the year 9999 looking for one)."""
    out = []
    for part in ("INTERVAL", "COUNT"):
        values = rule.get(part)
        if values and not (isinstance(values[0], int) and values[0] >= 1):
            out.append(f"RRULE {part}={values[0]}: must be a whole number of at least 1")
    if out or not any(rule.get(part) for part in _DAY_PARTS):
        return out
    if _never_occurs(rule):
        parts = ";".join(f"{part}={','.join(str(v) for v in rule[part])}" for part in _DAY_PARTS if rule.get(part))
        out.append(f"RRULE {parts} names no date that exists (the series would never occur); check the "
                   "month and day numbers")
    return out


def _never_occurs(rule: icalendar.vRecur) -> bool:
    """True when no day of any year satisfies the rule's day parts.

    Why this probe is bounded: the Gregorian calendar repeats every 400 years (weekdays included),
    so a yearly rule with the same day parts, started in 9599, either finds a day or stops at the
    year 9999 after 400 yearly steps (a few milliseconds), however the original rule is written."""
    from dateutil import rrule

    kwargs: dict[str, Any] = {name: [int(v) for v in rule[part]] for part, name in _DAY_PARTS.items() if rule.get(part)}
    weekdays = [str(v).upper() for v in rule.get("BYDAY") or []]
    if weekdays and all(day in _WEEKDAYS for day in weekdays):   # ordinals (2MO, -1FR) left out: a wider probe
        kwargs["byweekday"] = [_WEEKDAYS.index(day) for day in weekdays]
    try:
        probe = rrule.rrule(rrule.YEARLY, dtstart=dt.datetime(9599, 1, 1), **kwargs)
        return probe.after(dt.datetime(9599, 1, 1), inc=True) is None
    except (ValueError, TypeError, OverflowError):
        return False   # dateutil refuses the parts: rrulestr above reports that


def _check_steps(events: Iterable[IcsEvent], horizon: dt.datetime, day: dt.date) -> None:
    import icalendar

    limit = RECURRENCE_STEPS.value()
    problems = []
    for event in events:
        for body in event.rrules:
            rule = icalendar.vRecur.from_ical(body)
            steps = recurrence_steps(rule, event.start, horizon)
            if steps > limit:
                freq = str((rule.get("FREQ") or ["?"])[0]).upper()
                problems.append(problem(event.file, event.line, (
                    f"UID={event.uid}: RRULE:FREQ={freq} from {_show(event.start)} takes about {steps:,.0f} "
                    f"steps to reach the simulated day {day.isoformat()}; chronav follows at most {limit:,} "
                    f"({RECURRENCE_STEPS.env}): add COUNT or UNTIL, use a coarser FREQ, or start the series "
                    "closer to the simulated day")))
    if problems:
        raise AgendaSourceError(problems)


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
    import icalendar

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
    import icalendar

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


def _date_until_includes_its_day(vevent: icalendar.Event, start: Moment) -> None:
    """``UNTIL=20250402`` on a series of timed events means "up to and including the 2nd" (what
    calendar apps show); RFC 5545 wants a date-time there, so write it as one before expanding."""
    import icalendar

    rules = vevent.get("RRULE")
    if rules is None or not isinstance(start, dt.datetime):
        return
    fixed = []
    for rule in rules if isinstance(rules, list) else [rules]:
        untils = rule.get("UNTIL")
        if untils and not isinstance(untils[0], dt.datetime):
            rule = icalendar.vRecur(rule)
            end_of_day = dt.datetime.combine(untils[0], dt.time(23, 59, 59))
            rule["UNTIL"] = [end_of_day.replace(tzinfo=start.tzinfo).astimezone(UTC) if start.tzinfo else end_of_day]
        fixed.append(rule)
    vevent.pop("RRULE")
    for rule in fixed:
        vevent.add("RRULE", rule)


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
        return end - start
    if length is not None:
        if not isinstance(length.dt, dt.timedelta):
            problems.append(f"DURATION: {length.to_ical().decode()!r} is not a duration such as PT1H30M")
            return None
        return length.dt
    if not isinstance(start, dt.datetime):
        return dt.timedelta(days=1)  # RFC 5545: an all-day event without an end lasts that day
    problems.append("no DTEND or DURATION: say when the activity ends")
    return None


_SINGLE_VALUED = ("UID", "DTSTART", "DTEND", "DURATION", "RECURRENCE-ID", "STATUS")


def _parse_event(event: icalendar.Event, file: str, line: int | None) -> tuple[IcsEvent | None, list[str]]:
    import icalendar
    from dateutil import rrule

    problems: list[str] = [f"{prop}: {message}" for prop, message in event.errors]
    # icalendar hands a repeated property over as a list; RFC 5545 allows these once per event.
    problems += [f"{name} appears {len(repeated)} times; an event has at most one"
                 for name in _SINGLE_VALUED if isinstance(repeated := event.get(name), list)]
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
            problems.extend(_rule_problems(icalendar.vRecur.from_ical(body)))
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
    import icalendar

    if isinstance(data, bytes):
        try:
            data = data.decode("utf-8-sig")
        except UnicodeDecodeError as exc:
            raise AgendaSourceError([problem(source, None, f"not UTF-8 text (byte {exc.start}); "
                                                   "iCalendar files are UTF-8: export it again")]) from None
    text = data.removeprefix("\ufeff")  # a byte-order mark, as some Windows exports write
    if len(text) > ICS_BYTES.value():  # also received as text, by `chronav agenda load`
        raise AgendaSourceError([problem(source, None, f"{len(text):,} characters; an .ics file may have at most "
                                         f"{ICS_BYTES.value():,} ({ICS_BYTES.env})")])
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
    # walk("VEVENT") yields icalendar.Event objects (its component factory); typed as Component
    vevents = cast("list[icalendar.Event]", [event for calendar in calendars for event in calendar.walk("VEVENT")])
    if not calendars:
        raise AgendaSourceError([problem(source, None, "no complete VCALENDAR found: is this an .ics "
                                               "file, and does it end with END:VCALENDAR?")])
    lines: list[int | None] = list(_vevent_lines(text))
    if len(lines) != len(vevents):
        lines = [None] * len(vevents)
    events: list[IcsEvent] = []
    problems: list[SourceError] = []
    for vevent, line in zip(vevents, lines, strict=True):
        parsed, messages = _parse_event(vevent, source, line)
        uid = _text(vevent.get("UID")) or f"line-{line}"
        problems.extend(problem(source, line, f"UID={uid}: {message}") for message in messages)
        if parsed is not None:
            events.append(parsed)
            _date_until_includes_its_day(vevent, parsed.start)
    _check_series(events, problems)
    dates = sum(len(e.rdates) + len(e.exdates) for e in events)
    if dates > RECURRENCE_DATES.value():   # each RDATE becomes a copy of its event when expanded
        most = max(events, key=lambda e: len(e.rdates) + len(e.exdates))
        problems.append(problem(source, most.line, f"UID={most.uid}: the file lists {dates:,} RDATE/EXDATE dates; "
                                f"chronav reads at most {RECURRENCE_DATES.value():,} ({RECURRENCE_DATES.env}): "
                                "use an RRULE for a regular series"))
    if problems:
        raise AgendaSourceError(problems)
    return IcsAgenda(source=source, events=tuple(events), calendars=tuple(calendars))


def load_ics_file(path: str | Path) -> IcsAgenda:
    path = Path(path)
    try:
        data = read_bounded(path, max_bytes=ICS_BYTES.value(), limit_env=ICS_BYTES.env, what=".ics file")
    except SourceError as exc:
        raise AgendaSourceError([exc]) from None
    return parse_ics(data, str(path))
