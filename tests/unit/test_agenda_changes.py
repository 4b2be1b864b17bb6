"""Runtime agenda changes: pure, all-or-nothing, refusals a person can act on."""

from __future__ import annotations

import datetime as dt
import json
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from agents.lib.agenda import (ActivitySpec, ActivityState, AgendaChangeError, AgendaDay, AddChange,
                           CancelChange, LoadChange, MoveChange, add_activity, apply_change,
                           cancel_activity, expand_day, load_activities, load_ics_file, move_activity,
                           parse_change)

DATA = Path(__file__).resolve().parents[1] / "data"
OBJECTS = {"tv", "round_table"}
H = 3600.0


@pytest.fixture
def day() -> AgendaDay:
    specs = [ActivitySpec(id="serious_game", name="Serious game", object="tv", start="11:00", end="12:00",
                          source="scene.yaml:76"),
             ActivitySpec(id="table_therapy", name="Table therapy", object="round_table", start="12:00",
                          end="14:00", source="scene.yaml:77")]
    return expand_day(specs, dt.date(2025, 3, 30), "Europe/Madrid", OBJECTS)


def test_add_derives_an_id_and_leaves_the_original_alone(day: AgendaDay) -> None:
    spec = ActivitySpec(name="Extra therapy", object="round_table", start="10:04", end="10:40",
                        participants=["senior_2"])  # type: ignore[arg-type]
    new = add_activity(day, spec, known_objects=OBJECTS)
    added = new.get("round_table-1004")
    assert (added.start_s, added.end_s, added.participants) == (10 * H + 240, 10 * H + 2400, ("senior_2",))
    assert added.source == "added at run time"
    assert len(day.activities) == 2 and len(new.activities) == 3
    again = add_activity(new, spec, known_objects=OBJECTS)
    assert "round_table-1004-2" in again.ids()


def test_add_on_an_unknown_object_is_refused_whole(day: AgendaDay) -> None:
    spec = ActivitySpec(name="Bingo", object="sofa", start="10:00", end="11:00")
    with pytest.raises(AgendaChangeError) as info:
        add_activity(day, spec, known_objects=OBJECTS)
    assert str(info.value) == ("refused: activity 'sofa-1000' (Bingo, added at run time): no object named "
                               "'sofa' in the centre (known objects: round_table, tv)")


def test_add_refuses_a_taken_id_and_another_date(day: AgendaDay) -> None:
    taken = ActivitySpec(id="serious_game", name="x", object="tv", start="15:00", end="16:00")
    with pytest.raises(AgendaChangeError, match="id 'serious_game' is already used by scene.yaml:76"):
        add_activity(day, taken, known_objects=OBJECTS)
    tomorrow = ActivitySpec(name="x", object="tv", start="2025-03-31T15:00", end="2025-03-31T16:00")
    with pytest.raises(AgendaChangeError, match=r"not on today's agenda \(2025-03-30\)"):
        add_activity(day, tomorrow, known_objects=OBJECTS)


def test_cancel(day: AgendaDay) -> None:
    new = cancel_activity(day, "serious_game")
    assert new.get("serious_game").state is ActivityState.CANCELLED
    assert new.windows()[0].cancelled
    assert day.get("serious_game").state is ActivityState.SCHEDULED
    with pytest.raises(AgendaChangeError, match="already cancelled"):
        cancel_activity(new, "serious_game")
    with pytest.raises(AgendaChangeError, match=r"no activity with id 'bingo' today; `chronav agenda list` "
                                                r"shows them \(ids: serious_game, table_therapy\)"):
        cancel_activity(day, "bingo")


def test_move_keeps_id_and_duration(day: AgendaDay) -> None:
    moved = move_activity(day, "serious_game", start="11:30")
    game = moved.get("serious_game")
    assert (game.start_s, game.end_s) == (11.5 * H, 12.5 * H)
    both = move_activity(day, "serious_game", start="09:00", end="09:45")
    assert (both.get("serious_game").start_s, both.get("serious_game").end_s) == (9 * H, 9.75 * H)
    longer = move_activity(day, "table_therapy", end="15:00")
    assert longer.get("table_therapy").start_s == 12 * H
    utc = move_activity(day, "serious_game", start="2025-03-30T08:00Z", end="2025-03-30T09:00Z")
    assert utc.get("serious_game").start_s == 10 * H  # CEST


def test_move_refusals(day: AgendaDay) -> None:
    with pytest.raises(AgendaChangeError, match="would end before it starts"):
        move_activity(day, "serious_game", end="10:00")
    with pytest.raises(AgendaChangeError, match="say the new start and/or end"):
        move_activity(day, "serious_game")
    with pytest.raises(AgendaChangeError, match="cancel it and add it on that day"):
        move_activity(day, "serious_game", start="2025-03-31T11:00", end="2025-03-31T12:00")
    with pytest.raises(AgendaChangeError, match="is cancelled; add a new one"):
        move_activity(cancel_activity(day, "serious_game"), "serious_game", start="13:00")
    with pytest.raises(AgendaChangeError, match="not a time"):
        move_activity(day, "serious_game", start="later")


