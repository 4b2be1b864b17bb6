"""Scene files: every shipped scene validates, and bad scenes fail with file:line:col and the key."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from typer.testing import CliRunner

from scenes.loader import SCENES_DIR, load_scene
from scenes.clock import parse_clock
from agents.world.motion import people_at
from agents.world.dsr_readers import symbolic_view
from agents.world.offline import graph_at
from agents.world.scene_world import load_world
from scenes.yamlio import SourceError
from tools.cli import app

SHIPPED = sorted(p.name for p in SCENES_DIR.glob("*.yaml"))


@pytest.mark.parametrize("name", SHIPPED)
def test_shipped_scene_is_valid(name: str) -> None:
    scene = load_scene(SCENES_DIR / name).scene
    assert scene.missions, "a shipped scene must give the robot something to do"
    assert all(scene.room_at(o.pose.x, o.pose.y) for o in scene.objects)


def test_required_scenes_are_shipped() -> None:
    assert {"icra_usecase.yaml", "center_a.yaml", "center_b.yaml", "apartment_lab.yaml"} <= set(SHIPPED)


def _write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    return path


BASE = """name: t
walls:
  - [[0, 0], [6, 0], [6, 4], [0, 4], [0, 0]]
rooms:
  - {name: room, polygon: [[0, 0], [6, 0], [6, 4], [0, 4]]}
robot: {pose: [1, 1, 0]}
"""


def test_unknown_key_names_line_and_key(tmp_path: Path) -> None:
    path = _write(tmp_path, BASE.replace("robot: {pose: [1, 1, 0]}", "robot: {pose: [1, 1, 0], radiuss: 0.3}"))
    with pytest.raises(SourceError) as info:
        load_scene(path)
    err = info.value
    assert err.line == 6 and err.key == "robot.radiuss"
    assert str(err).startswith(f"{path}:6:")


def test_person_outside_building_is_reported_at_its_pose(tmp_path: Path) -> None:
    text = BASE + "people:\n  - {name: ann, pose: [40, 2, 0]}\n"
    with pytest.raises(SourceError) as info:
        load_scene(_write(tmp_path, text))
    assert info.value.line == 8 and "outside every room" in info.value.message


def test_walking_through_a_wall_is_refused(tmp_path: Path) -> None:
    text = BASE.replace("  - [[0, 0], [6, 0], [6, 4], [0, 4], [0, 0]]\n",
                        "  - [[0, 0], [6, 0], [6, 4], [0, 4], [0, 0]]\n  - [[3, 0], [3, 4]]\n")
    text += "people:\n  - name: ann\n    pose: [1, 2, 0]\n    waypoints:\n      - {time: '10:00', pose: [5, 2, 0]}\n"
    with pytest.raises(SourceError) as info:
        load_scene(_write(tmp_path, text))
    assert "walk through a wall" in info.value.message


def test_mission_to_unknown_room_is_refused(tmp_path: Path) -> None:
    text = BASE + "missions:\n  - {id: m, time: '10:00', goal: {room: kitchen}}\n"
    with pytest.raises(SourceError) as info:
        load_scene(_write(tmp_path, text))
    assert info.value.key == "missions[0].goal.room" and info.value.line == 8
    assert "no room named 'kitchen'" in info.value.message


def test_yaml_syntax_error_has_position(tmp_path: Path) -> None:
    with pytest.raises(SourceError) as info:
        load_scene(_write(tmp_path, "name: [unclosed\nwalls: 3\n"))
    assert info.value.line >= 1 and "YAML syntax error" in info.value.message


def test_cli_scene_check_exit_codes(tmp_path: Path) -> None:
    runner = CliRunner()
    ok = runner.invoke(app, ["scene", "check", str(SCENES_DIR / "icra_usecase.yaml")])
    assert ok.exit_code == 0, ok.output
    bad = _write(tmp_path, BASE.replace("name: t", "name: t\nclock: {start: '25:00'}"))
    result = runner.invoke(app, ["scene", "check", str(bad)])
    assert result.exit_code == 1
    assert f"{bad}:" in result.output


def test_people_follow_waypoints_and_face_their_way() -> None:
    scene = load_scene("icra_usecase").scene
    start = {p.name: p for p in people_at(scene, parse_clock("09:00"))}
    assert (start["senior_1"].x, start["senior_1"].y) == (1.2, 6.0)
    at_tv = {p.name: p for p in people_at(scene, parse_clock("11:30"))}
    assert math.hypot(at_tv["senior_1"].x - 5.0, at_tv["senior_1"].y - 2.1) < 1e-9
    walking = {p.name: p for p in people_at(scene, parse_clock("10:52:30"))}
    assert walking["senior_1"].moving


def test_symbolic_graph_has_the_shared_vocabulary() -> None:
    view = symbolic_view(graph_at(load_world("center_a"), parse_clock("11:30")))
    key = {data["name"]: node for node, data in view.nodes(data=True)}
    assert view.nodes[key["corridor"]]["type"] == "room"
    assert view.has_edge(key["corridor"], key["occupational_therapy"], key="connected")
    assert view.has_edge(key["robot"], key["corridor"], key="in")
    assert view.nodes[key["activity/tv_therapy"]]["state"] == "running"
    assert view.has_edge(key["activity/tv_therapy"], key["ot_tv"], key="has")


def test_agenda_errors_fail_the_scene_with_the_line(tmp_path: Path) -> None:
    text = BASE + "agenda:\n  - {name: Game, object: piano, start: '11:00', end: '12:00'}\n"
    with pytest.raises(SourceError) as info:
        load_world(_write(tmp_path, text))
    assert info.value.line == 8 and "piano" in info.value.message
