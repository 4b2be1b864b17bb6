"""Runtime changes to a day's agenda, as pure functions: AgendaDay in, new AgendaDay out.

Why pure: the agenda agent applies a change only if the whole of it is valid, and it can do that
by computing the new day first and publishing it only on success; a refused change leaves the
old day untouched (never half-applied).  Every refusal is an ``AgendaChangeError`` whose message
tells the person at the terminal what to do.  The ``*Change`` models are the wire form (JSON)
of the same operations, as sent by `chronav agenda` and scripted in scenes (``op: add|cancel|move``).
"""

from __future__ import annotations

from collections.abc import Collection, Iterable
from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, TypeAdapter, ValidationError, field_validator

from agents.lib.agenda.expand import AgendaSource, assign_ids, drafts_for_day, resolve_spec, with_ids
from agents.lib.agenda.model import (SECONDS_PER_DAY, Activity, ActivitySpec, ActivityState, AgendaDay,
                                 AgendaError, AgendaSourceError, format_clock, parse_when,
                                 wall_seconds)
from agents.lib.agenda.validate import ValidationReport, summary, validate_activities
from agents.lib.agenda.yaml_source import parse_agenda_text
from scenes.yamlio import user_message

LoadMode = Literal["replace", "merge"]


class AgendaChangeError(AgendaError):
    """A change was refused as a whole; the message says why and what to do instead."""


def _refuse(report: ValidationReport) -> None:
    if report.errors:
        raise AgendaChangeError("refused: " + summary(report.errors))


def add_activity(day: AgendaDay, spec: ActivitySpec, *, known_objects: Collection[str] | None,
                 known_rooms: Collection[str] | None = None,
                 known_people: Collection[str] | None = None) -> AgendaDay:
    """The day plus one activity; its id is derived (``tv-1100``) unless the spec gives one."""
    if not spec.source:
        spec = spec.model_copy(update={"source": "added at run time"})
    draft = resolve_spec(spec, day.date, day.zone)
    if draft is None:
        raise AgendaChangeError(f"refused: {spec.name!r} ({spec.start} to {spec.end}) is not on "
                                f"today's agenda ({day.date.isoformat()}); give clock times such as "
                                "\"11:00\" or date-times on that date")
    if spec.id is not None and day.find(spec.id) is not None:
        raise AgendaChangeError(f"refused: id {spec.id!r} is already used by "
                                f"{day.get(spec.id).source}; choose another id or leave it out")
    (draft,) = assign_ids([draft], taken=day.ids())
    _refuse(validate_activities(with_ids([draft]), known_objects, known_rooms, known_people))
    return day.with_activities([*day.activities, draft.to_activity()])


def _existing(day: AgendaDay, activity_id: str) -> Activity:
    found = day.find(activity_id)
    if found is None:
        listed = ", ".join(day.ids()) or "none"
        raise AgendaChangeError(f"refused: no activity with id {activity_id!r} today; "
                                f"`chronav agenda list` shows them (ids: {listed})")
    return found


def cancel_activity(day: AgendaDay, activity_id: str) -> AgendaDay:
    """The day with this activity cancelled (kept, so the DSR and the recording show it)."""
    activity = _existing(day, activity_id)
    if activity.cancelled:
        raise AgendaChangeError(f"activity {activity_id!r} is already cancelled; nothing to do")
    cancelled = activity.model_copy(update={"state": ActivityState.CANCELLED})
    return day.with_activities(cancelled if a.id == activity_id else a for a in day.activities)


def _seconds(text: str, day: AgendaDay) -> float:
    value = parse_when(text)
    if isinstance(value, float):
        return value
    if value.tzinfo is None:
        value = value.replace(tzinfo=day.zone)
    return wall_seconds(value, day.date, day.zone)


def move_activity(day: AgendaDay, activity_id: str, *, start: str | None = None,
                  end: str | None = None) -> AgendaDay:
    """The day with this activity's times changed; its id stays the same.

    Only ``start``: the activity keeps its duration.  Only ``end``: it keeps its start.
    """
    activity = _existing(day, activity_id)
    if start is None and end is None:
        raise AgendaChangeError("refused: say the new start and/or end, e.g. --start 11:30 --end 12:30")
    if activity.cancelled:
        raise AgendaChangeError(f"refused: activity {activity_id!r} is cancelled; add a new one instead "
                                "of moving it")
    try:
        start_s = _seconds(start, day) if start is not None else activity.start_s
        if end is not None:
            end_s = _seconds(end, day)
        else:
            end_s = start_s + (activity.end_s - activity.start_s)
    except ValueError as exc:
        raise AgendaChangeError(f"refused: {exc}") from None
    if end_s <= start_s:
        raise AgendaChangeError(f"refused: moving {activity_id!r} to {format_clock(start_s)}-"
                                f"{format_clock(end_s)} would end before it starts")
    if not (start_s < SECONDS_PER_DAY and end_s > 0.0):
        raise AgendaChangeError(f"refused: {format_clock(start_s)}-{format_clock(end_s)} is not on "
                                f"{day.date.isoformat()}; to move an activity to another day, cancel "
                                "it and add it on that day")
    moved = activity.model_copy(update={"start_s": start_s, "end_s": end_s})
    return day.with_activities(moved if a.id == activity_id else a for a in day.activities)


