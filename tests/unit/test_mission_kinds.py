"""Every mission kind through `chronav plan SCENE`, planned as the live executive plans it.

Issue 11: `pose:` was an unknown kind for `chronav plan`, `wait:` wanted the DSR node name
(`activity/ID`) instead of the id `chronav agenda list` shows, and `chronav plan` planned on its
own graph with its own mission handling.  Now both go through `agents/missions`.
"""

from __future__ import annotations

import json
import math

import pytest
from typer.testing import CliRunner

from agents.missions.goals import SOCIAL_DISTANCE_M
from agents.missions.kinds import KINDS, MissionStringError, parse_mission
from agents.missions.planning import MissionPlanner
from agents.missions.steps import RULE_VARS, Rule, Var
from agents.world.people import people_at
from agents.world.offline import graph_at
from agents.world.scene_world import load_world
from grammar import default_grammar_path, load_grammar
from scenes.clock import parse_clock
from tools.cli import app

RUNNER = CliRunner()


def plan(*args: str, exit_code: int = 0) -> dict:
    result = RUNNER.invoke(app, ["plan", "center_day", *args, "--json"])
    assert result.exit_code == exit_code, result.output
    return json.loads(result.stdout)


def test_mission_strings() -> None:
    assert parse_mission("wait:tv_game").names == ("activity/tv_game",)
    assert parse_mission("wait:activity/tv_game").names == ("activity/tv_game",)
    assert parse_mission("pose:1,2.5,-0.5").pose == (1.0, 2.5, -0.5)
    assert parse_mission("pose: 1 , 2").pose == (1.0, 2.0, None)
    assert parse_mission("group:a + b").names == ("a", "b")
    assert parse_mission("pose:1,2").grammar_mission("hall") == "room:hall"
    assert set(KINDS) == {"room", "object", "person", "group", "wait", "pose"}


@pytest.mark.parametrize("text,fragment", [
    ("kitchen", "not KIND:ARGUMENT"),
    ("fly:kitchen", "unknown mission kind 'fly'"),
    ("room:", "no argument"),
    ("pose:1", "expected pose:X,Y or pose:X,Y,THETA"),
    ("pose:1,2,3,4", "expected pose:X,Y"),
    ("pose:1,nan,0", "finite"),
    ("pose:a,b", "expected pose:X,Y"),
    ("wait:activity/", "names no activity"),
    ("group:ann", "at least two"),
    ("group:ann+ann", "twice"),
])
def test_malformed_mission_strings(text: str, fragment: str) -> None:
    with pytest.raises(MissionStringError, match=fragment):
        parse_mission(text)


def test_binding_names_are_the_grammars() -> None:
    """The executive reads each rule's bindings by the names the shipped grammar gives them."""
    rules = {rule.name: rule for rule in load_grammar(default_grammar_path()).rules}
    for rule, variables in RULE_VARS.items():
        declared = {node.name for node in rules[rule].lhs.nodes}
        assert set(variables) <= declared, f"{rule} binds {sorted(declared)}, the executive reads {variables}"
    assert Var.ROOM in {n.name for n in rules[Rule.APPROACH_PERSON].lhs.nodes}
    assert Var.ROBOT in {n.name for n in rules[Rule.CHANGE_ROOM].lhs.nodes}


def test_plan_pose_mission_shows_the_pose() -> None:
    out = plan("--mission", "pose:2.5,5,1.5708", "--at", "09:00")
    assert out["found"] and out["grammar_mission"] == "room:activity_room"
    assert [s["rule"] for s in out["steps"]] == ["changeRoom", "goToPose"]
    last = out["steps"][-1]
    assert last["goal"] == {"x": 2.5, "y": 5.0, "theta": 1.5708} and last["rooms"] == ["corridor", "activity_room"]
    assert out["intentions"] == 1
    text = RUNNER.invoke(app, ["plan", "center_day", "--mission", "pose:2.5,5,1.5708", "--at", "09:00"])
    assert text.exit_code == 0 and "goToPose" in text.stdout and "(2.50, 5.00)" in text.stdout


def test_plan_pose_outside_every_room() -> None:
    out = plan("--mission", "pose:40,40,0", exit_code=1)
    assert out["found"] is False and "in no room" in out["reason"]


def test_plan_room_mission_ends_inside_the_room() -> None:
    out = plan("--mission", "room:dining_room", "--at", "09:30")
    assert [s["rule"] for s in out["steps"]] == ["goToRoom"]
    assert out["steps"][0]["bindings"]["r2"] == "dining_room" and out["steps"][0]["goal"]["theta"] is None