def test_load_replace_and_merge(day: AgendaDay) -> None:
    therapy = load_ics_file(DATA / "agenda_daily_therapy.ics")
    replaced = load_activities(day, [therapy], mode="replace", known_objects=OBJECTS)
    assert replaced.ids() == ["round_table-1000"]
    merged = load_activities(day, [therapy], mode="merge", known_objects=OBJECTS)
    assert merged.ids() == ["round_table-1000", "serious_game", "table_therapy"]
    # Loading the same source again updates its activities instead of duplicating them.
    assert load_activities(merged, [therapy], mode="merge", known_objects=OBJECTS) == merged


def test_load_with_one_bad_activity_is_refused_whole(day: AgendaDay) -> None:
    good = ActivitySpec(name="Good", object="tv", start="15:00", end="16:00", source="new.yaml:2")
    bad = ActivitySpec(name="Bad", object="piano", start="16:00", end="17:00", source="new.yaml:6")
    with pytest.raises(AgendaChangeError, match=r"'piano-1600' \(Bad, new.yaml:6\): no object named 'piano'"):
        load_activities(day, [good, bad], mode="merge", known_objects=OBJECTS)
    with pytest.raises(AgendaChangeError, match="'replace' or 'merge'"):
        load_activities(day, [good], mode="append", known_objects=OBJECTS)  # type: ignore[arg-type]


def test_wire_changes_round_trip_through_json(day: AgendaDay) -> None:
    add = parse_change(json.dumps({"op": "add", "activity": {"name": "Extra", "object": "tv",
                                                              "start": "15:00", "end": "16:00"}}))
    assert isinstance(add, AddChange)
    assert apply_change(day, add, known_objects=OBJECTS).find("tv-1500") is not None
    cancel = parse_change(CancelChange(id="serious_game").model_dump_json())
    assert apply_change(day, cancel, known_objects=OBJECTS).get("serious_game").cancelled
    move = parse_change({"op": "move", "id": "table_therapy", "start": "12:30"})
    assert isinstance(move, MoveChange)
    assert apply_change(day, move, known_objects=OBJECTS).get("table_therapy").end_s == 14.5 * H
    text = (DATA / "agenda_daily_therapy.ics").read_text()
    load = LoadChange(mode="replace", format="ics", text=text, source="week.ics")
    assert apply_change(day, parse_change(load.model_dump_json()), known_objects=OBJECTS).ids() == [
        "round_table-1000"]


def test_malformed_wire_changes_are_refused_not_crashes(day: AgendaDay) -> None:
    with pytest.raises(AgendaChangeError, match="malformed agenda change"):
        parse_change('{"op": "explode"}')
    with pytest.raises(AgendaChangeError, match="malformed agenda change"):
        parse_change("not json")
    with pytest.raises(AgendaChangeError, match=r"activity.end"):
        parse_change({"op": "add", "activity": {"name": "x", "object": "tv", "start": "12:00", "end": "11:00"}})
    bad_file = (DATA / "agenda_bad.ics").read_text()
    with pytest.raises(AgendaChangeError, match=r"bad.ics has errors:\nbad.ics:4: UID=no-object"):
        apply_change(day, LoadChange(mode="merge", format="ics", text=bad_file, source="bad.ics"),
                     known_objects=OBJECTS)


@given(start=st.integers(0, 23 * 60 - 1), length=st.integers(1, 60))
def test_move_then_read_back(start: int, length: int) -> None:
    base = expand_day([ActivitySpec(id="g", name="g", object="tv", start="11:00", end="12:00")],
                      dt.date(2026, 11, 25), "UTC", OBJECTS)
    text = f"{start // 60:02d}:{start % 60:02d}"
    end = start + length
    end_text = f"{end // 60:02d}:{end % 60:02d}"
    moved = move_activity(base, "g", start=text, end=end_text).get("g")
    assert (moved.start_s, moved.end_s) == (start * 60.0, end * 60.0)


def test_loading_a_foreign_agenda_refuses_in_one_short_message() -> None:
    """Issue 39: the sample .ics into center_day gave 3,000 characters listing its 26 people five
    times; each list of names now comes once, cut with a count, and each activity's problems on one line."""
    from agents.lib.agenda.changes import parse_change
    from agents.world.scene_world import load_world
    from tests.support import REPO_ROOT
    from tools.agenda import load_change

    world = load_world(REPO_ROOT / "scenes" / "center_day.yaml")
    change = load_change(Path(REPO_ROOT / "scenes" / "sample_agenda.ics"), replace=False)
    with pytest.raises(AgendaChangeError) as refused:
        apply_change(world.agenda, parse_change(json.dumps(change)), known_objects=world.object_names,
                     known_rooms=world.room_names, known_people=world.person_names)
    text = str(refused.value)
    assert text.count("res_ana") == 1 and text.count("known rooms:") == 1 and "... and 14 more" in text
    assert len(text) < 1200 and len(text.splitlines()) == 5, text
    assert "participant 'therapist' is not a person of the scene (did you mean 'therapist_eva'?)" in text
