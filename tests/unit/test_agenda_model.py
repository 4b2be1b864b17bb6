"""Agenda data model: spec validation, activity states, day lookups."""

from __future__ import annotations

import datetime as dt

import pytest
from hypothesis import given
from hypothesis import strategies as st
from pydantic import ValidationError

from agents.lib.agenda import (Activity, ActivitySpec, ActivityState, AgendaDay, UnknownActivityError,
                               activity_state)
from scenes.clock import format_clock, parse_clock
from agents.lib.agenda.model import AgendaError, load_zone, parse_when, wall_seconds

H = 3600.0


def _activity(activity_id: str = "tv-1100", start: float = 11 * H, end: float = 12 * H,
              obj: str = "tv", state: ActivityState = ActivityState.SCHEDULED) -> Activity:
    return Activity(id=activity_id, name="Serious game", object=obj, start_s=start, end_s=end,
                    state=state, source="test")


def test_clock_times_parse_and_format() -> None:
    assert parse_clock("11:00") == 11 * H
    assert parse_clock("9:05:30") == 9 * H + 5 * 60 + 30
    assert parse_clock("24:00") == 24 * H
    for bad in ("24:01", "11:60", "11", "eleven", "25:00"):
        with pytest.raises(ValueError):
            parse_clock(bad)
    assert format_clock(11 * H) == "11:00:00"
    assert format_clock(11 * H + 30) == "11:00:30"
    assert format_clock(-H) == "-01:00:00"


def test_parse_when_distinguishes_clock_and_iso() -> None:
    assert parse_when("11:00") == 11 * H
    assert parse_when("2026-11-25T11:00") == dt.datetime(2026, 11, 25, 11, 0)
    assert parse_when("2026-11-25T10:00Z").tzinfo is not None  # type: ignore[union-attr]
    with pytest.raises(ValueError, match="without a time of day"):
        parse_when("2026-11-25")
    with pytest.raises(ValueError, match="HH:MM"):
        parse_when("noon")


def test_spec_rejects_end_before_start_naming_end() -> None:
    with pytest.raises(ValidationError) as info:
        ActivitySpec(name="x", object="tv", start="12:00", end="11:00")
    (error,) = info.value.errors()
    assert error["loc"] == ("end",)
    assert "not after start" in error["msg"]
    with pytest.raises(ValidationError):
        ActivitySpec(name="x", object="tv", start="2026-11-25T12:00", end="2026-11-25T12:00")


def test_spec_refuses_sexagesimal_numbers_and_accepts_python_times() -> None:
    with pytest.raises(ValidationError, match="quotes"):
        ActivitySpec(name="x", object="tv", start=660, end="12:00")  # type: ignore[arg-type]
    spec = ActivitySpec(name="x", object="tv", start=dt.time(11, 0), end=dt.datetime(2026, 11, 25, 12))  # type: ignore[arg-type]
    assert spec.start == "11:00:00" and spec.end == "2026-11-25T12:00:00"


def test_spec_participants_must_be_a_list_and_ids_have_no_spaces() -> None:
    with pytest.raises(ValidationError, match="list"):
        ActivitySpec(name="x", object="tv", start="11:00", end="12:00", participants="ana, luis")  # type: ignore[arg-type]
    with pytest.raises(ValidationError):
        ActivitySpec(id="my game", name="x", object="tv", start="11:00", end="12:00")
    with pytest.raises(ValidationError):
        ActivitySpec(name="x", object="tv", start="11:00", end="12:00", colour="red")  # type: ignore[call-arg]


