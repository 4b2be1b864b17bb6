"""docs/limits.md states the limits the code enforces: same names, same defaults, same fixed bounds."""

from __future__ import annotations

import importlib
import re

import pytest

from scenes import model
from scenes.limits import LIMITS, LimitConfigError, Limit
from agents.lib.socialmap import metrics
from tests.support import REPO_ROOT

DOC = (REPO_ROOT / "docs" / "limits.md").read_text(encoding="utf-8")


def _rows(text: str) -> list[list[str]]:
    return [[cell.strip() for cell in line.strip().strip("|").split("|")]
            for line in text.splitlines() if line.startswith("| `")]


def test_every_configurable_limit_is_documented_with_its_default() -> None:
    documented = {row[0].strip("`"): int(row[1]) for row in _rows(DOC)}
    assert documented == {limit.name: limit.default for limit in LIMITS}
    for limit in LIMITS:
        assert limit.env.startswith("CHRONAV_LIMIT_") and limit.name.upper() in limit.env


def test_fixed_bounds_in_the_doc_are_the_codes() -> None:
    assert f"at most {model.MAX_ROBOT_RADIUS_M} m" in DOC
    assert f"at most {model.MAX_SPEED_MPS} m/s" in DOC
    assert f"0 to {metrics.MAX_TRAJECTORY_TIME_S:,.0f} s" in DOC
    assert "`MAX_TRAJECTORY_TIME_S`" in DOC and "`MAX_ROBOT_RADIUS_M`" in DOC


def test_grammar_nesting_row_matches_the_parser_when_it_has_one() -> None:
    stated = int(re.search(r"grammar nesting.*?\| (\d+) levels", DOC)[1])  # type: ignore[index]
    parser = importlib.import_module("grammar.parser")
    if not hasattr(parser, "MAX_NESTING"):
        pytest.skip("grammar/parser.py has no MAX_NESTING on this branch (the grammar branch adds it)")
    assert parser.MAX_NESTING == stated


def test_a_limit_is_configured_by_its_environment_variable() -> None:
    limit = Limit("demo", 10, "things", "a test limit")
    assert limit.value({}) == 10
    assert limit.value({"CHRONAV_LIMIT_DEMO": "25"}) == 25
    for bad in ("0", "-3", "ten", "1e9", "9" * 30, "\u00b2", "\u0663"):
        with pytest.raises(LimitConfigError, match="CHRONAV_LIMIT_DEMO.*positive whole number"):
            limit.value({"CHRONAV_LIMIT_DEMO": bad})
