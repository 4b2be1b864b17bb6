"""People who are in the building only for their hours (issue 41: people arrive and leave by their
routines): a staff member's shift, a visitor's visit.  They come in at their scene pose at the
first time, live their routine, walk back there at the second and leave; outside their hours they
are nowhere (not simulated, not seen).  Tested through the scene's crowd, the one the simulator
feeds the DSR with (agents/world/people.py), and through `chronav scene check` for bad hours."""

from __future__ import annotations

import math
from pathlib import Path

from typer.testing import CliRunner

from agents.world.people import people_at
from agents.world.scene_world import load_world
from scenes.clock import parse_clock
from tools.cli import app

TINY = Path(__file__).resolve().parents[1] / "data" / "eval_tiny.yaml"
NURSE = '  - {name: nurse, role: staff, routine: staff, pose: [0.5, 3.5, 0], hours: ["09:20", "09:40"]}\n'
VISITOR = '  - {name: son, role: visitor, routine: visitor, visits: resident, pose: [5.5, 3.5, 3.14], hours: ["09:00", "09:30"]}\n'


def _scene(tmp_path: Path, *people: str) -> Path:
    text = TINY.read_text().replace('pose: [3.6, 1.5, -1.5708]}\n', 'pose: [3.6, 1.5, -1.5708]}\n' + "".join(people), 1)
    path = tmp_path / "hours.yaml"
    path.write_text(text)
    return path


def _where(world, name: str, clock: str, later_s: float = 0.0) -> tuple[float, float] | None:
    found = [p for p in people_at(world, parse_clock(clock) + later_s) if p.name == name]
    return (found[0].x, found[0].y) if found else None


def test_a_shift_and_a_visit_come_in_at_their_pose_and_leave_by_it(tmp_path: Path) -> None:
    world = load_world(_scene(tmp_path, NURSE, VISITOR))
    assert _where(world, "nurse", "09:10") is None                 # before the shift: not in the building
    arrived = _where(world, "nurse", "09:20", later_s=0.2)
    assert arrived is not None and math.dist(arrived, (0.5, 3.5)) < 0.5
    assert _where(world, "nurse", "09:30") is not None and _where(world, "nurse", "09:39:59") is not None
    assert _where(world, "nurse", "09:45") is None                  # walked back to the way in and left
    assert _where(world, "nurse", "10:20") is None                  # and stays gone
    assert _where(world, "son", "09:00") is not None and _where(world, "son", "09:35") is None
    assert _where(world, "resident", "09:10") is not None and _where(world, "resident", "10:20") is not None


def test_the_last_place_before_leaving_is_the_way_in(tmp_path: Path) -> None:
    world = load_world(_scene(tmp_path, NURSE))
    seen = [(k, _where(world, "nurse", "09:40", later_s=0.1 * k)) for k in range(0, 1200)]
    last = [pos for _, pos in seen if pos is not None]
    assert last and math.dist(last[-1], (0.5, 3.5)) < 0.9, seen[:5]


def test_hours_that_cannot_be_lived_are_refused_at_their_key(tmp_path: Path) -> None:
    backwards = _scene(tmp_path, NURSE.replace('["09:20", "09:40"]', '["09:40", "09:20"]'))
    result = CliRunner().invoke(app, ["scene", "check", str(backwards)])
    assert result.exit_code != 0 and "hours" in result.output and "after the time they arrive" in result.output
    still = _scene(tmp_path, '  - {name: clerk, role: staff, pose: [0.5, 3.5, 0], hours: ["09:20", "09:40"]}\n')
    result = CliRunner().invoke(app, ["scene", "check", str(still)])
    assert result.exit_code != 0 and "routine that walks" in result.output


def test_a_live_run_sees_people_only_in_their_hours(tmp_path: Path, monkeypatch) -> None:
    """In-process, as `chronav launch --in-process` runs it: the robot crosses the room at 10:00; the
    nurse (09:50-10:10) is there and in people.csv, the visitor (09:00-09:30) has left by then."""
    import csv
    import json

    monkeypatch.setenv("CHRONAV_RUNS", str(tmp_path / "runs"))
    scene = _scene(tmp_path, NURSE.replace('["09:20", "09:40"]', '["09:50", "10:10"]'), VISITOR)
    result = CliRunner().invoke(app, ["launch", str(scene), "--in-process", "--no-record", "--json"])
    assert result.exit_code == 0, result.output
    summary = json.loads(result.stdout)
    with (Path(summary["run_dir"]) / "people.csv").open() as handle:
        names = {row["name"] for row in csv.DictReader(handle)}
    assert {"resident", "nurse"} <= names and "son" not in names, names
