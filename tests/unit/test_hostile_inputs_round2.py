"""Hostile input, round two (issue 31): each input kind found to give a traceback, a hang or a
silent acceptance now gets a clear error naming the file, line and key (or the option), a non-zero
exit and no traceback, through the command a user types.

Inputs live under tests/data/hostile/; the ones that are huge or special (a 200,000-character CSV
cell, 50,000 RDATEs, include chains, a 40-room clique world, ``/dev/zero``, FIFOs) are made by the
test in its temporary folder.  ``python -m tests.unit.test_hostile_inputs_round2`` prints the
table of the issue's note (input -> exit code -> first line of the message).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from tests.support import REPO_ROOT
from tools.cli import app

HOSTILE = Path(__file__).resolve().parents[1] / "data" / "hostile"
AGGL = REPO_ROOT / "tests" / "data" / "aggl"
runner = CliRunner()


def _h(name: str) -> str:
    return str(HOSTILE / name)


def run(args: list[str], env: dict[str, str] | None = None) -> tuple[int, str, str]:
    """Exit code, first line of stderr (else stdout), and all output, as the user sees them."""
    result = runner.invoke(app, args, env={"CHRONAV_ZENOH_CONNECT": "tcp/127.0.0.1:1", "COLUMNS": "200",
                                           **(env or {})})
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise result.exception
    text = result.stderr or result.stdout
    return result.exit_code, (text.splitlines() or [""])[0], result.stdout + result.stderr


def check(args: list[str], code: int, expected: str, env: dict[str, str] | None = None,
          max_chars: int = 2_000) -> str:
    """Run ``args``; the exit code, the message's first line and a short, traceback-free output."""
    exit_code, first, output = run(args, env)
    assert exit_code == code, output[:2000]
    assert expected in first, output[:2000]
    assert "Traceback" not in output and "Error:" not in first.split(":")[0], output[:2000]
    assert len(output) < max_chars, f"{len(output):,} characters of output: an input is echoed whole"
    return output


FROM_MAP = ["scene", "from-map"]
PATH_ARGS = ["--at", "10:00", "--from", "1,1", "--to", "4,1"]

# (command line, expected exit code, text the first line of the output must contain)
CASES: list[tuple[list[str], int, str]] = [
    # Tracebacks before.
    (["scene", "check", _h("resolution_5e-324.yaml")], 1, "resolution: must be at least 0.001, got 5e-324"),
    (["path", _h("resolution_5e-324.yaml"), *PATH_ARGS], 2, "resolution: must be at least 0.001"),
    (["scene", "check", _h("date_9999.yaml")], 1, "clock.date: the simulated day 9999-12-31 is outside 1900-2999"),
    (["scene", "check", "/dev/zero"], 1, "/dev/zero: is a device, not a YAML file"),
    (["grammar", "check", "/dev/zero"], 1, "/dev/zero: is a device, not a grammar file"),
    (["chaos", _h("bom.yaml"), "--schedule", "/dev/zero"], 2, "/dev/zero: is a device, not a JSON schedule"),
    ([*FROM_MAP, _h("map_pgm_60000.yaml"), "--out", "{tmp}/s.yaml"], 2,
     "map_bomb_header.pgm: the image has more than"),
    ([*FROM_MAP, _h("map_resolution_1e-200.yaml"), "--out", "{tmp}/s.yaml"], 2,
     "resolution: must be at least 0.001, got 1e-200"),
    ([*FROM_MAP, _h("map_resolution_1e300.yaml"), "--out", "{tmp}/s.yaml"], 2, "resolution: must be at most 10.0"),
    ([*FROM_MAP, _h("map_origin_1e308.yaml"), "--out", "{tmp}/s.yaml"], 2,
     "origin: origin [1e+308, 1e+308] is more than 100,000 m"),
    ([*FROM_MAP, _h("map_ok.yaml"), "--out", "{tmp}/s.yaml", "--min-room-area", "1e307"], 1,
     "no free area of at least 1e+307 m2 on the map"),
    (["evaluate", _h("bom.yaml"), "--seeds", "1000000000000", "--out", "{tmp}/study"], 2,
     "--seeds 1,000,000,000,000: give 1 to 10,000"),
    (["chaos", _h("bom.yaml"), "--faults", "1000000000"], 2, "a chaos run injects at most 1,000 faults"),
    # Hangs before.
    (["scene", "check", _h("agenda_interval_0.yaml")], 1, "RRULE INTERVAL=0: must be a whole number of at least 1"),
    (["scene", "check", _h("agenda_never_true.yaml")], 1, "RRULE BYMONTH=2;BYMONTHDAY=30 names no date that exists"),
    # Accepted silently before.
    (["scene", "check", _h("people_nfc_nfd.yaml")], 1, "people[1].name: duplicate person name 'jos\u00e9'"),
    (["scene", "check", _h("people_same_spot.yaml")], 1, "people[1].pose: person 'bob' at (3, 3) stands on person 'ana'"),
    (["scene", "check", _h("robot_on_person.yaml")], 1, "robot.pose: robot at (1, 1) starts on person 'ana'"),
    (["path", _h("robot_on_person.yaml"), *PATH_ARGS], 2, "starts on person 'ana'"),
    (["scene", "check", _h("clock_rate_1e-300.yaml")], 1, "clock.rate: must be at least 0.01, got 1e-300"),
    # Slow, then failing its own output's limits, before.
    ([*FROM_MAP, _h("map_png_5000.yaml"), "--out", "{tmp}/s.yaml"], 2,
     "the image is 5,000 x 5,000 pixels; chronav reads maps of 1 to 16,000,000 pixels"),
]


