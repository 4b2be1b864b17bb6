"""`chronav scene show SCENE [--json]`: rooms (a point inside each), doors, objects, people with
coordinates, the robot, the day's agenda and the missions, readable at 80 columns (issue 39)."""

from __future__ import annotations

import json

import pytest
from shapely.geometry import Point, Polygon
from typer.testing import CliRunner

from agents.world.scene_world import load_world
from tests.support import REPO_ROOT
from tools.cli import app

runner = CliRunner()
PIPED = {"COLUMNS": "80"}


@pytest.mark.parametrize("scene", ["center_day", "icra_usecase"])
def test_scene_show_json_holds_every_name_and_a_point_in_each_room(scene: str) -> None:
    world = load_world(REPO_ROOT / "scenes" / f"{scene}.yaml")
    result = runner.invoke(app, ["scene", "show", scene, "--json"])
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    spec = world.scene
    assert [r["name"] for r in data["rooms"]] == [r.name for r in spec.rooms]
    assert [d["name"] for d in data["doors"]] == [d.name for d in spec.doors]
    assert {o["name"]: o["at"] for o in data["objects"]} == {o.name: [o.pose.x, o.pose.y] for o in spec.objects}
    assert {p["name"]: p["at"] for p in data["people"]} == {p.name: [p.pose.x, p.pose.y] for p in spec.people}
    assert [a["id"] for a in data["agenda"]] == [a.id for a in world.agenda.activities]
    assert [m["goal"] for m in data["missions"]] == [m.goal_text() for m in spec.missions]
    for room, row in zip(spec.rooms, data["rooms"], strict=True):
        assert Polygon(room.polygon).contains(Point(row["point"])), (room.name, row["point"])
    assert data["robot"]["at"] == [spec.robot.pose.x, spec.robot.pose.y]


@pytest.mark.parametrize("scene", ["center_day", "icra_usecase"])
def test_scene_show_piped_at_80_columns(scene: str) -> None:
    world = load_world(REPO_ROOT / "scenes" / f"{scene}.yaml")
    result = runner.invoke(app, ["scene", "show", scene], env=PIPED)
    assert result.exit_code == 0, result.output
    lines = result.stdout.splitlines()
    assert all(len(line) <= 80 for line in lines), [line for line in lines if len(line) > 80]
    words = set(result.stdout.replace(",", " ").replace("(", " ").replace(")", " ").split())
    names = ({r.name for r in world.scene.rooms} | {o.name for o in world.scene.objects}
             | {p.name for p in world.scene.people} | {a.id for a in world.agenda.activities})
    assert names <= words, names - words           # every name whole, none split across lines
    assert len(lines) < 2 * (len(names) + len(world.scene.missions)) + 20
    assert f"rooms ({len(world.scene.rooms)}): a point inside each" in lines


def test_the_room_points_are_points_chronav_path_plans_between() -> None:
    data = json.loads(runner.invoke(app, ["scene", "show", "icra_usecase", "--json"]).stdout)
    (ot, pt) = (r["point"] for r in data["rooms"])
    result = runner.invoke(app, ["path", "icra_usecase", "--at", "10:00", "--from", f"{ot[0]},{ot[1]}",
                                 "--to", f"{pt[0]},{pt[1]}", "--json"])
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout)["length_m"] > 0


def test_scene_show_of_a_bad_scene_names_the_file_line_and_key(tmp_path) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: bad\nrooms: []\nrobot: {pose: [1, 1, 0]}\n")
    result = runner.invoke(app, ["scene", "show", str(bad)])
    assert result.exit_code == 1 and "bad.yaml:2" in result.stderr and "Traceback" not in result.output
