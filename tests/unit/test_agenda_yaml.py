"""YAML agendas: standalone files, a scene's agenda, and errors that name file, line and key."""

from __future__ import annotations

import datetime as dt
from pathlib import Path

import pytest

from agents.lib.agenda import (ActivitySpec, AgendaSourceError, IcsAgenda, expand_day, load_agenda_file,
                           load_scene_agenda, parse_yaml_agenda)

DATA = Path(__file__).resolve().parents[1] / "data"
SCENES = Path(__file__).resolve().parents[2] / "scenes"
H = 3600.0

GOOD = """\
# the centre's Wednesday
activities:
  - name: Serious game
    object: tv
    room: occupational_therapy
    start: 11:00            # unquoted on purpose: must stay "11:00", not the YAML 1.1 number 660
    end: "12:00"
    participants: [senior_1, therapist]
    kind: serious_game
  - id: therapy
    name: Table therapy
    object: round_table
    start: "2026-11-25T12:00"
    end: "2026-11-25T14:00"
  - name: Tomorrow only
    object: tv
    start: "2026-11-26T11:00"
    end: "2026-11-26T12:00"
"""


def _problems(text: str) -> list[tuple[int | None, str, str]]:
    with pytest.raises(AgendaSourceError) as info:
        parse_yaml_agenda(text, "agenda.yaml")
    assert all(p.file == "agenda.yaml" for p in info.value.problems)
    return [(p.line, p.key, p.message) for p in info.value.problems]


def test_standalone_file_parses_with_sources() -> None:
    specs = parse_yaml_agenda(GOOD, "agenda.yaml")
    assert [s.source for s in specs] == ["agenda.yaml:3", "agenda.yaml:10", "agenda.yaml:15"]
    game = specs[0]
    assert game == ActivitySpec(name="Serious game", object="tv", room="occupational_therapy",
                                start="11:00", end="12:00", participants=("senior_1", "therapist"),
                                kind="serious_game", source="agenda.yaml:3")


def test_expansion_uses_clock_times_every_day_and_iso_times_on_their_date() -> None:
    specs = parse_yaml_agenda(GOOD, "agenda.yaml")
    wednesday = expand_day(specs, dt.date(2026, 11, 25), "Europe/Madrid", {"tv", "round_table"})
    assert [(a.id, a.start_s, a.end_s) for a in wednesday.activities] == [
        ("tv-1100", 11 * H, 12 * H), ("therapy", 12 * H, 14 * H)]
    thursday = expand_day(specs, dt.date(2026, 11, 26), "Europe/Madrid", {"tv", "round_table"})
    assert [(a.id, a.name) for a in thursday.activities] == [("tv-1100", "Serious game"),
                                                            ("tv-1100-2", "Tomorrow only")]
    again = expand_day(specs, dt.date(2026, 11, 26), "Europe/Madrid", {"tv", "round_table"})
    assert again == thursday  # derived ids are deterministic


def test_iso_time_with_offset_is_converted_to_the_centres_zone() -> None:
    specs = parse_yaml_agenda('activities:\n  - {name: g, object: tv, start: "2026-11-25T10:00Z", '
                              'end: "2026-11-25T11:00+00:00"}\n', "a.yaml")
    (activity,) = expand_day(specs, dt.date(2026, 11, 25), "Europe/Madrid", {"tv"}).activities
    assert (activity.start_s, activity.end_s) == (11 * H, 12 * H)  # CET = UTC+1


def test_errors_name_line_and_key_and_all_are_reported() -> None:
    text = """\
activities:
  - name: Serious game
    object: tv
    start: "25:00"
    end: "12:00"
  - name: Table therapy
    objet: round_table
    start: "12:00"
    end: "14:00"
  - name: Backwards
    object: tv
    start: "12:00"
    end: "11:00"
  - object: tv
    start: "12:00"
    end: "13:00"
    participants: [ana, [luis]]
  - just a string
"""
    problems = _problems(text)
    assert (4, "activities[0].start", "'25:00' is not a valid clock time (00:00 to 24:00)") in problems
    assert any(line == 7 and key == "activities[1].objet" and "did you mean 'object'?" in msg
               for line, key, msg in problems)
    assert (13, "activities[2].end", "end '11:00' is not after start '12:00'") in problems
    assert (17, "activities[3].participants[1]", "expected a plain value, not a list or a mapping") in problems
    assert any(line == 18 and key == "activities[4]" and "must be a mapping" in msg
               for line, key, msg in problems)


