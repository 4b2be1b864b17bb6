"""Real AGM grammars and worlds that AGM loads, read as AGM reads them, through the CLI a
RoboComp user types: a stray ')' after a formula, a rule redefined across an include, an include
that is not found, a world with a <link> left open."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from grammar.errors import GrammarError
from grammar.parser import load_grammar, parse_grammar
from tests.support import REPO_ROOT
from tools.cli import app

DATA = REPO_ROOT / "tests" / "data" / "aggl"
runner = CliRunner()


def run(*args: str, env: dict[str, str] | None = None):
    return runner.invoke(app, list(args), env=env)


# ----------------------------------------------------------------------------- stray ')'
def test_a_stray_parenthesis_after_a_formula_is_read_as_agm_reads_it_with_a_warning() -> None:
    grammar = str(DATA / "stray_paren.aggl")
    checked = run("grammar", "check", grammar)
    assert checked.exit_code == 0, checked.output
    assert f"{grammar}:30:3: warning: stray ')' after the effect's formula" in checked.stderr
    # the formula before it is kept: the effect removes the 'frio' link the target wants gone
    plan = run("plan", "--world", str(DATA / "kitchen_world.xml"), "--target", str(DATA / "hot_not_cold.aggt"),
               "--grammar", grammar, "--json")
    assert plan.exit_code == 0, plan.output
    assert [line.split("@")[0] for line in json.loads(plan.stdout)["agm_plan"]] == ["calentar"]
    assert f"{grammar}:30:3: warning: stray ')'" in plan.stderr
    strict = run("grammar", "check", "--strict", grammar)
    assert strict.exit_code == 1
    assert f"{grammar}:30:3: stray ')' after the effect's formula" in strict.stderr
    assert "[strict check: warnings are errors]" in strict.stderr


def test_stray_parentheses_in_targets_and_what_stays_refused() -> None:
    from grammar.parser import parse_target

    target = parse_target("{ 1:robot a:room }\nprecondition { (in 1 a) ) }\n", "t.aggt")
    assert [str(w) for w in target.warnings] == [
        "t.aggt:2:25: warning: stray ')' after the precondition's formula, ignored as AGM ignores it (AGM "
        "reads one formula and skips the rest); remove it ('grammar check --strict' refuses it)"]
    with pytest.raises(GrammarError, match="unexpected '\\)' in an empty effect") as err:
        parse_grammar("name=x\n===\nr : active(1) { { } => { } effect { ) } }\n", "e.aggl")
    assert (err.value.line, err.value.column) == (3, 37)
    with pytest.raises(GrammarError, match="unexpected '\\('") as err:  # a formula after it is refused
        parse_grammar("name=x\n===\nr : active(1) { { a:t } => { a:t } effect { (in a a) ) (on a a) } }\n")
    assert (err.value.line, err.value.column) == (3, 56)


# ----------------------------------------------------------------------------- redefinition across an include
def test_a_rule_redefined_after_its_include_replaces_it_as_in_agm() -> None:
    grammar = DATA / "redefine" / "domain_specific.aggl"
    checked = run("grammar", "check", str(grammar), "--json")
    assert checked.exit_code == 0, checked.output
    info = json.loads(checked.stdout)["files"][0]
    assert info["rules"] == 1 and info["includes"] == 1
    included = (DATA / "redefine" / "domain_navigation.aggl").resolve()
    assert info["warnings"] == [f"{grammar}:6:1: warning: rule 'changeRoom' is defined again here; AGM uses "
                                f"the later definition, so this one replaces the one at {included}:3:1"]
    # the world has an omnirobot between locations: only the including file's changeRoom applies
    plan = run("plan", "--world", str(DATA / "redefine" / "locations.xml"),
               "--target", str(DATA / "redefine" / "robot_in_3.aggt"), "--grammar", str(grammar), "--json")
    assert plan.exit_code == 0, plan.output
    assert json.loads(plan.stdout)["agm_plan"] == ["changeRoom@{'robot': '1', 'r1': '2', 'r2': '3'}"]
    assert "is defined again here" in plan.stderr
    assert run("grammar", "check", "--strict", str(grammar)).exit_code == 1


def test_an_include_after_a_definition_wins_and_one_file_twice_is_no_conflict(tmp_path: Path) -> None:
    (tmp_path / "nav.aggl").write_text((DATA / "redefine" / "domain_navigation.aggl").read_text())
    (tmp_path / "also.aggl").write_text("name=also\n===\ninclude(nav.aggl)\n")
    main = tmp_path / "main.aggl"
    main.write_text("name=main\n===\nchangeRoom : active(5) { { } => { } }\ninclude(nav.aggl)\ninclude(also.aggl)\n")
    grammar = load_grammar(main)
    assert [(r.name, r.cost, r.pos.file) for r in grammar.rules] == [("changeRoom", 1.0, str(tmp_path / "nav.aggl"))]
    assert len(grammar.warnings) == 1 and str(grammar.warnings[0]).startswith(f"{tmp_path / 'nav.aggl'}:3:1: warning")
    assert f"replaces the one at {main}:3:1" in str(grammar.warnings[0])
    # two definitions in one file stay an error: a mistake, not a reuse
    with pytest.raises(GrammarError, match="defined twice"):
        parse_grammar("name=x\n===\nr : active(1) { { } => { } }\nr : active(2) { { } => { } }\n")


# ----------------------------------------------------------------------------- include not found
def test_an_include_not_found_is_quoted_whole(tmp_path: Path) -> None:
    path = "/home/robocomp/robocomp/components/robocomp-ursus-rockin/etc/planning/domain_navigation.aggl"
    grammar = tmp_path / "g.aggl"
    grammar.write_text(f"name=g\n===\ninclude({path})\n")
    result = run("grammar", "check", str(grammar), env={"AGGLPATH": "/opt/agm_a;/opt/agm_b"})
    assert result.exit_code == 1
    assert f"{grammar}:3:9: included file '{path}' not found (looked at: {path}; " in result.stderr
    assert f"/opt/agm_b{path}); set AGGLPATH" in result.stderr
    assert "…" not in result.stderr


# ----------------------------------------------------------------------------- world with an open <link>
@pytest.mark.parametrize("after,where,message", [
    ('\t<link src="2" dst="1" label="has" />\n</AGMModel>\n', "5:2",
     "<link> inside <link src=\"1\" dst=\"2\" label=\"in\"> opened at line 4: that <link> is not closed"),
    ("</AGMModel>\n", "5:3",
     "not well-formed XML (mismatched tag): <link src=\"1\" dst=\"2\" label=\"in\"> opened at line 4 is not closed"),
    ("", "5:1",
     "not well-formed XML (no element found): <link src=\"1\" dst=\"2\" label=\"in\"> opened at line 4 is not closed"),
])
def test_a_link_left_open_in_a_world_is_named_with_its_line(tmp_path: Path, after: str, where: str,
                                                            message: str) -> None:
    world = tmp_path / "world.xml"
    world.write_text('<AGMModel>\n\t<symbol id="1" type="robot" />\n\t<symbol id="2" type="room" />\n'
                     f'\t<link src="1" dst="2" label="in">\n{after}')
    result = run("plan", "--world", str(world), "--target", str(DATA / "robot_in_3.aggt"),
                 "--grammar", str(DATA / "teleport.aggl"))
    assert result.exit_code == 2
    assert f"{world}:{where}: {message}" in result.stderr


# ----------------------------------------------------------------------------- where chronav reads AGM differently
def test_a_right_hand_side_absent_link_on_a_new_symbol_stays_absent_and_is_warned_about(tmp_path: Path) -> None:
    """robocomp-shelly's GraspMug shape: AGM adds ``o->r(reach)*`` as a real link; chronav does not."""
    grammar = tmp_path / "see.aggl"
    grammar.write_text("name=see\n===\nsee : active(1)\n{\n\t{\n\t\tr:robot\n\t}\n\t=>\n\t{\n\t\tr:robot\n"
                       "\t\to:object\n\t\tr->o(know)\n\t\to->r(reach)*\n\t}\n}\n")
    world = tmp_path / "w.xml"
    world.write_text('<AGMModel>\n\t<symbol id="1" type="robot" />\n</AGMModel>\n')
    checked = run("grammar", "check", str(grammar))
    assert checked.exit_code == 0
    assert (f"{grammar}:13:3: warning: rule 'see': right-hand-side link o->r(reach)* is read as 'this link "
            "is absent'") in checked.stderr
    for wanted, found in (("x->1(reach)", False), ("1->x(know)\n\tx->1(reach)*", True)):
        target = tmp_path / "t.aggt"
        target.write_text(f"{{\n\t1:robot\n\tx:object\n\t{wanted}\n}}\n")
        result = run("plan", "--world", str(world), "--target", str(target), "--grammar", str(grammar),
                     "--max-expansions", "20", "--json")  # 'see' applies forever: a short search says enough
        assert (result.exit_code == 0) == found, result.output