def _id(case: tuple[list[str], int, str]) -> str:
    args = case[0]
    shown = [Path(a).name if a.startswith(str(HOSTILE)) else a[:14] for a in args if not a.startswith("{tmp}")]
    return " ".join(shown)[:70]


@pytest.mark.parametrize("case", CASES, ids=[_id(c) for c in CASES])
def test_hostile_input_gets_a_clear_error(case: tuple[list[str], int, str], tmp_path: Path) -> None:
    args, code, expected = case
    check([a.replace("{tmp}", str(tmp_path)) for a in args], code, expected)


def test_a_limit_variable_that_is_not_a_plain_number_is_named() -> None:
    check(["scene", "check", _h("bom.yaml")], 1, "CHRONAV_LIMIT_YAML_BYTES='\u00b2': expected a positive whole number",
          env={"CHRONAV_LIMIT_YAML_BYTES": "\u00b2"})


def test_a_200000_character_csv_cell_is_a_located_error(tmp_path: Path) -> None:
    csv = tmp_path / "traj.csv"
    csv.write_text("t,x,y,theta\n36000,1,1,0\n36001," + "x" * 200_000 + ",1,0\n", encoding="utf-8")
    check(["metrics", _h("bom.yaml"), str(csv)], 2, f"{csv}:3: a cell of more than 131,072 characters")


RARE_BUT_REAL = ("FREQ=YEARLY;BYMONTH=2;BYMONTHDAY=29", "FREQ=MONTHLY;BYDAY=FR;BYMONTHDAY=13",
                 "FREQ=YEARLY;BYWEEKNO=53;BYDAY=MO", "FREQ=MONTHLY;BYMONTHDAY=-1", "FREQ=YEARLY;BYYEARDAY=366",
                 "FREQ=MONTHLY;BYDAY=2MO;BYMONTH=2", "FREQ=DAILY;BYMONTH=2,4;BYMONTHDAY=30",
                 "FREQ=MINUTELY;BYMONTH=2;BYMONTHDAY=29;BYDAY=MO", "FREQ=DAILY;COUNT=3")
NEVER = ("FREQ=DAILY;BYMONTH=4;BYMONTHDAY=31", "FREQ=MINUTELY;BYMONTH=2;BYMONTHDAY=30,31",
         "FREQ=MONTHLY;BYMONTH=2;BYMONTHDAY=-30", "FREQ=YEARLY;BYMONTH=1;BYYEARDAY=100", "FREQ=DAILY;INTERVAL=0",
         "FREQ=DAILY;COUNT=0")


@pytest.mark.parametrize("rule", RARE_BUT_REAL + NEVER)
def test_only_rules_that_can_never_occur_are_refused(rule: str) -> None:
    """The yearly probe refuses what names no date, and nothing rare but real (Feb 29 on a Monday)."""
    import icalendar

    from agents.lib.agenda.ics_source import _rule_problems

    problems = _rule_problems(icalendar.vRecur.from_ical(rule))
    assert bool(problems) == (rule in NEVER), problems


