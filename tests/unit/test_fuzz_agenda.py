"""Fuzzing agenda files (YAML and iCalendar) and the agenda changes staff send at run time.

Reading and expanding any file gives activities or an AgendaError that names the file (and the
line when there is one); applying any change to a running day gives a new day or an
AgendaChangeError (the agenda agent catches exactly that, so anything else would kill it)."""

from __future__ import annotations

import datetime as dt
import json
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from agents.lib.agenda import (AgendaChangeError, AgendaError, AgendaSourceError, apply_change, expand_day, parse_ics,
                           load_agenda_file, parse_agenda_text, parse_change)
from agents.world.scene_world import load_world
from scenes.loader import SCENES_DIR
from tests.support import REPO_ROOT
from tests.unit.fuzz_mutations import NASTY_VALUES, fuzz_settings, mutated_bytes, mutated_text, token_soup

ICS_FILES = sorted([SCENES_DIR / "sample_agenda.ics", *(REPO_ROOT / "tests" / "data").glob("*.ics")])
ICS_TEXTS = [p.read_text(encoding="utf-8") for p in ICS_FILES]
YAML_TEXT = """\
# a standalone agenda file
activities:
  - name: Serious game
    object: tv
    room: occupational_therapy
    start: 11:00
    end: "12:00"
    participants: [senior_1, therapist]
    kind: serious_game
  - id: therapy
    name: Table therapy
    object: round_table
    start: "2026-11-25T12:00"
    end: "2026-11-25T14:00+01:00"
  - name: Stretching
    object: stretcher
    start: "23:30"
    end: "24:00"
"""
SCENE = load_world("icra_usecase")
OBJECTS = {o.name for o in SCENE.scene.objects}
ROOMS = {r.name for r in SCENE.scene.rooms}
# The scene's day, and the two days the clocks change in the centre's zone.
DAYS = (SCENE.scene.clock.date, dt.date(2026, 3, 29), dt.date(2026, 10, 25))
ICS_WORDS = ("BEGIN:VCALENDAR", "END:VCALENDAR", "BEGIN:VEVENT", "END:VEVENT", "DTSTART:", "DTEND:", "RRULE:",
             "EXDATE:", "RECURRENCE-ID:", "DURATION:", "X-CHRONAV-OBJECT:", "TZID=", ";", "\r\n")


def read_and_expand(text: str, fmt: str, source: str, day: dt.date) -> None:
    try:
        expand_day(parse_agenda_text(text, fmt, source), day, SCENE.scene.clock.timezone, OBJECTS,
                   known_rooms=ROOMS)
    except AgendaSourceError as exc:
        assert all(problem.file == source for problem in exc.problems), exc
        assert all(problem.line is None or problem.line >= 1 for problem in exc.problems), exc
    except AgendaError as exc:
        assert source in str(exc), f"the error does not name {source}: {exc}"


def test_sources_expand() -> None:
    expand_day(parse_agenda_text(YAML_TEXT, "yaml", "a.yaml"), DAYS[0], "Europe/Madrid", OBJECTS, known_rooms=ROOMS)
    expand_day(parse_agenda_text(ICS_TEXTS[0], "ics", "a.ics"), DAYS[0], "Europe/Madrid", None)


@fuzz_settings(250)
@given(data=st.data())
def test_mutated_ics_files_give_agenda_errors(data: st.DataObject) -> None:
    text = data.draw(st.sampled_from(ICS_TEXTS), label="source")
    mutated = data.draw(st.one_of(mutated_text(text), token_soup(text, ICS_WORDS)), label="text")
    read_and_expand(mutated, "ics", "fuzz.ics", data.draw(st.sampled_from(DAYS), label="day"))


@fuzz_settings(200)
@given(data=st.data())
def test_mutated_yaml_agendas_give_agenda_errors(data: st.DataObject) -> None:
    mutated = data.draw(st.one_of(mutated_text(YAML_TEXT), token_soup(YAML_TEXT), st.text(max_size=80)), label="text")
    read_and_expand(mutated, "yaml", "fuzz.yaml", data.draw(st.sampled_from(DAYS), label="day"))


@pytest.fixture(scope="module")
def workdir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("fuzz_agenda")


