"""Checks on a day's activities that need the world (which objects exist) or the whole day.

Why a report instead of raising at the first problem: staff fix a file in one go when they see
every problem at once.  Errors (unknown object or room, end not after start, duplicate id) stop
a load or a change; infos (overlaps on one object) do not: overlapping activities are allowed and
R(t) takes their maximum downstream, but staff usually want to know.
"""

from __future__ import annotations

import difflib
import enum
from collections.abc import Collection, Iterable
from dataclasses import dataclass
from typing import Protocol

from agents.lib.agenda.model import AgendaDay, AgendaError
from scenes.clock import format_clock
from scenes.limits import ACTIVITIES_PER_DAY
from scenes.names import check_name, shown


class ActivityLike(Protocol):
    """What validation reads; both resolved Activities and not-yet-built drafts provide it."""

    @property
    def id(self) -> str: ...
    @property
    def name(self) -> str: ...
    @property
    def object(self) -> str: ...
    @property
    def room(self) -> str | None: ...
    @property
    def start_s(self) -> float: ...
    @property
    def end_s(self) -> float: ...
    @property
    def source(self) -> str: ...
    @property
    def cancelled(self) -> bool: ...
    @property
    def participants(self) -> tuple[str, ...]: ...
    @property
    def kind(self) -> str | None: ...


class Severity(enum.StrEnum):
    ERROR = "error"
    INFO = "info"


@dataclass(frozen=True)
class Finding:
    """One observation about the agenda, naming the activity and where it was written."""

    severity: Severity
    code: str  # unknown_object | unknown_room | unknown_participant | bad_name | too_many |
    #            end_not_after_start | duplicate_id | overlap
    message: str
    activity_id: str
    source: str
    known: str = ""   # the names that exist, as the message ends with them: "(known objects: a, b)"

    def __str__(self) -> str:
        return f"{self.severity}: {self.message}"

    @property
    def short(self) -> str:
        """The message without the list of names that exist (``summary`` lists them once)."""
        return self.message.removesuffix(f" ({self.known})") if self.known else self.message


# How many names a summary lists before "... and N more".
SUMMARY_NAMES = 12


def summary(findings: Iterable[Finding]) -> str:
    """The findings one per line without their lists of known names, then each list once (cut at
    SUMMARY_NAMES names, with a count): loading a foreign agenda into a scene of 26 people used
    to give 3,000 characters that listed the 26 names five times."""
    findings = list(findings)
    if len(findings) == 1:
        return findings[0].message
    lines: list[str] = []
    known: dict[str, str] = {}
    by_activity: dict[str, list[str]] = {}     # "activity 'x' (name, file:line)" -> its problems
    for finding in findings:
        label, sep, problem = finding.short.partition(": ")
        if sep and label.startswith("activity "):
            problems = by_activity.setdefault(label, [])
            problem = problem.replace("; did you mean ", " (did you mean ").replace("?", "?)") \
                if "; did you mean " in problem else problem
            if problem not in problems:
                problems.append(problem)
        elif finding.short not in lines:
            lines.append(finding.short)
        if finding.known:
            what, _, names = finding.known.partition(": ")
            known.setdefault(what, names)
    lines += [f"{label}: {'; '.join(problems)}" for label, problems in by_activity.items()]
    for what, names in known.items():
        items = names.split(", ")
        rest = len(items) - SUMMARY_NAMES
        lines.append(f"{what}: {', '.join(items[:SUMMARY_NAMES])}" + (f" ... and {rest} more" if rest > 0 else ""))
    return "\n".join(lines)


@dataclass(frozen=True)
class ValidationReport:
    findings: tuple[Finding, ...] = ()

    @property
    def errors(self) -> tuple[Finding, ...]:
        return tuple(f for f in self.findings if f.severity is Severity.ERROR)

    @property
    def infos(self) -> tuple[Finding, ...]:
        return tuple(f for f in self.findings if f.severity is Severity.INFO)

    @property
    def ok(self) -> bool:
        return not self.errors

    def raise_if_errors(self) -> None:
        if self.errors:
            raise AgendaValidationError(self)

    def __str__(self) -> str:
        return "\n".join(str(f) for f in self.findings)


class AgendaValidationError(AgendaError):
    """The agenda has errors; ``report`` holds all of them (and the infos)."""

    def __init__(self, report: ValidationReport) -> None:
        self.report = report
        super().__init__("\n".join(f.message for f in report.errors))


def _label(activity: ActivityLike) -> str:
    return f"activity {shown(activity.id, 60)!r} ({shown(activity.name, 60)}, {shown(activity.source, 200)})"


def _known(kind: str, known: Collection[str]) -> str:
    """``known objects: a, b`` (what a Finding's ``known`` holds)."""
    return f"{kind}: {', '.join(sorted(known)) if known else 'none'}"


