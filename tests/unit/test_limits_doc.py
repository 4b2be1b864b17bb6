"""docs/limits.md states the limits the code enforces: same names, same defaults, same fixed bounds."""

from __future__ import annotations

import importlib
import re

import pytest

from scenes import model
from scenes.limits import LIMITS, LimitConfigError, Limit
from agents.lib.metrics import metrics
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


def test_round_two_fixed_bounds_in_the_doc_are_the_codes() -> None:
    """Issue 31's bounds: each row names its constant and states its value."""
    from agents.missions import kinds
    from grammar import agm_world, parser, planner
    from scenes import from_map, occupancy
    from tools.chaos import schedule as chaos_schedule
    from tools.evaluate import command as evaluate

    rows = {line.split("|")[1].strip(): line for line in DOC.splitlines() if line.startswith("| ")}

    def row(start: str) -> str:
        return next(line for key, line in rows.items() if key.startswith(start))

    assert f"at least {model.MIN_RESOLUTION_M} m" in row("scene grid resolution")
    assert f"at least {model.MIN_CLOCK_RATE} sim s" in row("sim clock rate (lower bound)")
    assert f"{model.MIN_DATE.isoformat()} to {model.MAX_DATE.isoformat()}" in row("simulated day")
    assert f"{occupancy.MIN_MAP_RESOLUTION_M} to {occupancy.MAX_MAP_RESOLUTION_M} m" in row("map resolution")
    assert f"within {occupancy.MAX_MAP_ORIGIN_M:,.0f} m" in row("map origin")
    assert f"{occupancy.MAX_MAP_CELLS:,} pixels, {occupancy.MAX_MAP_IMAGE_BYTES} bytes" in row("map image")
    assert f"at most {from_map.MAX_DOOR_WIDTH_M} m" in row("scene from-map `--door-width`")
    assert f"{parser.MAX_GRAMMAR_BYTES} bytes" in row("grammar or target file")
    assert f"{agm_world.MAX_WORLD_BYTES} bytes" in row("AGM world file")
    assert f"{parser.MAX_INCLUDES} include reads" in row("grammar includes")
    assert (f"{planner.MATCH_TRIES_PER_EXPANSION} candidate nodes per allowed expansion, at least "
            f"{planner.MIN_MATCH_BUDGET}") in row("grammar matching")
    assert f"{kinds.MAX_MISSION_CHARS} characters" in row("mission text")
    assert f"1 to {evaluate.MAX_SEEDS}" in row("evaluate `--seeds`")
    assert (f"{chaos_schedule.MAX_FAULTS}; a schedule file at most {chaos_schedule.MAX_SCHEDULE_BYTES} bytes"
            in row("chaos `--faults`"))


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
