"""Hostile and careless input, through the commands a user types (issue 12): every file under
tests/data/hostile/ gets a located error in the user's words and a non-zero exit (or is accepted
when it should be), within bounded time and memory, never a traceback.

``CASES`` is also the table of the issue's note: ``python -m tests.unit.test_hostile_inputs``
prints input -> exit code -> first line of the message.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from tools.cli import app

HOSTILE = Path(__file__).resolve().parents[1] / "data" / "hostile"
runner = CliRunner()


def _h(name: str) -> str:
    return str(HOSTILE / name)


# (command line, expected exit code, text the first line of the output must contain)
CASES: list[tuple[list[str], int, str]] = [
    # Crashes that were tracebacks: invalid dates, huge integers, deep nesting, in every command.
    *[([*cmd, _h(f)], code, "is not a valid date or time")
      for f in ("date_month13.yaml", "date_feb30.yaml", "timestamp_hour25.yaml")
      for cmd, code in ((["scene", "check"], 1), (["launch", "--no-record", "--timeout", "5"], 2), (["demo"], 2))],
    (["path", _h("date_month13.yaml"), "--at", "10:00", "--from", "1,1", "--to", "4,1"], 2, "2026-13-45"),
    (["plan", _h("date_feb30.yaml"), "--mission", "room:room"], 2, "2026-02-30"),
    (["metrics", _h("timestamp_hour25.yaml"), _h("traj_ok_bom.csv")], 2, "2026-11-25T25:00:00"),
    (["scene", "check", _h("int_5000_digits.yaml")], 1, "a number of 5,000 digits; chronav reads at most 30"),
    (["scene", "check", _h("nesting_1000.yaml")], 1, "nested more than 64 levels deep"),
    # Unbounded memory and time.
    (["scene", "check", _h("billion_laughs.yaml")], 1, "the file expands to more than 100,000 values"),
    (["scene", "check", _h("agenda_secondly.yaml")], 1, "RRULE:FREQ=SECONDLY from 2026-01-01 09:00"),
    (["scene", "check", _h("room_2km.yaml")], 1, "40,000 x 40,000 = 1,600,000,000 cells, more than the limit"),
    (["path", _h("room_1e6m.yaml"), "--at", "10:00", "--from", "1,1", "--to", "4,1"], 2,
     "400,000,000,000,000 cells, more than the limit of 16,000,000"),
    # Silently accepted before.
    (["scene", "check", _h("person_on_wall.yaml")], 1, "person 'ana' at (3, 4) is on a wall"),
    (["scene", "check", _h("person_in_footprint.yaml")], 1, "person 'ana' at (5.5, 2) is inside object 'tv'"),
    (["scene", "check", _h("robot_in_object.yaml")], 1, "robot at (5.2, 2) is inside object 'tv'"),
    (["scene", "check", _h("robot_in_wall.yaml")], 1, "robot at (0.1, 1) is on a wall"),
    (["scene", "check", _h("goal_on_wall.yaml")], 1, "goal of mission 'm1' at (6, 1) is on a wall"),
    (["scene", "check", _h("goal_walled_off.yaml")], 1, "cannot be reached from the robot's start (1, 1)"),
    (["scene", "check", _h("door_ok.yaml")], 0, "door_ok.yaml: ok (2 rooms"),
    (["scene", "check", _h("door_off_wall.yaml")], 1, "is not on the outline of room 'west'"),
    (["scene", "check", _h("door_of_covered_room.yaml")], 1, "is not on the outline of room 'closet'"),
    (["scene", "check", _h("door_solid_wall.yaml")], 1, "door 'd' at (3, 3.2) is on solid wall"),
    (["scene", "check", _h("radius_50.yaml")], 1, "robot.radius: must be at most 2.0, got 50"),
    (["scene", "check", _h("max_speed_inf.yaml")], 1, "robot.max_speed: must be at most 5.0, got inf"),
    (["scene", "check", _h("pose_bools.yaml")], 1, "robot.pose[0]: expected a number, got true"),
    (["scene", "check", _h("duplicate_key.yaml")], 1, ":13:1: robot: duplicate key 'robot' (first on line 12"),
    (["scene", "check", _h("agenda_unknown_participant.yaml")], 1, "participant 'bob' is not a person of the scene"),
    (["scene", "check", _h("agenda_overlap.yaml")], 0, "agenda_overlap.yaml: ok"),
    (["scene", "check", _h("agenda_long_name.yaml")], 1, "a value of 100,000 characters; chronav reads at most"),
    (["scene", "check", _h("agenda_ansi_name.yaml")], 1, "Game \\x1b[2J\\x1b[31mred contains control characters"),
    (["metrics", _h("bom.yaml"), _h("traj_outside.csv")], 2, "no sample of the trajectory lies in a room"),
    (["metrics", _h("bom.yaml"), _h("traj_zero_duration.csv")], 2, "the trajectory lasts 0 s"),
    (["metrics", _h("bom.yaml"), _h("traj_huge_t.csv")], 2, "3.6e304 s is not a time of the simulated day"),
    (["metrics", _h("bom.yaml"), _h("traj_ok_bom.csv"), "--json"], 0, '{"scene": "hostile"'),
    (["scene", "check", _h("bom.yaml")], 0, "bom.yaml: ok"),
    # Messages a user can act on.
    (["scene", "check", _h("pose_text.yaml")], 1, "robot.pose: a pose is [x, y] or [x, y, theta]"),
    (["scene", "check", _h("agenda_id_with_space.yaml")], 1, "agenda[0].id: an id is one word without spaces"),
    (["scene", "check", _h("misspelt_key.yaml")], 1, ":12:1: robto: unknown key 'robto' (did you mean 'robot'?)"),
    (["scene", "check", _h("duplicate_names.yaml")], 1, ":12:6: people[1].name: duplicate person name 'ana'"),
    (["scene", "check", _h("unknown_reference.yaml")], 1, ":14:36: missions[0].goal.room: no room named 'kitchen'"),
    (["path", _h("bom.yaml"), "--at", "10:00", "--from", "1,1", "--to", "5.5,2"], 1,
     "goal (5.50, 2.00) m is blocked: it is 0.00 m from the footprint of object 'tv'"),
    (["path", _h("bom.yaml"), "--at", "9", "--from", "1,1", "--to", "4,1"], 2, "'9' is not a clock time"),
    (["plan", _h("bom.yaml"), "--mission", "room:room", "--at", "9"], 2, "'9' is not a clock time"),
    (["agenda", "add", "tv", "10:00", "11:00", "--name", "x" * 100_000], 1, "a name of 100,000 characters"),
    (["agenda", "add", "tv", "10:00", "11:00", "--name", "\x1b[2J\x1b]0;pwned\x07"], 1, "\\x1b[2J"),
    (["agenda", "load", _h("agenda_file_ansi.yaml")], 1, "has errors, nothing was sent"),
]


def run(args: list[str]) -> tuple[int, str, str]:
    """Exit code, first line of stderr (else stdout), and all output, as the user sees them."""
    result = runner.invoke(app, args, env={"CHRONAV_ZENOH_CONNECT": "tcp/127.0.0.1:1", "COLUMNS": "200"})
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise result.exception
    text = result.stderr or result.stdout
    return result.exit_code, (text.splitlines() or [""])[0], result.stdout + result.stderr


def _id(case: tuple[list[str], int, str]) -> str:
    args = case[0]
    files = [Path(a).name for a in args if a.startswith(str(HOSTILE))]
    return " ".join([args[0], *files, *(a[:12] for a in args[1:] if not a.startswith(str(HOSTILE)))])[:80]


@pytest.mark.parametrize("case", CASES, ids=[_id(c) for c in CASES])
def test_hostile_input_gets_a_clear_error(case: tuple[list[str], int, str]) -> None:
    args, code, expected = case
    exit_code, first, output = run(args)
    assert exit_code == code, output[:2000]
    assert expected in first, output[:2000]
    assert "Traceback" not in output and "pydantic" not in output and "Value error" not in output
    assert "\x1b" not in output, "a terminal escape reached the terminal"
    assert len(output) < 20_000, "a message must not echo a whole input"


def test_agenda_file_of_a_scene_with_ansi_is_refused_with_escapes_shown(tmp_path: Path) -> None:
    exit_code, first, output = run(["agenda", "load", _h("agenda_file_ansi.yaml")])
    assert exit_code == 1 and "\\x1b]0;pwned" in output and "\x1b" not in output


if __name__ == "__main__":  # the table of the note
    for args, _, _ in CASES:
        code, first, _ = run(args)
        shown = " ".join(Path(a).name if a.startswith(str(HOSTILE)) else (a if len(a) < 30 else a[:20] + "...")
                         for a in args)
        sys.stdout.write(f"| `chronav {shown.encode('unicode_escape').decode()}` | {code} | "
                         f"{first.replace(str(HOSTILE) + '/', '').replace('|', '/')[:160]} |\n")
