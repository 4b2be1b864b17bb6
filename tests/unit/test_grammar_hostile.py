"""Hostile and careless grammar, target and world files through `chronav grammar check` and
`chronav plan` (issue 12): a located error in the user's words and a non-zero exit, never a
traceback, within bounded time and memory. Inputs are in tests/data/hostile/ (the 5 MB token is
generated: too large to keep in the repository)."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from grammar import GrammarError, parse_grammar
from tests.support import REPO_ROOT
from tools.cli import app

HOSTILE = REPO_ROOT / "tests" / "data" / "hostile"
DATA = REPO_ROOT / "tests" / "data" / "aggl"
runner = CliRunner()


def check(path: Path) -> object:
    return runner.invoke(app, ["grammar", "check", str(path)])


@pytest.mark.parametrize("name,first_line", [
    ("grammar_deep_parentheses.aggl", ":5:41: nested too deeply: more than 100 levels"),
    ("grammar_deep_effect.aggl", ":5:1065: nested too deeply: more than 100 levels"),
    ("grammar_undeclared_type.aggl", ":7:26: rule 'go' uses type 'rooom', which the types section does not declare"),
    ("grammar_infinite_cost.aggl", ":2:6: rule 'r': cost inf is not a finite number"),
    ("grammar_empty.aggl", ":1:1: the file is empty"),
    ("grammar_comments_only.aggl", ":1:1: the file is empty"),
])
def test_bad_grammars_are_located_errors(name: str, first_line: str) -> None:
    result = check(HOSTILE / name)
    assert result.exit_code == 1, result.output
    assert result.stderr.splitlines()[0].startswith(f"{HOSTILE / name}{first_line}"), result.stderr
    assert "Traceback" not in result.output


def test_a_utf8_bom_is_accepted_in_grammars_and_targets() -> None:
    result = runner.invoke(app, ["grammar", "check", str(HOSTILE / "grammar_bom.aggl"), str(HOSTILE / "target_bom.aggt")])
    assert result.exit_code == 0, result.output
    assert "2 file(s) OK" in result.stdout


def test_a_missing_grammar_file_is_named_not_located_at_zero() -> None:
    missing = HOSTILE / "no_such_grammar.aggl"
    result = check(missing)
    assert result.exit_code == 1 and result.stderr.strip() == f"{missing}: grammar file not found"
    planned = runner.invoke(app, ["plan", "--world", str(DATA / "two_rooms.xml"), "--target",
                                  str(DATA / "robot_in_3.aggt"), "--grammar", str(missing)])
    assert planned.exit_code == 2 and planned.stderr.strip() == f"{missing}: grammar file not found"


def test_an_error_does_not_echo_a_huge_token(tmp_path: Path) -> None:
    big = tmp_path / "one_line.aggl"
    big.write_text("rule " + "a" * 5_000_000 + " { lhs { } }")
    result = check(big)
    assert result.exit_code == 1
    assert len(result.stderr) < 600 and "has no 'rhs' section" in result.stderr
    string = tmp_path / "long_string.aggl"
    string.write_text('rule r { lhs { a:room } rhs { a:room } where a.x == "' + "c" * 5_000_000 + '" zz }')
    result = check(string)
    assert result.exit_code == 1 and len(result.stderr) < 600 and "unexpected 'zz'" in result.stderr


@pytest.mark.parametrize("name,message", [
    ("world_list.json", "a world must be a JSON object with 'nodes' and 'links', not a list"),
    ("world_nodes_number.json", "key 'nodes': expected a list of node objects"),
    ("world_billion_laughs.xml", ":2:16: refused: the file uses a DTD or entities"),
    ("world_link_to_nowhere.xml", ":3:2: link 1->9(in): dst '9' is not a symbol declared before it"),
])
def test_bad_worlds_are_clear_errors(name: str, message: str) -> None:
    world = HOSTILE / name
    result = runner.invoke(app, ["plan", "--world", str(world), "--target", str(DATA / "robot_in_3.aggt"),
                                 "--grammar", str(DATA / "teleport.aggl")])
    assert result.exit_code == 2, result.output
    assert result.stderr.strip().startswith(str(world)) and message in result.stderr
    if name.endswith(".json"):  # the older form: the world given as SCENE
        old = runner.invoke(app, ["plan", str(world), "--mission", "room:kitchen"])
        assert old.exit_code == 2 and message in old.stderr


@settings(max_examples=25, deadline=None)
@given(depth=st.integers(1, 600), kind=st.sampled_from(["parens", "not", "fnot", "exists", "block"]))
def test_any_nesting_depth_parses_or_gives_a_located_error(depth: int, kind: str) -> None:
    """Deep structures of every kind: a model or a located GrammarError, never a RecursionError."""
    body = {
        "parens": "where " + "(" * depth + "a.x == 1" + ")" * depth,
        "not": "where " + "not " * depth + "a.x",
        "fnot": "precondition { " + "(not " * depth + "(in a a)" + ")" * depth + " }",
        "exists": "precondition { " + "".join(f"(exists x{i}:room " for i in range(depth)) + "(in a a)" + ")" * depth + " }",
        "block": "where " + "exists { b:room [" * depth + "x == 1" + "] }" * depth,
    }[kind]
    text = f"rule r {{\n  lhs {{ a:room }}\n  rhs {{ a:room }}\n  {body}\n}}\n"
    try:
        parse_grammar(text, "deep.aggl")
    except GrammarError as err:
        assert err.file == "deep.aggl" and err.line >= 1 and err.column >= 1, str(err)