def test_activity_state_through_the_day() -> None:
    game = _activity()
    window = 45 * 60.0
    assert activity_state(game, 9 * H, window) is ActivityState.SCHEDULED
    assert activity_state(game, 11 * H - window, window) is ActivityState.UPCOMING
    assert activity_state(game, 10.5 * H, window) is ActivityState.UPCOMING
    assert activity_state(game, 11 * H, window) is ActivityState.RUNNING
    assert activity_state(game, 12 * H - 1, window) is ActivityState.RUNNING
    assert activity_state(game, 12 * H, window) is ActivityState.FINISHED
    cancelled = _activity(state=ActivityState.CANCELLED)
    assert activity_state(cancelled, 11.5 * H, window) is ActivityState.CANCELLED
    with pytest.raises(ValueError):
        activity_state(game, 0.0, -1.0)


_ORDER = [ActivityState.SCHEDULED, ActivityState.UPCOMING, ActivityState.RUNNING, ActivityState.FINISHED]


@given(start=st.floats(0, 80000), length=st.floats(1, 20000), window=st.floats(0, 7200),
       t1=st.floats(-1000, 110000), t2=st.floats(-1000, 110000))
def test_activity_state_never_goes_back_in_time(start: float, length: float, window: float,
                                                t1: float, t2: float) -> None:
    activity = _activity(start=start, end=start + length)
    early, late = sorted((t1, t2))
    assert _ORDER.index(activity_state(activity, early, window)) <= _ORDER.index(
        activity_state(activity, late, window))


def test_activity_requires_end_after_start() -> None:
    with pytest.raises(ValidationError, match="not after"):
        _activity(start=12 * H, end=12 * H)


def test_agenda_day_sorts_looks_up_and_rejects_duplicates() -> None:
    late = _activity("table", 12 * H, 14 * H, obj="round_table")
    early = _activity("game", 11 * H, 12 * H)
    day = AgendaDay(date=dt.date(2026, 11, 25), tz="Europe/Madrid", activities=(late, early))
    assert day.ids() == ["game", "table"]
    assert day.get("table") is late
    assert day.find("nope") is None
    with pytest.raises(UnknownActivityError, match="ids: game, table"):
        day.get("nope")
    assert day.objects() == {"tv", "round_table"}
    assert day.on_object("tv") == (early,)
    assert [(w.object, w.start_s, w.end_s, w.cancelled) for w in day.windows()] == [
        ("tv", 11 * H, 12 * H, False), ("round_table", 12 * H, 14 * H, False)]
    with pytest.raises(ValidationError, match="duplicate activity id 'game'"):
        AgendaDay(date=dt.date(2026, 11, 25), tz="UTC", activities=(early, early))
    with pytest.raises(ValidationError, match="unknown time zone"):
        AgendaDay(date=dt.date(2026, 11, 25), tz="Mars/Olympus")


def test_agenda_day_at_refreshes_states_without_touching_cancelled() -> None:
    day = AgendaDay(date=dt.date(2026, 11, 25), tz="UTC", activities=(
        _activity("game"), _activity("gone", 12 * H, 13 * H, state=ActivityState.CANCELLED)))
    later = day.at(11.5 * H, 1800.0)
    assert later.get("game").state is ActivityState.RUNNING
    assert later.get("gone").state is ActivityState.CANCELLED
    assert day.get("game").state is ActivityState.SCHEDULED  # the original is untouched
    assert day.windows()[1].cancelled


def test_wall_seconds_counts_local_clock_even_on_dst_days() -> None:
    madrid = load_zone("Europe/Madrid")
    spring = dt.date(2025, 3, 30)
    ten_local = dt.datetime(2025, 3, 30, 8, 0, tzinfo=dt.UTC)  # 10:00 CEST
    assert wall_seconds(ten_local, spring, madrid) == 10 * H
    next_day = dt.datetime(2025, 3, 31, 0, 30, tzinfo=madrid)
    assert wall_seconds(next_day, spring, madrid) == 24.5 * H
    day = AgendaDay(date=spring, tz="Europe/Madrid")
    assert day.seconds_of(ten_local) == 10 * H
    with pytest.raises(AgendaError, match="IANA"):
        load_zone("Nowhere/Zone")