def _unknown(kind: str, value: str, known: Collection[str]) -> str:
    close = difflib.get_close_matches(value, list(known), n=1)
    hint = f"; did you mean {close[0]!r}?" if close else ""
    return f"no {kind} named {shown(value, 60)!r} in the centre{hint} ({_known(f'known {kind}s', known)})"


def _bad_names(item: ActivityLike) -> list[str]:
    """Names that are too long or hold control characters (they end up in terminals and the DSR)."""
    problems = []
    for label, value in (("id", item.id), ("name", item.name), ("object", item.object), ("room", item.room),
                         ("kind", item.kind), *(("participant", p) for p in item.participants)):
        if value is None:
            continue
        try:
            check_name(value)
        except ValueError as exc:
            problems.append(f"{label}: {exc}")
    return problems


def validate_activities(activities: Iterable[ActivityLike], known_objects: Collection[str] | None,
                        known_rooms: Collection[str] | None = None,
                        known_people: Collection[str] | None = None) -> ValidationReport:
    """Every error and info about these activities; ``None`` skips the object/room/people check."""
    items = list(activities)
    findings: list[Finding] = []
    limit = ACTIVITIES_PER_DAY.value()
    if len(items) > limit:
        first = items[0]
        return ValidationReport((Finding(Severity.ERROR, "too_many",
                                         f"{len(items):,} activities on one day; chronav handles at most {limit:,} "
                                         f"({ACTIVITIES_PER_DAY.env}); is a recurrence rule too frequent?",
                                         first.id, first.source),))
    seen: dict[str, ActivityLike] = {}
    for item in items:
        names = _bad_names(item)
        if names:
            findings.extend(Finding(Severity.ERROR, "bad_name", f"activity from {shown(item.source, 200)}: {text}",
                                    shown(item.id, 60), item.source) for text in names)
            continue
        if item.id in seen:
            findings.append(Finding(Severity.ERROR, "duplicate_id",
                                    f"{_label(item)}: id already used by {seen[item.id].source}; "
                                    "give each activity its own id", item.id, item.source))
        else:
            seen[item.id] = item
        if item.end_s <= item.start_s:
            findings.append(Finding(Severity.ERROR, "end_not_after_start",
                                    f"{_label(item)}: end {format_clock(item.end_s)} is not after "
                                    f"start {format_clock(item.start_s)}", item.id, item.source))
        if known_objects is not None and item.object not in known_objects:
            findings.append(Finding(Severity.ERROR, "unknown_object",
                                    f"{_label(item)}: {_unknown('object', item.object, known_objects)}",
                                    item.id, item.source, _known("known objects", known_objects)))
        if known_rooms is not None and item.room is not None and item.room not in known_rooms:
            findings.append(Finding(Severity.ERROR, "unknown_room",
                                    f"{_label(item)}: {_unknown('room', item.room, known_rooms)}",
                                    item.id, item.source, _known("known rooms", known_rooms)))
        if known_people is not None:
            for person in item.participants:
                if person not in known_people:
                    close = difflib.get_close_matches(person, list(known_people), n=1)
                    hint = f"; did you mean {close[0]!r}?" if close else ""
                    people = _known("people", known_people)
                    findings.append(Finding(Severity.ERROR, "unknown_participant",
                                            f"{_label(item)}: participant {shown(person, 60)!r} is not a person of "
                                            f"the scene{hint} ({people})", item.id, item.source, people))
    findings.extend(_overlaps(items))
    return ValidationReport(tuple(findings))


def _overlaps(items: list[ActivityLike]) -> list[Finding]:
    """Pairs of live activities sharing an object and some time (sweep per object)."""
    by_object: dict[str, list[ActivityLike]] = {}
    for item in items:
        if not item.cancelled and item.end_s > item.start_s:
            by_object.setdefault(item.object, []).append(item)
    findings: list[Finding] = []
    for object_name, group in sorted(by_object.items()):
        group.sort(key=lambda a: (a.start_s, a.end_s, a.id))
        for index, first in enumerate(group):
            for second in group[index + 1:]:
                if second.start_s >= first.end_s:
                    break
                lo, hi = second.start_s, min(first.end_s, second.end_s)
                findings.append(Finding(
                    Severity.INFO, "overlap",
                    f"activities {shown(first.id, 60)!r} ({shown(first.source)}) and {shown(second.id, 60)!r} "
                    f"({shown(second.source)}) "
                    f"overlap on object {object_name!r} from {format_clock(lo)} to {format_clock(hi)}; "
                    "allowed, the object's R(t) takes the larger value", second.id, second.source))
    return findings


def validate_day(day: AgendaDay, known_objects: Collection[str] | None,
                 known_rooms: Collection[str] | None = None,
                 known_people: Collection[str] | None = None) -> ValidationReport:
    """Report on a built day (its ids and intervals are already valid; objects and overlaps may not be)."""
    return validate_activities(day.activities, known_objects, known_rooms, known_people)
