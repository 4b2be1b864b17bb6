"""`chronav grammar check` and `chronav plan`, through the real typer app."""

from __future__ import annotations

import json
from pathlib import Path

import networkx as nx
import pytest
from typer.testing import CliRunner

from grammar.parser import default_grammar_path
from grammar.world import graph_from_mapping
from tools.cli import app

runner = CliRunner()


def test_grammar_check_ok_and_broken_files(tmp_path: Path) -> None:
    ok = runner.invoke(app, ["grammar", "check", str(default_grammar_path())])
    assert ok.exit_code == 0, ok.output
    assert "6 rules" in ok.stdout and "1 file(s) OK" in ok.stdout
    broken = tmp_path / "broken.aggl"
    broken.write_text("rule r {\n  lhs { a:room @ }\n  rhs { }\n}\n")
    also = tmp_path / "also.aggt"
    also.write_text("{ a:b }\nfoo\n")
    result = runner.invoke(app, ["grammar", "check", str(broken), str(default_grammar_path()), str(also)])
    assert result.exit_code == 1
    errors = result.stderr.strip().splitlines()
    assert errors == [f"{broken}:2:16: unexpected '@'; expected one of '[', 'not', '}}', a name, a quoted string",
                      f"{also}:2:1: unexpected 'foo'; expected 'precondition'"]
    assert "social_navigation" in result.stdout


def test_grammar_check_json(tmp_path: Path) -> None:
    broken = tmp_path / "b.aggl"
    broken.write_text("name=x\n===\nr : active(1) { { } => { }\n")
    result = runner.invoke(app, ["grammar", "check", "--json", str(broken)])
    assert result.exit_code == 1
    payload = json.loads(result.stdout)
    assert payload["ok"] is False and payload["files"][0]["line"] == 3


def write_graph(tmp_path: Path) -> Path:
    graph = graph_from_mapping(
        {"hall": {"type": "room"}, "gym": {"type": "room"}, "lounge": {"type": "room"}, "d1": {"type": "door"},
         "d2": {"type": "door"}, "robot": {"type": "omnirobot"}},
        [("hall", "gym", "connected", {"door": "d1"}), ("gym", "lounge", "connected", {"door": "d2"}),
         ("robot", "hall", "in")])
    path = tmp_path / "centre.json"
    path.write_text(json.dumps(nx.node_link_data(graph, edges="links")))
    return path


def test_plan_prints_steps_with_bindings(tmp_path: Path) -> None:
    scene = write_graph(tmp_path)
    result = runner.invoke(app, ["plan", str(scene), "--mission", "room:lounge"])
    assert result.exit_code == 0, result.output
    lines = result.stdout.strip().splitlines()
    assert lines[0].startswith("plan for 'room:lounge': 2 step(s), cost 2")
    assert lines[1].split() == ["1.", "changeRoom", "robot=robot", "r1=hall", "r2=gym", "d=d1"]
    assert lines[2].split() == ["2.", "changeRoom", "robot=robot", "r1=gym", "r2=lounge", "d=d2"]


def test_plan_json_and_no_plan_and_errors(tmp_path: Path) -> None:
    scene = write_graph(tmp_path)
    result = runner.invoke(app, ["plan", str(scene), "-m", "room:gym", "--json"])
    assert result.exit_code == 0
    payload = json.loads(result.stdout)
    assert payload["found"] and payload["cost"] == 1
    bindings = {"robot": "robot", "r1": "hall", "r2": "gym", "d": "d1"}
    assert payload["steps"] == [{"rule": "changeRoom", "cost": 1.0, "bindings": bindings, "hierarchical": False,
                                 "agm_bindings": bindings}]
    assert payload["agm_plan"] == ["changeRoom@{'robot': 'robot', 'r1': 'hall', 'r2': 'gym', 'd': 'd1'}"]
    missing = runner.invoke(app, ["plan", str(scene), "-m", "room:attic", "--json"])
    assert missing.exit_code == 1 and json.loads(missing.stdout)["found"] is False
    assert "no node named 'attic'" in missing.stderr
    bad = runner.invoke(app, ["plan", str(scene), "-m", "fly:attic"])
    assert bad.exit_code == 2 and "unknown mission kind 'fly'" in bad.stderr
    broken_grammar = tmp_path / "g.aggl"
    broken_grammar.write_text("rule {")
    bad_grammar = runner.invoke(app, ["plan", str(scene), "-m", "room:gym", "--grammar", str(broken_grammar)])
    assert bad_grammar.exit_code == 2 and bad_grammar.stderr.startswith(f"{broken_grammar}:1:6:")


def test_plan_on_a_shipped_scene_at_a_time_of_day() -> None:
    scene = Path(__file__).resolve().parents[2] / "scenes" / "center_a.yaml"
    if not scene.exists():
        pytest.skip("scenes/center_a.yaml not in this checkout")
    result = runner.invoke(app, ["plan", str(scene), "-m", "room:dining_room", "--at", "10:30", "--json"])
    assert result.exit_code == 0, result.output
    steps = json.loads(result.stdout)["steps"]
    assert steps and steps[-1]["rule"] == "changeRoom" and steps[-1]["bindings"]["r2"] == "dining_room"
    bad_time = runner.invoke(app, ["plan", str(scene), "-m", "room:dining_room", "--at", "25:00"])
    assert bad_time.exit_code == 2 and "--at: '25:00' is not a valid clock time" in bad_time.stderr


def test_no_plan_names_the_blocking_rule_condition_and_facts(tmp_path: Path) -> None:
    """Issue 11 item 4: an object whose interaction space is in use says who uses it."""
    graph = graph_from_mapping(
        {"hall": {"type": "room"}, "gym": {"type": "room"}, "d1": {"type": "door"}, "robot": {"type": "omnirobot"},
         "ot_table": {"type": "object"}, "resident_3": {"type": "person", "role": "resident"}},
        [("hall", "gym", "connected", {"door": "d1"}), ("robot", "hall", "in"), ("ot_table", "gym", "in"),
         ("resident_3", "gym", "in"), ("resident_3", "ot_table", "interacting")])
    world = tmp_path / "busy.json"
    world.write_text(json.dumps(nx.node_link_data(graph, edges="links")))
    result = runner.invoke(app, ["plan", str(world), "-m", "object:ot_table"])
    assert result.exit_code == 1
    lines = result.stderr.splitlines()
    assert lines[0].startswith("no plan for 'object:ot_table': no sequence of rules reaches the target")
    assert "  never reached: robot -near-> ot_table" in lines
    blocked = [line for line in lines if line.startswith("  blocked: ")]
    assert blocked[0].startswith("  blocked: goToObject(robot=robot, o=ot_table): where not exists { p:person  "
                                 "p->o(interacting) } (")
    assert blocked[0].endswith("fails: resident_3 -interacting-> ot_table")
    payload = json.loads(runner.invoke(app, ["plan", str(world), "-m", "object:ot_table", "--json"]).stdout)
    blocker = payload["diagnosis"]["blockers"][0]
    assert blocker["rule"] == "goToObject" and blocker["focus"] == {"robot": "robot", "o": "ot_table"}
    assert blocker["pos"]["file"].endswith("social_navigation.aggl") and blocker["pos"]["line"] > 0
    assert blocker["witnesses"] == [{"var": "p", "node": "resident_3", "type": "person", "attrs": {}}]
    assert payload["diagnosis"]["unmet"] == ["robot -near-> ot_table"]