def test_missing_key_points_at_the_activity() -> None:
    problems = _problems('activities:\n  - name: x\n    start: "11:00"\n    end: "12:00"\n')
    assert problems == [(2, "activities[0].object", "required key is missing")]


def test_duplicate_key_and_wrong_shapes() -> None:
    ((line, key, message),) = _problems('activities:\n  - {name: a, object: tv, start: "11:00", start: "11:30", '
                                        'end: "12:00"}\n')
    assert (line, key) == (2, "activities[0].start")
    assert message.startswith("duplicate key 'start' (first on line 2, column 27)")
    assert _problems("activities: {name: a}\n")[0][:2] == (1, "activities")
    assert _problems("- {name: a}\n")[0][0] == 1
    assert _problems("activites: []\n") == [(1, "activites", "unknown top-level key 'activites' (did you mean "
                                                                "'activities'?); an agenda file has only 'activities:'")]


def test_yaml_syntax_error_has_its_line() -> None:
    problems = _problems('activities:\n  - name: a\n    object: tv\n     start: "11:00"\n')
    assert problems[0][0] == 4 and problems[0][2].startswith("YAML syntax error")


def test_participants_list_item_error_points_at_the_item() -> None:
    problems = _problems('activities:\n  - name: a\n    object: tv\n    start: "11:00"\n    end: "12:00"\n'
                         '    participants:\n      - ana\n      - ""\n')
    assert problems[0][:2] == (8, "activities[0].participants[1]")


def test_empty_file_is_an_empty_agenda() -> None:
    assert parse_yaml_agenda("", "empty.yaml") == []
    assert parse_yaml_agenda("activities:\n", "empty.yaml") == []


def test_scene_agenda_and_agenda_file(tmp_path: Path) -> None:
    specs = load_scene_agenda(SCENES / "icra_usecase.yaml")
    assert [(s.id, s.object, s.start, s.end) for s in specs] == [
        ("serious_game", "tv", "11:00", "12:00"), ("table_therapy", "round_table", "12:00", "14:00")]
    serious_game_line = next(i for i, line in enumerate((SCENES / "icra_usecase.yaml").read_text().splitlines(), 1)
                             if "id: serious_game" in line)
    assert specs[0].source.endswith(f"icra_usecase.yaml:{serious_game_line}")
    scene = tmp_path / "scene.yaml"
    (tmp_path / "agendas").mkdir()
    (tmp_path / "agendas" / "week.ics").write_bytes((DATA / "agenda_daily_therapy.ics").read_bytes())
    scene.write_text('name: s\nagenda:\n  - {name: g, object: tv, start: "11:00", end: "12:00"}\n'
                     "agenda_file: agendas/week.ics\n")
    sources = load_scene_agenda(scene)
    assert isinstance(sources[0], ActivitySpec) and isinstance(sources[1], IcsAgenda)
    scene.write_text("name: s\nagenda_file: missing.ics\n")
    with pytest.raises(AgendaSourceError, match=r"scene.yaml:2:1: agenda_file: agenda file 'missing.ics' not found"):
        load_scene_agenda(scene)
    scene.write_text('name: s\nagenda:\n  - {name: g, object: tv, start: "11:00", end: "10:00"}\n')
    with pytest.raises(AgendaSourceError, match=r"scene.yaml:3:\d+: agenda\[0\].end: end '10:00' is not after"):
        load_scene_agenda(scene)


def test_load_agenda_file_dispatches_by_suffix(tmp_path: Path) -> None:
    path = tmp_path / "a.yml"
    path.write_text(GOOD)
    assert len(load_agenda_file(path)) == 3
    with pytest.raises(AgendaSourceError, match="unknown agenda format"):
        load_agenda_file(tmp_path / "a.csv")
    with pytest.raises(AgendaSourceError, match="no such file"):
        load_agenda_file(tmp_path / "missing.yaml")