@fuzz_settings(60)
@given(data=st.data())
def test_agenda_files_with_stray_bytes_give_agenda_errors(workdir: Path, data: st.DataObject) -> None:
    suffix, text = data.draw(st.sampled_from([(".ics", ICS_TEXTS[0]), (".yaml", YAML_TEXT)]), label="source")
    path = workdir / f"bytes{suffix}"
    path.write_bytes(data.draw(mutated_bytes(text), label="content"))
    try:
        expand_day(load_agenda_file(path), DAYS[0], "Europe/Madrid", OBJECTS, known_rooms=ROOMS)
    except AgendaSourceError as exc:
        assert all(problem.file == str(path) for problem in exc.problems), exc
    except AgendaError as exc:
        assert str(path) in str(exc), exc


CHANGES = [
    {"op": "add", "activity": {"id": "extra", "name": "Extra", "object": "tv", "start": "10:00", "end": "10:30",
                               "participants": ["senior_1"]}},
    {"op": "move", "id": "serious_game", "start": "11:30"},
    {"op": "move", "id": "table_therapy", "end": "2026-11-25T15:00"},
    {"op": "cancel", "id": "table_therapy"},
    {"op": "load", "mode": "merge", "format": "yaml", "text": YAML_TEXT, "source": "staff.yaml"},
    {"op": "load", "mode": "replace", "format": "ics", "text": ICS_TEXTS[0], "source": "staff.ics"},
]


@fuzz_settings(250)
@given(data=st.data())
def test_mutated_agenda_changes_are_refused_not_crashing(data: st.DataObject) -> None:
    """What `chronav agenda` (or anyone on the network) may put in an agenda_request."""
    change = dict(data.draw(st.sampled_from(CHANGES), label="change"))
    if change["op"] == "load":
        change["text"] = data.draw(mutated_text(change["text"]), label="file")
        text = json.dumps(change)
    else:
        text = data.draw(st.one_of(mutated_text(json.dumps(change)),
                                   st.sampled_from(NASTY_VALUES).map(lambda v, c=change: json.dumps({**c, "id": v}))),
                         label="json")
    try:
        apply_change(SCENE.agenda, parse_change(text), known_objects=OBJECTS, known_rooms=ROOMS)
    except AgendaChangeError as exc:
        assert str(exc).strip()


ONE_EVENT = ("BEGIN:VCALENDAR\nVERSION:2.0\nPRODID:x\nBEGIN:VEVENT\nUID:a\nDTSTART:20261125T100000\n{extra}"
             "X-CHRONAV-OBJECT:tv\nEND:VEVENT\nEND:VCALENDAR\n")


@pytest.mark.parametrize("extra,fragment", [
    ("DTEND:20261125T110000\nDTSTART:20261125T100000\n", "DTSTART appears 2 times"),   # was AttributeError
    ("DURATION:PT1H\nDURATION:PT2H\n", "DURATION appears 2 times"),                   # was AttributeError
    ("DURATION:20261125T110000\n", "is not a duration"),                               # was TypeError
])
def test_crashes_found_by_fuzzing_are_located_errors(extra: str, fragment: str) -> None:
    with pytest.raises(AgendaSourceError) as info:
        parse_ics(ONE_EVENT.format(extra=extra), "found.ics")
    (problem,) = info.value.problems
    assert problem.file == "found.ics" and problem.line == 4 and fragment in problem.message


def test_a_crash_inside_icalendar_is_an_agenda_error() -> None:
    """Found by fuzzing a `load` change: a VTIMEZONE with two TZIDs crashed icalendar itself."""
    text = ICS_TEXTS[0].replace("TZID:Europe/Madrid\n", "TZID:Europe/Madrid\nTZID:Europe/Paris\n", 1)
    assert text != ICS_TEXTS[0]
    with pytest.raises(AgendaSourceError, match="not a valid iCalendar file"):
        parse_ics(text, "two_tzids.ics")
    with pytest.raises(AgendaChangeError, match="two_tzids.ics"):
        apply_change(SCENE.agenda, parse_change(json.dumps({"op": "load", "mode": "merge", "format": "ics",
                                                                "text": text, "source": "two_tzids.ics"})),
                     known_objects=OBJECTS, known_rooms=ROOMS)
