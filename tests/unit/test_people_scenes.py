"""`chronav scene check` on people's routines: each mistake named at its file, line and key."""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from tools.cli import app

SCENE = Path(__file__).resolve().parents[1] / "data" / "crowd_small.yaml"
ANA = "  - {name: ana, routine: wander, pose: [2.0, 4.0, 0], home: activity_room}"


def check(tmp_path: Path, ana: str, extra: str = "") -> tuple[int, str]:
    text = SCENE.read_text()
    assert ANA in text
    scene = tmp_path / "scene.yaml"
    scene.write_text(text.replace(ANA, ana) + extra)
    result = CliRunner().invoke(app, ["scene", "check", str(scene)])
    line = next(i for i, row in enumerate(scene.read_text().splitlines(), start=1) if "name: ana" in row)
    return result.exit_code, result.output.replace(str(scene), "SCENE").replace(f"SCENE:{line}:", "SCENE:ANA:")


@pytest.mark.parametrize(("ana", "expected"), [
    ("  - {name: ana, routine: jog, pose: [2.0, 4.0, 0]}", "routine"),
    ("  - {name: ana, routine: wander, pose: [2.0, 4.0, 0], waypoints: [{time: '09:10', pose: [2, 5, 0]}]}",
     "timed waypoints go with routine 'stay'"),
    ("  - {name: ana, routine: wander, pose: [2.0, 4.0, 0], visits: carla}", "'visits' belongs to routine 'visitor'"),
    ("  - {name: ana, role: visitor, routine: visitor, pose: [2.0, 4.0, 0]}", "needs 'visits'"),
    ("  - {name: ana, routine: wander, pose: [2.0, 4.0, 0], dwell: [300, 60]}", "not above the maximum"),
    ("  - {name: ana, routine: wander, pose: [2.0, 4.0, 0], speed: 3.0}", "1.5"),
    ("  - {name: ana, pose: [2.0, 4.0, 0], rooms: [lounge]}", "this person has routine 'stay'"),
    ("  - {name: ana, routine: wander, pose: [2.0, 4.0, 0], home: kitchen}", "no room named 'kitchen'"),
    ("  - {name: ana, routine: wander, pose: [2.0, 4.0, 0], rooms: [lounge, atrium]}", "no room named 'atrium'"),
    ("  - {name: ana, role: visitor, routine: visitor, visits: zoe, pose: [2.0, 4.0, 0]}", "no person named 'zoe'"),
])
def test_routine_mistakes_are_located(tmp_path: Path, ana: str, expected: str) -> None:
    code, output = check(tmp_path, ana)
    assert code == 1, output
    assert "SCENE:ANA:" in output and "people[0]" in output, output
    assert expected in output, output
    assert "Traceback" not in output


def test_nobody_to_fetch_an_escorted_resident(tmp_path: Path) -> None:
    text = SCENE.read_text()
    for staff in ("  - {name: eva, role: therapist, routine: staff, pose: [8.0, 4.0, 0], rooms: [therapy_room, corridor]}",
                  "  - {name: marta, role: staff, routine: staff, pose: [10.0, 1.2, 0]}"):
        assert staff in text
        text = text.replace(staff, staff.replace("routine: staff, ", "").replace(", rooms: [therapy_room, corridor]", ""))
    scene = tmp_path / "scene.yaml"
    scene.write_text(text)
    result = CliRunner().invoke(app, ["scene", "check", str(scene)])
    assert result.exit_code == 1 and "people[1].escort" in result.output and "nobody has routine 'staff'" in result.output


def test_a_room_nobody_can_walk_to(tmp_path: Path) -> None:
    """The lounge's door walled up: a resident whose rooms include it is refused at the scene check."""
    code, output = check(tmp_path, "  - {name: ana, routine: wander, pose: [2.0, 4.0, 0], rooms: [activity_room, lounge]}",
                         "\n")
    assert code == 0, output
    text = SCENE.read_text().replace("  - [[15.6, 2.4], [18, 2.4]]", "  - [[14.4, 2.4], [18, 2.4]]")
    text = text.replace(ANA, "  - {name: ana, routine: wander, pose: [2.0, 4.0, 0], rooms: [activity_room, lounge]}")
    text = text.replace("  - {name: door_lounge, between: [corridor, lounge], position: [15, 2.4], width: 1.2}\n", "")
    text = text.replace("  - {name: carla, routine: wander, pose: [16.0, 4.0, 0], home: lounge}\n", "")
    text = text.replace("  - {name: luis, role: visitor, routine: visitor, visits: carla, pose: [17.0, 1.2, 3.14]}\n", "")
    text = text.replace("  - {name: ben, routine: wander, pose: [14.0, 5.0, 0], walker: true, escort: true}\n", "")
    scene = tmp_path / "walled.yaml"
    scene.write_text(text)
    result = CliRunner().invoke(app, ["scene", "check", str(scene)])
    assert result.exit_code == 1, result.output
    assert "people[0].rooms" in result.output and "cannot walk" in result.output and "'lounge'" in result.output