def load_activities(day: AgendaDay, sources: Iterable[AgendaSource], *, mode: LoadMode,
                    known_objects: Collection[str] | None,
                    known_rooms: Collection[str] | None = None,
                    known_people: Collection[str] | None = None) -> AgendaDay:
    """Replace the day's agenda with the sources', or merge them in (same id -> replaced).

    Ids are derived from the loaded sources alone, so loading an edited file again updates its
    activities instead of duplicating them.  Any error refuses the whole load.
    """
    if mode not in ("replace", "merge"):
        raise AgendaChangeError(f"refused: load mode must be 'replace' or 'merge', not {mode!r}")
    drafts = assign_ids(drafts_for_day(sources, day.date, day.zone))
    _refuse(validate_activities(with_ids(drafts), known_objects, known_rooms, known_people))
    loaded = [d.to_activity() for d in drafts]
    if mode == "replace":
        return day.with_activities(loaded)
    new_ids = {a.id for a in loaded}
    return day.with_activities([*(a for a in day.activities if a.id not in new_ids), *loaded])


# ---------------------------------------------------------------------------------------------
# Wire form.
# ---------------------------------------------------------------------------------------------

class _Change(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")


class AddChange(_Change):
    op: Literal["add"] = "add"
    activity: ActivitySpec


class CancelChange(_Change):
    op: Literal["cancel"] = "cancel"
    id: str


class MoveChange(_Change):
    op: Literal["move"] = "move"
    id: str
    start: str | None = None
    end: str | None = None

    @field_validator("start", "end")
    @classmethod
    def _time(cls, value: str | None) -> str | None:
        if value is not None:
            parse_when(value)
        return value


class LoadChange(_Change):
    op: Literal["load"] = "load"
    mode: LoadMode
    format: Literal["ics", "yaml"]
    text: str = Field(description="the file's content")
    source: str = Field("loaded file", description="the file's name, used in messages")


AgendaChange = Annotated[AddChange | CancelChange | MoveChange | LoadChange, Field(discriminator="op")]
_CHANGE = TypeAdapter(AgendaChange)


def parse_change(data: str | bytes | dict[str, Any]) -> AddChange | CancelChange | MoveChange | LoadChange:
    """JSON (or a dict) -> a change model; malformed input is an AgendaChangeError, not a crash."""
    try:
        if isinstance(data, dict):
            return _CHANGE.validate_python(data)
        return _CHANGE.validate_json(data)
    except ValidationError as exc:
        parts = [".".join(str(p) for p in e["loc"] if not (isinstance(p, str) and "function-" in p))
                 for e in exc.errors()]
        details = "; ".join(f"{part or 'change'}: {user_message(e)}" for part, e in zip(parts, exc.errors(),
                                                                                    strict=True))
        raise AgendaChangeError(f"refused: malformed agenda change ({details})") from None


def apply_change(day: AgendaDay, change: AddChange | CancelChange | MoveChange | LoadChange, *,
                 known_objects: Collection[str] | None,
                 known_rooms: Collection[str] | None = None,
                 known_people: Collection[str] | None = None) -> AgendaDay:
    """Dispatch one change; the result is a new day, or AgendaChangeError and nothing changed."""
    try:
        return _apply(day, change, known_objects=known_objects, known_rooms=known_rooms, known_people=known_people)
    except AgendaChangeError:
        raise
    except AgendaSourceError as exc:  # found while expanding (a recurrence rule out of bounds)
        raise AgendaChangeError(f"refused: {exc}") from None
    except AgendaError as exc:
        raise AgendaChangeError(f"refused: {exc}") from None


def _apply(day: AgendaDay, change: AddChange | CancelChange | MoveChange | LoadChange, *,
           known_objects: Collection[str] | None, known_rooms: Collection[str] | None,
           known_people: Collection[str] | None) -> AgendaDay:
    if isinstance(change, AddChange):
        return add_activity(day, change.activity, known_objects=known_objects, known_rooms=known_rooms,
                            known_people=known_people)
    if isinstance(change, CancelChange):
        return cancel_activity(day, change.id)
    if isinstance(change, MoveChange):
        return move_activity(day, change.id, start=change.start, end=change.end)
    if isinstance(change, LoadChange):
        try:
            sources = parse_agenda_text(change.text, change.format, change.source)
        except AgendaSourceError as exc:
            raise AgendaChangeError(f"refused: {change.source} has errors:\n{exc}") from None
        return load_activities(day, sources, mode=change.mode, known_objects=known_objects,
                               known_rooms=known_rooms, known_people=known_people)
    raise AgendaChangeError(f"refused: unknown change {type(change).__name__}")
