"""Regression tests of issue 11 through the commands a user types: the offline commands see the
scripted world (doors, agenda changes, activity ends) exactly as the live agents do."""

from __future__ import annotations

import json
from pathlib import Path

import shapely
from typer.testing import CliRunner

from agents.lib.agenda.model import ActivityWindow
from agents.lib.agenda.chronemics import is_active
from agents.world.building import door_segment
from agents.world.navigation import NavigationMaps
from agents.world.offline import SceneMaps
from agents.world.scene_world import load_world
from scenes.clock import parse_clock
from scenes.loader import SCENES_DIR
from scenes.yamlio import SourceError
from tools.cli import app

RUNNER = CliRunner()


def chronav(*args: str, exit_code: int = 0) -> dict:
    result = RUNNER.invoke(app, [*args, "--json"])
    assert result.exit_code == exit_code, result.output
    return json.loads(result.stdout)


def scene_with(tmp_path: Path, base: str, extra: str) -> Path:
    path = tmp_path / f"{base}_variant.yaml"
    path.write_text((SCENES_DIR / f"{base}.yaml").read_text() + extra)
    return path


def test_a_door_closed_by_the_script_is_closed_for_plan_and_path(tmp_path: Path) -> None:
    scene = scene_with(tmp_path, "center_b", '\ndoor_changes:\n  - {at: "09:56", door: door_ot_north, open: false}\n')
    north = shapely.LineString(door_segment(load_world(scene).scene, "door_ot_north"))
    # Symbolic: into the OT room from the living room's side only through the south door now.
    plan = chronav("plan", str(scene), "--mission", "room:occupational_therapy", "--at", "10:00")
    doors = [step["bindings"].get("d") for step in plan["steps"] if step["rule"] in ("changeRoom", "goToRoom")]
    assert "door_ot_north" not in doors and "door_ot_south" in doors
    # Metric: the corridor's north end to the OT room's north end goes round by the south door.
    path = chronav("path", str(scene), "--at", "10:00", "--from", "7.2,14", "--to", "10,14")
    assert not shapely.LineString(path["points"]).intersects(north)
    assert path["length_m"] > 10.0
    before = chronav("path", str(scene), "--at", "09:55", "--from", "7.2,14", "--to", "10,14")
    assert before["length_m"] < 4.0, "before 09:56 the north door is open"


def test_a_scripted_cancellation_is_seen_by_path(tmp_path: Path) -> None:
    scene = scene_with(tmp_path, "icra_usecase", '\nagenda_changes:\n  - {at: "10:30", op: cancel, id: serious_game}\n')
    after = chronav("path", str(scene), "--at", "11:10", "--from", "1,1", "--to", "8,1")
    assert after["objects"]["tv"] == {"R": 1.5, "band": 0, "active": False}
    shipped = chronav("path", "icra_usecase", "--at", "11:10", "--from", "1,1", "--to", "8,1")
    assert shipped["objects"]["tv"]["R"] == 3.5 and shipped["objects"]["tv"]["active"]


def test_offline_maps_keep_the_navigation_margin() -> None:
    world = load_world("icra_usecase")
    offline = SceneMaps.load("icra_usecase").nav.params.grid
    assert offline == NavigationMaps.for_scene(world.scene).params.grid
    assert offline.robot_radius_m > world.scene.robot.radius  # body + planning margin, as the agent


def test_an_activity_is_over_at_its_end_everywhere() -> None:
    window = ActivityWindow("tv", parse_clock("11:00"), parse_clock("12:00"))
    assert is_active(parse_clock("11:59:59"), [window]) and not is_active(parse_clock("12:00"), [window])
    world = load_world("icra_usecase")
    at_end = SceneMaps.load(world).graph(parse_clock("12:00"))
    assert at_end.get_node_by_name("activity/serious_game").attrs["state"] == "finished"
    assert at_end.get_node_by_name("tv").attrs["active"] is False


def test_interactions_with_an_object_end_with_its_activity() -> None:
    during = chronav("plan", "center_a", "--mission", "object:ot_table", "--at", "11:00", exit_code=1)
    assert during["found"] is False
    after = chronav("plan", "center_a", "--mission", "object:ot_table", "--at", "12:10")
    assert after["found"] and after["steps"][-1]["rule"] == "goToObject"


def test_interacting_with_an_object_in_a_scene_is_refused_with_what_to_do(tmp_path: Path) -> None:
    text = (SCENES_DIR / "center_a.yaml").read_text().replace(
        "{name: senior_1, role: resident, pose: [3.0, 5.1, 1.5708]}",
        "{name: senior_1, role: resident, pose: [3.0, 5.1, 1.5708], interacting_with: [ot_table]}")
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    try:
        load_world(path)
    except SourceError as exc:
        assert "links to objects come from the agenda" in exc.message
    else:
        raise AssertionError("a person interacting with an object in the scene was accepted")
