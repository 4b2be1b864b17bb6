"""RoboComp AGM compatibility through the CLI a RoboComp user types: rule heads read as AGM's
parser reads them, includes found under AGGLPATH, hierarchical rules planned and expanded as
AGM's planner does, worlds exchanged in AGM's XML, plans printed in AGM's plan-file form."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from grammar.agm_world import agm_world_xml, load_agm_world, parse_agm_world
from grammar.errors import GrammarError
from grammar.parser import parse_grammar
from tests.support import REPO_ROOT
from tools.cli import app

DATA = REPO_ROOT / "tests" / "data" / "aggl"
CORPUS = REPO_ROOT.parent / "shared" / "corpus" / "aggl"
runner = CliRunner()


def corpus(name: str) -> Path:
    if not CORPUS.is_dir():
        pytest.skip(f"AGM corpus not found at {CORPUS}")
    return CORPUS / name


def run(*args: str, env: dict[str, str] | None = None) -> object:
    return runner.invoke(app, list(args), env=env)


# ----------------------------------------------------------------------------- rule heads
@pytest.mark.parametrize("head,name,dormant,hierarchical", [
    ("hierarchicalFoo", "hierarchicalFoo", False, False),         # an ordinary rule for AGM
    ("hierarchical hierarchicalFoo", "hierarchicalFoo", False, True),
    ("hierarchical Foo", "Foo", False, True),
    ("dormant dormantFoo", "dormantFoo", True, False),
    ("DormantFoo", "Foo", True, False),                           # caseless keyword, prefix match
    ("Dormant foo", "foo", True, False),
    ("dormantX", "X", True, False),
    ("dormant hierarchical foo", "foo", True, True),
    ("hierarchical dormant foo", "foo", True, True),
    ("include", "include", False, False),                         # not a reserved word in a head
])
def test_rule_heads_are_read_as_agm_reads_them(head: str, name: str, dormant: bool, hierarchical: bool) -> None:
    g = parse_grammar(f"name=x\n===\n{head} : active(1)\n{{\n\t{{ }}\n\t=>\n\t{{ }}\n}}\n", "heads.aggl")
    rule = g.rules[0]
    assert (rule.name, rule.dormant, rule.hierarchical) == (name, dormant, hierarchical)
    glued = head.split()[0].lower().startswith("dormant") and head.split()[0].lower() != "dormant"
    assert bool(g.warnings) == glued, g.warnings


@pytest.mark.parametrize("head", ["Hierarchical foo", "dormant", "a b"])
def test_rule_heads_agm_cannot_read_are_located_errors(head: str) -> None:
    with pytest.raises(GrammarError, match="cannot read rule head") as err:
        parse_grammar(f"name=x\n===\n{head} : active(1) {{ {{ }} => {{ }} }}\n", "heads.aggl")
    assert (err.value.line, err.value.column) == (3, 1)


def test_grammar_check_reads_real_style_heads_and_warns_about_glued_keywords() -> None:
    result = run("grammar", "check", str(DATA / "hierarchical_names.aggl"), "--json")
    assert result.exit_code == 0, result.output
    info = json.loads(result.stdout)["files"][0]
    assert info["rules"] == 5 and info["hierarchical"] == 1
    assert "'DormantSleep' is read as the dormant rule 'Sleep'" in result.stderr
    text = run("grammar", "check", str(DATA / "hierarchical_names.aggl"))
    assert "5 rules, 1 hierarchical" in text.stdout


def test_grammar_check_summary_mentions_combo_rules(tmp_path: Path) -> None:
    combo = tmp_path / "combo.aggl"
    combo.write_text("name=c\n===\nr : active(1) { { } => { } }\nboth : active(2) { r as a  r as b where: a.x = b.x }\n")
    result = run("grammar", "check", str(combo))
    assert result.exit_code == 0 and "1 combo rules (parsed, not planned" in result.stdout


# ----------------------------------------------------------------------------- includes
def test_absolute_includes_are_found_under_agglpath_and_can_be_skipped() -> None:
    grammar = str(DATA / "includes_absolute.aggl")
    missing = run("grammar", "check", grammar, env={"AGGLPATH": ""})
    assert missing.exit_code == 1
    assert "included file '/home/luis/robocomp/grammars/common_rules.aggl' not found" in missing.stderr
    assert "set AGGLPATH" in missing.stderr
    found = run("grammar", "check", grammar, "--json", env={"AGGLPATH": f"/nonexistent;{DATA / 'agglpath'}"})
    assert found.exit_code == 0, found.output
    info = json.loads(found.stdout)["files"][0]
    assert info["rules"] == 2 and info["includes"] == 1
    alone = run("grammar", "check", grammar, "--no-includes", env={"AGGLPATH": ""})
    assert alone.exit_code == 0 and "1 rules" in alone.stdout and "1 includes not read" in alone.stdout


def test_absolute_includes_are_found_under_the_working_directory(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(DATA / "agglpath")
    monkeypatch.delenv("AGGLPATH", raising=False)
    result = run("grammar", "check", str(DATA / "includes_absolute.aggl"))
    assert result.exit_code == 0, result.output


# ----------------------------------------------------------------------------- hierarchical planning
def test_hierarchical_step_is_planned_and_expanded_like_agm() -> None:
    args = ["plan", "--world", str(DATA / "fetch_world.xml"), "--target", str(DATA / "fetch_milk.aggt"),
            "--grammar", str(DATA / "fetch_domain.aggl")]
    result = run(*args)
    assert result.exit_code == 0, result.output
    lines = result.stdout.splitlines()
    assert lines[1].split() == ["1.", "*fetchMilk", "robot=1", "o=5"]
    assert "expands into (3 step(s), cost 3):" in lines[2]
    agm = lines[lines.index("AGM plan:") + 1:]
    assert [line.strip() for line in agm] == [
        "changeRoom@{'robot': '1', 'r1': '2', 'r2': '3'}",
        "changeRoom@{'robot': '1', 'r1': '3', 'r2': '4'}",
        "pick@{'robot': '1', 'r': '4', 'o': '5'}",
        "#!*fetchMilk@{'robot': '1', 'o': '5'}",
    ]
    payload = json.loads(run(*args, "--json").stdout)
    step = payload["steps"][0]
    assert step["hierarchical"] and step["rule"] == "fetchMilk"
    assert [s["rule"] for s in step["expansion"]] == ["changeRoom", "changeRoom", "pick"]
    assert payload["agm_plan"][-1] == "#!*fetchMilk@{'robot': '1', 'o': '5'}"


def test_one_rule_grammar_plain_and_hierarchical() -> None:
    world, target = str(DATA / "two_rooms.xml"), str(DATA / "robot_in_3.aggt")
    plain = run("plan", "--world", world, "--target", target, "--grammar", str(DATA / "teleport.aggl"), "--json")
    assert plain.exit_code == 0 and json.loads(plain.stdout)["agm_plan"] == ["teleport@{'robot': '1', 'a': '2', 'b': '3'}"]
    # hierarchical: AGM plans the step, then expands it without the rule itself: nothing left to
    # reach the sub-target, so AGM reports no plan, and so does chronav, saying why
    hier = run("plan", "--world", world, "--target", target, "--grammar", str(DATA / "teleport_hierarchical.aggl"))
    assert hier.exit_code == 1
    assert "starts with hierarchical step teleport(robot=1, a=2, b=3) but its expansion failed" in hier.stderr


# ----------------------------------------------------------------------------- the shared corpus
@pytest.mark.parametrize("grammar,world,target,expected", [
    ("change_roomViriato2.aggl", "world_viriato.xml", "targetGoToKitchen_Viriato.aggt",
     ["goToPerson@{'p': '70', 'robot': '200'}", "takeTheAttention@{'p': '70', 'robot': '200'}",
      "askForIndividualPermission@{'p': '70', 'robot': '200'}",
      "changeRoom@{'robot': '200', 'room1': '58', 'room2': '59'}",
      "changeRoom@{'robot': '200', 'room1': '59', 'room2': '60'}"]),
    ("change_room4.aggl", "world_change_room4.xml", "target_robot_in_4.aggt",
     ["changeRoom@{'robot': '1', 'room1': '2', 'room2': '3'}", "changeRoom@{'robot': '1', 'room1': '3', 'room2': '4'}"]),
    ("domain_navigation.aggl", "world_domain_navigation.xml", "target_robot_in_4.aggt",
     ["changeRoom@{'robot': '1', 'r1': '2', 's1': '5', 'r2': '3', 's2': '6'}",
      "changeRoom@{'robot': '1', 'r1': '3', 's1': '6', 'r2': '4', 's2': '7'}"]),
])
def test_corpus_grammars_plan_on_agm_worlds(grammar: str, world: str, target: str, expected: list[str]) -> None:
    target_path = corpus(target) if (CORPUS / target).exists() else DATA / target
    result = run("plan", "--world", str(DATA / world), "--target", str(target_path),
                 "--grammar", str(corpus(grammar)), "--json")
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout)["agm_plan"] == expected


def test_every_corpus_file_checks() -> None:
    files = sorted(str(p) for p in corpus(".").glob("*.agg[lt]"))
    result = run("grammar", "check", *files)
    assert result.exit_code == 0, result.output
    assert f"{len(files)} file(s) OK" in result.stdout


# ----------------------------------------------------------------------------- worlds
def test_world_xml_round_trip_keeps_symbols_links_attributes_and_disabled_links(tmp_path: Path) -> None:
    world = load_agm_world(DATA / "fetch_world.xml")
    assert world.symbols["5"].attrs == {"name": "milk", "imName": "milk_carton"}
    assert [l.enabled for l in world.links] == [True, True, True, False, True]
    written = agm_world_xml(world.to_networkx(include_disabled=True))
    again = parse_agm_world(written, "again.xml")
    assert again.symbols == world.symbols
    assert sorted((l.src, l.dst, l.label, l.enabled, tuple(l.attrs.items())) for l in again.links) == \
        sorted((l.src, l.dst, l.label, l.enabled, tuple(l.attrs.items())) for l in world.links)
    assert agm_world_xml(again.to_networkx(include_disabled=True)) == written
    graph = world.to_networkx()  # what the planner sees: the disabled link is not there
    assert not graph.has_edge("4", "3") and graph.nodes["5"]["agm:name"] == "milk"
    assert graph.edges["3", "4", "door"]["width"] == "0.9"


def test_world_type_mismatch_is_named(tmp_path: Path) -> None:
    world = tmp_path / "upper.xml"
    world.write_text('<AGMModel>\n<symbol id="1" type="ROBOT"/>\n<symbol id="2" type="room"/>\n'
                     '<symbol id="3" type="room"/>\n<link src="1" dst="2" label="in"/>\n</AGMModel>\n')
    result = run("plan", "--world", str(world), "--target", str(DATA / "robot_in_3.aggt"),
                 "--grammar", str(DATA / "teleport.aggl"))
    assert result.exit_code == 1
    assert "the target needs '1' to be a 'robot', but that world node is a 'ROBOT' (the names differ only " \
           "in case)" in result.stderr


def test_plan_arguments_must_be_one_form_or_the_other() -> None:
    assert run("plan", "--world", str(DATA / "two_rooms.xml")).exit_code == 2
    bad = run("plan", "x.yaml", "-m", "room:a", "--world", str(DATA / "two_rooms.xml"),
              "--target", str(DATA / "robot_in_3.aggt"))
    assert bad.exit_code == 2 and "give no SCENE" in bad.stderr
    assert "give SCENE --mission M" in run("plan").stderr


def test_nested_hierarchical_steps_expand_recursively() -> None:
    from grammar import parse_target, plan
    from grammar.world import graph_from_mapping

    g = parse_grammar('''
        rule walk { lhs { r:robot a:room b:room  r->a(in) a->b(door) } rhs { r:robot a:room b:room  r->b(in) a->b(door) } }
        rule pick cost 2 { lhs { r:robot x:room o:object  r->x(in) o->x(in) } rhs { r:robot x:room o:object  r->x(in) r->o(holds) } }
        rule give { lhs { r:robot o:object p:person x:room  r->o(holds) r->x(in) p->x(in) }
                    rhs { r:robot o:object p:person x:room  r->x(in) p->o(holds) } }
        rule fetch hierarchical { lhs { r:robot o:object } rhs { r:robot o:object  r->o(holds) } }
        rule serve hierarchical { lhs { r:robot o:object p:person } rhs { r:robot o:object p:person  p->o(holds) } }
    ''', "serve.aggl")
    world = graph_from_mapping({"1": {"type": "robot"}, "2": {"type": "room"}, "3": {"type": "room"},
                                "4": {"type": "object"}, "5": {"type": "person"}},
                               [("1", "2", "in"), ("2", "3", "door"), ("4", "2", "in"), ("5", "2", "in")])
    result = plan(g, world, parse_target("{ 4:object 5:person 5->4(holds) }", "t.aggt"))
    assert result.found and [s.rule for s in result.steps] == ["serve"]
    serve = result.steps[0].expansion
    assert serve is not None and [s.rule for s in serve.steps] == ["fetch", "give"]  # cheaper than pick
    assert [s.rule for s in result.flat_steps()] == ["pick", "give"]
    assert result.agm_lines() == ["pick@{'r': '1', 'x': '2', 'o': '4'}", "#!*fetch@{'r': '1', 'o': '4'}",
                                  "give@{'r': '1', 'o': '4', 'x': '2', 'p': '5'}",
                                  "#!*serve@{'r': '1', 'o': '4', 'p': '5'}"]