def test_plan_wait_by_the_agenda_id() -> None:
    for text in ("wait:table_therapy", "wait:activity/table_therapy"):
        out = plan("--mission", text, "--at", "09:05")
        (step,) = out["steps"]
        assert step["rule"] == "waitFor" and step["until_s"] == parse_clock("09:20")
    unknown = RUNNER.invoke(app, ["plan", "center_day", "--mission", "wait:tv_gam"])
    assert unknown.exit_code == 1
    assert "no activity 'tv_gam' on today's agenda; activities: bingo, coffee, exercise" in unknown.stderr
    assert "table_therapy, tv_game" in unknown.stderr


def test_plan_object_only_after_its_activity() -> None:
    during = plan("--mission", "object:therapy_table", "--at", "09:06", exit_code=1)
    assert during["found"] is False
    assert during["diagnosis"]["blockers"][0]["rule"] == "goToObject", "the grammar says why"
    text = RUNNER.invoke(app, ["plan", "center_day", "--mission", "object:therapy_table", "--at", "09:06"])
    assert "fails: activity/table_therapy -has-> therapy_table" in text.stderr
    after = plan("--mission", "object:therapy_table", "--at", "09:20")
    assert after["steps"][-1]["rule"] == "goToObject" and "goal" in after["steps"][-1]


def test_plan_person_where_the_dsr_has_her_then() -> None:
    for at in ("09:00", "09:45:06"):
        out = plan("--mission", "person:nurse_marta", "--at", at)
        goal = out["steps"][-1]["goal"]
        nurse = next(p for p in people_at(load_world("center_day"), parse_clock(at)) if p.name == "nurse_marta")
        assert math.hypot(goal["x"] - nurse.x, goal["y"] - nurse.y) == pytest.approx(SOCIAL_DISTANCE_M, abs=0.01)
        bearing = math.atan2(nurse.y - goal["y"], nurse.x - goal["x"])
        assert abs(math.remainder(goal["theta"] - bearing, math.tau)) < 0.01


def test_plan_group_and_errors() -> None:
    out = plan("--mission", "group:res_carla+visitor_luis", "--at", "09:35")
    assert out["steps"][-1]["rule"] == "takeTheAttention"
    bad = RUNNER.invoke(app, ["plan", "center_day", "--mission", "fly:x"])
    assert bad.exit_code == 2 and "expected one of room, object, person, group, wait, pose" in bad.stderr
    nobody = RUNNER.invoke(app, ["plan", "center_day", "--mission", "person:nobody", "--json"])
    assert nobody.exit_code == 1 and "no person named 'nobody'; people: nurse_marta" in nobody.stderr
    assert json.loads(nobody.stdout)["found"] is False


@pytest.mark.parametrize("mission,at", [("pose:2.5,5,1.5708", "09:00"), ("room:dining_room", "09:30"),
                                        ("object:therapy_table", "09:20"), ("person:nurse_marta", "09:45"),
                                        ("group:res_carla+visitor_luis", "09:35"), ("wait:table_therapy", "09:05")])
def test_chronav_plan_is_the_executives_plan(mission: str, at: str) -> None:
    """The command prints what the executive's planner gives on the agents' DSR at that time."""
    world = load_world("center_day")
    t = parse_clock(at)
    steps = MissionPlanner(world.scene).plan(graph_at(world, t), mission).steps
    out = plan("--mission", mission, "--at", at)
    assert [(s["rule"], s["bindings"]) for s in out["steps"]] == [(s.rule, s.bindings) for s in steps]


@pytest.mark.parametrize("goal,fragment", [
    ("{group: [res_carla, visitor_lu]}", "no person named 'visitor_lu'; did you mean 'visitor_luis'?"),
    ("{group: [res_carla, res_carla]}", "'res_carla' is named twice in the group"),
    ("{group: [res_carla]}", "group"),
    ("{wait: table_therapi}", "waits for unknown activity 'table_therapi'; activities: bingo, coffee"),
    ("{dance: res_carla}", "a goal is one of"),
])
def test_scene_check_names_bad_group_and_wait_goals(tmp_path, goal: str, fragment: str) -> None:
    from scenes.loader import SCENES_DIR

    text = (SCENES_DIR / "center_day.yaml").read_text()
    scene = tmp_path / "bad.yaml"
    scene.write_text(text + f'  - {{id: extra, time: "10:00", goal: {goal}}}\n')
    line = len(text.splitlines()) + 1
    result = RUNNER.invoke(app, ["scene", "check", str(scene)])
    assert result.exit_code != 0 and fragment in result.stderr, result.output
    assert f"{scene}:{line}:" in result.stderr, "located at the mission's line"