def test_50000_rdates_are_refused_before_they_are_expanded(tmp_path: Path) -> None:
    dates = ",".join(f"20261125T{9 + i // 3600:02d}{i // 60 % 60:02d}{i % 60:02d}" for i in range(50_000))
    (tmp_path / "many.ics").write_text(
        "BEGIN:VCALENDAR\nVERSION:2.0\nPRODID:-//hostile//EN\nBEGIN:VEVENT\nUID:many@hostile\n"
        "DTSTART;TZID=Europe/Madrid:20261125T090000\nDURATION:PT1S\n"
        f"RDATE;TZID=Europe/Madrid:{dates}\nX-CHRONAV-OBJECT:tv\nSUMMARY:x\nEND:VEVENT\nEND:VCALENDAR\n")
    scene = tmp_path / "scene.yaml"
    scene.write_text((HOSTILE / "bom.yaml").read_text(encoding="utf-8-sig") + "agenda_file: many.ics\n")
    check(["scene", "check", str(scene)], 1, "many.ics:4: UID=many@hostile: the file lists 50,000 RDATE/EXDATE dates")


def test_grammar_files_each_including_the_next_twice_stop_at_the_include_bound(tmp_path: Path) -> None:
    for i in range(1, 24):   # native files of includes only: 2^23 reads without a bound on the total
        includes = f'include "g{i + 1}.aggl"\ninclude "g{i + 1}.aggl"\n' if i < 23 else ""
        (tmp_path / f"g{i}.aggl").write_text(f"grammar g{i}\n{includes}")
    top = tmp_path / "g0.aggl"
    top.write_text((AGGL / "teleport.aggl").read_text().replace("===\n", "===\ninclude(g1.aggl)\ninclude(g1.aggl)\n", 1))
    check(["grammar", "check", str(top)], 1, "more than 200 includes in all")


def test_a_ring_target_on_a_clique_world_stops_at_the_expansion_bound(tmp_path: Path) -> None:
    rooms = range(2, 42)   # 40 rooms, every one linked to every other
    world = tmp_path / "clique.xml"
    world.write_text("<AGMModel>\n<symbol id=\"1\" type=\"robot\"/>\n"
                     + "".join(f'<symbol id="{r}" type="room"/>\n' for r in rooms)
                     + "".join(f'<link src="{a}" dst="{b}" label="conn"/>\n' for a in rooms for b in rooms if a != b)
                     + '<link src="1" dst="2" label="in"/>\n</AGMModel>\n')
    ring = [f"r{i}" for i in range(9)]   # a 9-room ring, and one room linked to itself (none is)
    target = tmp_path / "ring.aggt"
    target.write_text("{\n1:robot\n" + "".join(f"{r}:room\n" for r in ring)
                      + "".join(f"{ring[i]}->{ring[(i + 1) % 9]}(conn)\n" for i in range(9))
                      + "1->r8(in)\nr4->r4(conn)\n}\n")
    check(["plan", "--world", str(world), "--target", str(target), "--grammar", str(AGGL / "teleport.aggl"),
           "--max-expansions", "1"], 1, "expansion limit of 1 reached while matching patterns")


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="FIFOs are a POSIX feature")
def test_fifos_directories_and_devices_are_refused_as_such(tmp_path: Path) -> None:
    os.mkfifo(tmp_path / "agenda.yaml")
    os.mkfifo(tmp_path / "fifo.aggl")
    os.mkfifo(tmp_path / "map.pgm")
    (tmp_path / "folder.yaml").mkdir()
    for name in ("zero.yaml", "zero.xml", "zero.json"):
        (tmp_path / name).symlink_to("/dev/zero")
    for world in ("zero.xml", "zero.json"):
        check(["plan", "--world", str(tmp_path / world), "--target", str(AGGL / "robot_in_3.aggt"), "--grammar",
               str(AGGL / "teleport.aggl")], 2, f"{world}: is a device, not a world file")
    scene = tmp_path / "scene.yaml"
    scene.write_text((HOSTILE / "bom.yaml").read_text(encoding="utf-8-sig") + "agenda_file: agenda.yaml\n")
    check(["scene", "check", str(scene)], 1, "agenda_file: agenda file 'agenda.yaml': is a FIFO (named pipe)")
    check(["scene", "check", str(tmp_path / "agenda.yaml")], 1, "is a FIFO (named pipe), not a YAML file")
    for name, what in (("agenda.yaml", "is a FIFO (named pipe)"), ("folder.yaml", "is a directory"),
                       ("zero.yaml", "is a device")):
        check(["agenda", "load", str(tmp_path / name)], 1, f"{tmp_path / name}: {what}, not a yaml agenda file")
    grammar = tmp_path / "includes_fifo.aggl"
    grammar.write_text((AGGL / "teleport.aggl").read_text().replace("===\n", "===\ninclude(fifo.aggl)\n", 1))
    check(["grammar", "check", str(grammar)], 1, "included file 'fifo.aggl' at")
    check(["grammar", "check", str(tmp_path / "fifo.aggl")], 1, "is a FIFO (named pipe), not a grammar file")
    (tmp_path / "map.yaml").write_text((HOSTILE / "map_ok.yaml").read_text().replace("map_small.pgm", "map.pgm"))
    check([*FROM_MAP, str(tmp_path / "map.yaml"), "--out", str(tmp_path / "s.yaml")], 2,
          "map.pgm: is a FIFO (named pipe), not a map image")


