"""Agenda validation: unknown objects/rooms and bad intervals are errors, overlaps are infos."""

from __future__ import annotations

import datetime as dt

import pytest

from agents.lib.agenda import (ActivitySpec, AgendaValidationError, Severity, expand_day,
                           validate_activities, validate_day)
from agents.lib.agenda.expand import Draft

H = 3600.0
DAY = dt.date(2026, 11, 25)


def _spec(name: str, obj: str, start: str, end: str, **extra: object) -> ActivitySpec:
    return ActivitySpec(name=name, object=obj, start=start, end=end,
                        source=f"agenda.yaml:{len(name)}", **extra)  # type: ignore[arg-type]


def _draft(activity_id: str, obj: str, start: float, end: float, cancelled: bool = False) -> Draft:
    return Draft(id=activity_id, name=activity_id, object=obj, room=None, start_s=start, end_s=end,
                 participants=(), kind=None, source=f"src-{activity_id}", cancelled=cancelled)


def test_unknown_object_is_an_error_naming_activity_source_and_known_objects() -> None:
    with pytest.raises(AgendaValidationError) as info:
        expand_day([_spec("Bingo", "sofa", "11:00", "12:00")], DAY, "Europe/Madrid", {"tv", "round_table"})
    (error,) = info.value.report.errors
    assert error.code == "unknown_object" and error.activity_id == "sofa-1100"
    assert error.source == "agenda.yaml:5"
    assert error.message == ("activity 'sofa-1100' (Bingo, agenda.yaml:5): no object named 'sofa' in the "
                             "centre (known objects: round_table, tv)")


def test_none_skips_the_object_check_but_not_the_others() -> None:
    day = expand_day([_spec("Bingo", "sofa", "11:00", "12:00")], DAY, "UTC", None)
    assert day.activities[0].object == "sofa"
    report = validate_day(day, {"tv"})
    assert [f.code for f in report.errors] == ["unknown_object"]


def test_unknown_room_when_rooms_are_given() -> None:
    spec = _spec("Game", "tv", "11:00", "12:00", room="gym")
    assert expand_day([spec], DAY, "UTC", {"tv"}).activities[0].room == "gym"
    with pytest.raises(AgendaValidationError, match="no room named 'gym'"):
        expand_day([spec], DAY, "UTC", {"tv"}, known_rooms={"occupational_therapy"})


def test_end_not_after_start_from_mixed_times_is_reported() -> None:
    # "HH:MM" against an ISO date-time cannot be compared by the spec alone.
    spec = _spec("Odd", "tv", "2026-11-25T12:00", "11:00")
    with pytest.raises(AgendaValidationError) as info:
        expand_day([spec], DAY, "Europe/Madrid", {"tv"})
    (error,) = info.value.report.errors
    assert error.code == "end_not_after_start"
    assert "end 11:00:00 is not after start 12:00:00" in error.message


def test_every_error_is_collected_in_one_report() -> None:
    specs = [_spec("A", "sofa", "11:00", "12:00"), _spec("Bee", "tv", "11:00", "12:00", id="x"),
             _spec("Cee", "tv", "13:00", "14:00", id="x")]
    with pytest.raises(AgendaValidationError) as info:
        expand_day(specs, DAY, "UTC", {"tv"})
    codes = sorted(f.code for f in info.value.report.errors)
    assert codes == ["duplicate_id", "unknown_object"]
    assert "agenda.yaml:3" in str(info.value)  # the duplicate names both sources


def test_overlaps_on_one_object_are_infos_not_errors() -> None:
    drafts = [_draft("a", "tv", 10 * H, 12 * H), _draft("b", "tv", 11 * H, 13 * H),
              _draft("c", "tv", 11.5 * H, 11.75 * H), _draft("d", "tv", 13 * H, 14 * H),
              _draft("e", "round_table", 10 * H, 12 * H), _draft("f", "tv", 9 * H, 15 * H, cancelled=True)]
    report = validate_activities(drafts, {"tv", "round_table"})
    assert report.ok
    pairs = sorted((f.message.split("'")[1], f.activity_id) for f in report.infos)
    # a-b, a-c, b-c overlap; b-d only touch; e is another object; f is cancelled.
    assert pairs == [("a", "b"), ("a", "c"), ("b", "c")]
    assert all(f.severity is Severity.INFO for f in report.infos)
    first = next(f for f in report.infos if f.activity_id == "b")
    assert "from 11:00:00 to 12:00:00" in first.message and "R(t) takes the larger value" in first.message


def test_expand_day_accepts_overlaps() -> None:
    day = expand_day([_spec("A", "tv", "11:00", "12:00"), _spec("Bb", "tv", "11:30", "12:30")],
                     DAY, "UTC", {"tv"})
    assert len(day.activities) == 2
    assert len(validate_day(day, {"tv"}).infos) == 1
