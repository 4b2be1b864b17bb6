"""Parsing grammar and target files of both dialects, and the errors of broken ones."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from grammar.errors import GrammarError
from grammar.model import (
    AttrRef,
    Compare,
    Exists,
    FAnd,
    FForall,
    FLink,
    FNot,
    FWhen,
    Literal,
    Not,
)
from grammar.parser import default_grammar_path, detect_dialect, load_grammar, load_target, parse_grammar, parse_target
from tests.support import REPO_ROOT

CORPUS = REPO_ROOT.parent / "shared" / "corpus" / "aggl"


def corpus(name: str) -> Path:
    path = CORPUS / name
    if not CORPUS.is_dir():
        pytest.skip(f"AGM corpus not found at {CORPUS}")
    return path


# ----------------------------------------------------------------------------- real AGM files
def test_corpus_change_room4_parses_with_negated_links_and_forall_preconditions() -> None:
    g = load_grammar(corpus("change_room4.aggl"))
    assert g.dialect == "agm" and g.name == "change_room4"
    assert g.properties["fontName"] == "Arial"
    assert [r.name for r in g.rules] == ["askForGroupalPermission", "askForIndividualPermission", "changeRoom",
                                         "goToGroupOfPeople", "goToPerson", "takeTheAttention"]
    assert set(g.types.parents) == {"person", "robot", "room"}
    change = g.rule("changeRoom")
    blocked = [l for l in change.lhs.links if l.label == "blocked"]
    assert blocked and blocked[0].negated and blocked[0].src == blocked[0].dst == "robot"
    assert {(l.src, l.dst, l.label) for l in change.added_links} == {("robot", "room2", "in")}
    assert {(l.src, l.dst, l.label) for l in change.removed_links} == {("robot", "room1", "in")}
    pre = g.rule("askForGroupalPermission").precondition
    assert isinstance(pre, FForall) and pre.vars[0].name == "otherp" and pre.vars[0].type == "person"
    assert isinstance(pre.body, FWhen) and isinstance(pre.body.then, FLink)
    attention = g.rule("takeTheAttention")
    assert [(l.src, l.dst, l.label) for l in attention.added_links] == [("p", "robot", "front")]


def test_corpus_viriato_parses_and_keeps_the_and_precondition() -> None:
    g = load_grammar(corpus("change_roomViriato2.aggl"))
    assert g.name == "change_room2" and len(g.rules) == 4
    pre = g.rule("changeRoom").precondition
    assert isinstance(pre, FAnd) and len(pre.items) == 3
    assert g.rule("goToPerson").precondition is None  # a precondition block holding only blank lines


def test_corpus_domain_navigation_without_types_section_and_with_passive_rules() -> None:
    g = load_grammar(corpus("domain_navigation.aggl"))
    assert dict(g.types.parents) == {}
    assert {r.name: r.active for r in g.rules}["unsetStop"] is False
    assert g.rule("reachPose").cost == 3
    assert g.rule("setStop").lhs.node("1").type == "robot"  # names made of digits
    effect = g.rule("changeRoom").effect
    assert isinstance(effect, FForall) and isinstance(effect.body, FWhen)
    then = effect.body.then
    assert isinstance(then, FAnd) and isinstance(then.items[0], FNot)


def test_corpus_target_has_digit_constants() -> None:
    t = load_target(corpus("targetGoToKitchen_Viriato.aggt"))
    assert [(n.name, n.type, n.constant) for n in t.pattern.nodes] == [("200", "omnirobot", "200"),
                                                                      ("60", "room", "60")]
    assert [(l.src, l.dst, l.label) for l in t.pattern.links] == [("200", "60", "in")]


# ----------------------------------------------------------------------------- AGM constructs
AGM_HEAD = "name=test\nfontSize=14\n===\n"


def test_agm_one_line_rule_flags_and_types_inheritance() -> None:
    text = AGM_HEAD + (
        "types\n{\n(thing)\n(robot person : thing)\n(omnirobot : robot)\n}\n===\n"
        "r:active(1){{v:robot(0,0)}=>{v:robot(0,0)}precondition{}}\n"
        "dormant hierarchical h : passive(2) success(0.7) activates(r, r) { { } => { } }\n"
        "x : active(1) { { a:thing\n b:thing\n a->b(!on)\n a->a(self)* } => { a:thing } parameters { p:person } "
        "precondition { } effect { (delete b) } }\n"
    )
    g = parse_grammar(text, "t.aggl")
    assert g.types.is_subtype("omnirobot", "thing") and not g.types.is_subtype("thing", "robot")
    h = g.rule("h")
    assert h.dormant and h.hierarchical and not h.active and h.success == 0.7 and h.activates == ("r", "r")
    x = g.rule("x")
    assert x.deleted_nodes == ("b",) and x.parameters[0].type == "person"
    assert [(l.label, l.negated) for l in x.lhs.links] == [("on", False), ("self", True)]


def test_agm_negative_cost_is_refused_with_position() -> None:
    with pytest.raises(GrammarError) as err:
        parse_grammar(AGM_HEAD + "x : active(-1) { { } => { } }\n", "neg.aggl")
    assert (err.value.line, err.value.column) == (4, 1) and "negative" in err.value.message


def test_agm_combo_rules_and_includes_relative_to_the_including_file(tmp_path: Path) -> None:
    sub = tmp_path / "my dir"
    sub.mkdir()
    (sub / "base.aggl").write_text(AGM_HEAD + "baseRule : active(1) { { a:room } => { a:room } }\n")
    main = tmp_path / "main.aggl"
    main.write_text(AGM_HEAD + "include(my dir/base.aggl)\n"
                    "combo : active(3) { baseRule as b1\n baseRule as b2 optional\n where: b1.a = b2.a }\n"
                    "# a comment line\nlocal : active(1) { { } => { } } # trailing comment (accepted)\n")
    g = load_grammar(main)
    assert [r.name for r in g.rules] == ["baseRule", "local"]
    assert g.combos[0].atoms[1].optional and g.combos[0].equivalences == ((("b1", "a"), ("b2", "a")),)
    assert str((sub / "base.aggl").resolve()) in g.includes


def test_include_cycle_is_an_error(tmp_path: Path) -> None:
    (tmp_path / "a.aggl").write_text('include "b.aggl"\n')
    (tmp_path / "b.aggl").write_text('include "a.aggl"\n')
    with pytest.raises(GrammarError, match="include cycle"):
        load_grammar(tmp_path / "a.aggl")


def test_dialect_detection() -> None:
    assert detect_dialect("# c\n\nname=x\n===") == "agm"
    assert detect_dialect("grammar x\n") == "native"
    assert detect_dialect("rule r { lhs { } rhs { } }") == "native"


# ----------------------------------------------------------------------------- native dialect
NATIVE = '''
grammar demo   # comments anywhere
types {
    entity
    room, door : entity
    robot : entity
    (omnirobot : robot)
}
rule move cost 2.5 {
    lhs {
        robot:robot  a:room  b:room  d:door
        robot->a(in)
        a--b(connected) [door == d.name]
        not robot->b(blocked)
    }
    rhs { robot:robot a:room b:room d:door robot->b(in) a--b(connected) }
    where d.open != false and not exists { x:room  x->b(busy) }
    unless { "kitchen":room  b->kitchen(part_of) }
    set robot.last_door = d.name
}
'''


def test_native_rule_model() -> None:
    g = parse_grammar(NATIVE, "demo.aggl")
    assert g.name == "demo" and g.dialect == "native"
    assert g.types.is_subtype("omnirobot", "entity")
    move = g.rule("move")
    assert move.cost == 2.5 and move.active
    connected = [l for l in move.lhs.links if l.label == "connected"][0]
    assert connected.undirected
    assert connected.conditions == (Compare("==", AttrRef(None, "door"), AttrRef("d", "name")),)
    blocked = [l for l in move.lhs.links if l.label == "blocked"][0]
    assert blocked.negated
    assert len(move.where) == 2 and isinstance(move.where[1], Not) and isinstance(move.where[1].expr, Exists)
    kitchen = move.where[1].expr.pattern.node("kitchen")
    assert kitchen is not None and kitchen.constant == "kitchen"
    assert move.assignments[0].var == "robot" and move.assignments[0].attr == "last_door"
    assert [(l.src, l.label) for l in move.added_links] == [("robot", "in")]


def test_native_target() -> None:
    t = parse_target('target { "a1":activity [state == "finished"] } where a1.room != none', "t.aggt")
    node = t.pattern.nodes[0]
    assert node.constant == "a1" and node.conditions == (Compare("==", AttrRef(None, "state"), Literal("finished")),)
    assert len(t.where) == 1


def test_shipped_grammar_parses_with_all_required_rules() -> None:
    g = load_grammar(default_grammar_path())
    names = {r.name for r in g.rules}
    assert {"changeRoom", "goToObject", "approachPerson", "takeTheAttention", "waitFor"} <= names
    assert g.types.is_subtype("omnirobot", "robot")


# ----------------------------------------------------------------------------- broken files
BROKEN = [
    # (name, text, line, column, fragment of the message)
    ("missing_brace.aggl", AGM_HEAD + "r : active(1)\n{\n\t{\n\t\ta:b\n\t=>\n\t{ }\n}\n", 8, 2,
     "unexpected '=>'"),
    ("float_cost.aggl", AGM_HEAD + "r : active(1.5) { { } => { } }\n", 4, 13, "expected ')'"),
    ("bad_mode.aggl", AGM_HEAD + "r : actif(1) { { } => { } }\n", 4, 5, "'active' or 'passive'"),
    ("bad_head.aggl", AGM_HEAD + "Hierarchical foo : active(1) { { } => { } }\n", 4, 1, "cannot read rule head"),
    ("link_first.aggl", AGM_HEAD + "r : active(1) {\n{ a->b(in)\n a:b }\n=>\n{ }\n}\n", 6, 3, "expected '->'"),
    ("no_header_end.aggl", "name=x\nr : active(1) { { } => { } }\n", 2, 3, "expected '='"),
    ("truncated.aggl", AGM_HEAD + "r : active(1)\n{\n{ }\n=>\n", 7, 3, "unexpected end of file"),
    ("two_formulas.aggl", AGM_HEAD + "r : active(1) {\n { a:b } => { a:b }\n precondition { (in a a)\n (on a a) }\n}\n",
     7, 3, "(and ...)"),
    ("unknown_parent.aggl", "name=x\n===\ntypes\n{\n(a : b)\n}\n===\nr : active(1) { { } => { } }\n", 5, 1,
     "not declared earlier"),
    ("undeclared_link.aggl", "rule r {\n  lhs { a:room }\n  rhs { a:room b->a(in) }\n}\n", 3, 16, "undeclared node 'b'"),
    ("bad_char.aggl", "rule r {\n  lhs { a:room @ }\n  rhs { }\n}\n", 2, 16, "unexpected '@'"),
    ("no_rhs.aggl", "rule r {\n  lhs { a:room }\n}\n", 1, 6, "no 'rhs' section"),
    ("unknown_var.aggl", "rule r {\n  lhs { a:room }\n  rhs { a:room }\n  where b.x == 1\n}\n", 4, 9,
     "unknown variable 'b'"),
    ("effect_or.aggl", "rule r {\n  lhs { a:room }\n  rhs { a:room }\n  effect { (or (in a a) (on a a)) }\n}\n",
     4, 17, "(or ...)"),
    ("dup_rule.aggl", "rule r { lhs { } rhs { } }\n\nrule r { lhs { } rhs { } }\n", 3, 6, "defined twice"),
    ("rhs_condition.aggl", "rule r {\n  lhs { a:room }\n  rhs { a:room [x == 1] }\n}\n", 3, 9, "left-hand side"),
    ("missing_include.aggl", 'grammar g\ninclude "nope.aggl"\n', 2, 9, "not found"),
    ("unterminated_string.aggl", 'rule r {\n  lhs { a:room [name == "x] }\n  rhs { a:room }\n}\n', 2, 25,
     "unexpected '\"'"),
    ("activates_unknown.aggl", "rule r activates nothing { lhs { } rhs { } }\n", 1, 6, "unknown rule 'nothing'"),
    ("set_deleted.aggl", "rule r {\n  lhs { a:room }\n  rhs { }\n  set a.x = 1\n}\n", 4, 7, "right-hand side"),
]


@pytest.mark.parametrize("name,text,line,column,fragment", BROKEN, ids=[b[0] for b in BROKEN])
def test_broken_files_report_file_line_column(tmp_path: Path, name: str, text: str, line: int, column: int,
                                              fragment: str) -> None:
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(GrammarError) as err:
        load_grammar(path)
    e = err.value
    assert (e.file, e.line, e.column) == (str(path), line, column), str(e)
    assert fragment in e.message
    assert str(e) == f"{path}:{line}:{column}: {e.message}"


@pytest.mark.parametrize("text,line,column,fragment", [
    ("{ a:b }\nfoo", 2, 1, "unexpected 'foo'"),           # AGM ignores trailing text; we do not
    ("{ a:b a->c(in) }", 1, 7, "undeclared node 'c'"),
    ("target { a:room } where", 1, 24, "unexpected end of file"),
])
def test_broken_targets(text: str, line: int, column: int, fragment: str) -> None:
    with pytest.raises(GrammarError) as err:
        parse_target(text, "t.aggt")
    assert (err.value.file, err.value.line, err.value.column) == ("t.aggt", line, column)
    assert fragment in err.value.message


def test_empty_target_is_valid() -> None:
    assert parse_target("", "empty.aggt").pattern.nodes == ()


def test_unreadable_file_is_a_grammar_error(tmp_path: Path) -> None:
    with pytest.raises(GrammarError, match="grammar file not found") as err:
        load_grammar(tmp_path / "missing.aggl")
    assert str(err.value) == f"{tmp_path / 'missing.aggl'}: grammar file not found"


def test_the_examples_of_docs_grammar_md_parse() -> None:
    text = (REPO_ROOT / "docs" / "grammar.md").read_text()
    native, agm = re.findall(r"```text\n(.*?)```", text, re.S)[:2]
    native_grammar = parse_grammar(native.replace('include "common.aggl"', ""), "docs-native")
    assert [r.name for r in native_grammar.rules] == ["changeRoom"]
    agm_grammar = parse_grammar(agm.replace("include(/path/to/other file.aggl)", ""), "docs-agm")
    assert [r.name for r in agm_grammar.rules] == ["changeRoom", "other"] and len(agm_grammar.combos) == 1