def test_from_map_writes_its_values_with_a_yaml_emitter(tmp_path: Path) -> None:
    exit_code, _, output = run([*FROM_MAP, _h("map_ok.yaml"), "--out", str(tmp_path / "s.yaml"), "--name",
                                "x\nresolution: 0.1"])
    assert exit_code == 2 and "Invalid value for --name" in output and "contains control characters" in output
    assert not (tmp_path / "s.yaml").exists()
    name = 'Jos\u00e9: "ward" # 2'   # YAML's own punctuation stays part of the name
    exit_code, _, output = run([*FROM_MAP, _h("map_ok.yaml"), "--out", str(tmp_path / "s.yaml"), "--name", name])
    assert exit_code == 0, output
    written = yaml.safe_load((tmp_path / "s.yaml").read_text(encoding="utf-8"))
    assert written["name"] == name and "resolution" not in written


def test_a_name_typed_in_either_unicode_form_is_the_same_name(tmp_path: Path) -> None:
    scene = tmp_path / "jose.yaml"   # the scene says josé with one code point, the mission with two
    scene.write_text((HOSTILE / "bom.yaml").read_text(encoding="utf-8-sig").replace("name: ana", "name: jos\u00e9"),
                     encoding="utf-8")
    exit_code, _, output = run(["plan", str(scene), "--mission", "person:jose\u0301"])
    assert exit_code == 0 and "no person named" not in output, output


def test_a_100000_character_mission_is_not_echoed_whole() -> None:
    for extra in ([], ["--json"]):
        output = check(["plan", _h("bom.yaml"), "--mission", "room:" + "x" * 100_000, *extra], 2,
                       "a mission of 100,005 characters")
        assert output.count("x" * 100) <= 1
    exit_code, _, output = run(["plan", _h("bom.yaml"), "--mission", "room:" + "x" * 900, "--json"])
    assert exit_code == 1 and "no room named" in output and len(output) < 1_500, output[:3000]
    for args in (["path", _h("bom.yaml"), *PATH_ARGS, "--planner", "p" * 100_000],
                 ["evaluate", _h("bom.yaml"), "--planners", "p" * 100_000]):
        exit_code, _, output = run(args)
        assert exit_code == 2 and "unknown planner" in output and len(output) < 2_000, output[:3000]


if __name__ == "__main__":  # the table of the note
    import tempfile

    with tempfile.TemporaryDirectory() as folder:
        for args, _, _ in CASES:
            args = [a.replace("{tmp}", folder) for a in args]
            code, first, _ = run(args)
            shown = " ".join(Path(a).name if a.startswith(str(HOSTILE)) else (a if len(a) < 30 else a[:20] + "...")
                             for a in args)
            sys.stdout.write(f"| `chronav {shown}` | {code} | "
                             f"{first.replace(str(HOSTILE) + '/', '').replace('|', '/')[:160]} |\n")
