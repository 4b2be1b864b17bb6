"""The planners a run can choose (agents/lib/planning/planners.py), offline and through `chronav path`."""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest
from typer.testing import CliRunner

from agents.lib.planning.planners import InflationParams, check_planner, planner, planner_names
from agents.lib.registry import UnknownExtension
from agents.lib.planning.plan import plan
from agents.world.offline import SceneMaps
from tests.support import REPO_ROOT
from tools.cli import app

TINY = REPO_ROOT / "tests" / "data" / "eval_tiny.yaml"
GAME_S = 10 * 3600.0 + 60.0          # 10:01: the serious game on the TV runs, the resident watches


@pytest.fixture(scope="module")
def game_map():
    return SceneMaps.load(TINY).at(GAME_S)


def _cell(smap, x: float, y: float) -> tuple[int, int, float, float]:
    row, col = smap.spec.cell_of(x, y)
    centre = smap.spec.centres(np.array([[row, col]]))[0]
    return row, col, float(centre[0]), float(centre[1])


def test_inflation_follows_nav2s_formula_around_people(game_map) -> None:
    grid = planner("inflation").grid(game_map)
    person = game_map.people[0]
    params = game_map.params
    inscribed, body = params.grid.robot_radius_m, params.grid.person_radius_m
    k = InflationParams().cost_scaling_factor
    for distance in (0.55, 0.7, 0.9, 1.1):     # from the body's edge, beyond the inscribed radius
        row, col, cx, cy = _cell(game_map, person.x + body + distance, person.y)
        d = math.hypot(cx - person.x, cy - person.y) - body
        nav2 = math.floor(252 * math.exp(-k * (d - inscribed)))      # Nav2: (253 - 1) * exp(-k (d - r_in))
        assert grid[row, col] == pytest.approx(1 + 3 * nav2 / 252, rel=1e-5), distance
    assert math.isinf(grid[_cell(game_map, person.x + body + 0.3, person.y)[:2]])  # within the inscribed radius
    row, col, _, _ = _cell(game_map, person.x + body + 1.4, person.y)
    assert grid[row, col] == 1.0                                     # beyond the inflation radius


def test_static_prices_every_space_at_r_min_whatever_the_agenda(game_map) -> None:
    tv = next(s for s in game_map.object_spaces if s.name == "tv")
    assert tv.active and tv.r == pytest.approx(game_map.params.chronemics.r_max)
    row, col, _, _ = _cell(game_map, 2.0, 1.9)      # in the TV's space, 1.6 m from the resident
    assert planner("departure").grid(game_map)[row, col] == pytest.approx(game_map.params.chronemics.r_max)
    assert planner("static").grid(game_map)[row, col] == pytest.approx(game_map.params.chronemics.r_min)
    assert planner("baseline").grid(game_map)[row, col] == 1.0
    assert planner("inflation").grid(game_map)[row, col] == 1.0


def test_every_planner_plans_and_the_baseline_is_shortest(game_map) -> None:
    lengths = {name: plan(game_map, (0.8, 1.2), (5.2, 1.2), planner=name).length_m for name in planner_names()}
    assert lengths["baseline"] == min(lengths.values())
    assert lengths["social"] > lengths["static"] > lengths["baseline"]   # the game makes the TV's space dear


def test_plan_takes_one_planner_name(game_map) -> None:
    """plan() has one way to choose: ``planner`` (default social); an unknown name is refused
    naming the known ones and the package each comes from."""
    assert check_planner("social") == "social"
    assert {"social", "departure", "static", "baseline", "inflation"} <= set(planner_names())
    default = plan(game_map, (0.8, 1.2), (5.2, 1.2))
    assert default.cost == plan(game_map, (0.8, 1.2), (5.2, 1.2), planner="social").cost
    with pytest.raises(UnknownExtension, match=r"known: baseline \(chronav\), departure \(chronav\)"):
        plan(game_map, (0.8, 1.2), (5.2, 1.2), planner="nav2")
    with pytest.raises(TypeError):
        plan(game_map, (0.8, 1.2), (5.2, 1.2), baseline=True)  # type: ignore[call-arg]


def _path(*extra: str) -> dict:
    result = CliRunner().invoke(app, ["path", str(TINY), "--at", "10:01", "--from", "0.8,1.2", "--to", "5.2,1.2",
                                      "--json", *extra])
    assert result.exit_code == 0, result.output
    return json.loads(result.stdout)


def test_path_planner_option_and_its_aliases() -> None:
    assert _path("--planner", "baseline")["points"] == _path("--baseline")["points"]
    assert _path("--planner", "departure")["points"] == _path("--departure-time")["points"]
    static = _path("--planner", "static")
    assert static["planner"] == "static" and static["metrics"]["psi_interaction_percent"]["tv"] > 0
    bad = CliRunner().invoke(app, ["path", str(TINY), "--at", "10:01", "--from", "0.8,1.2", "--to", "5.2,1.2",
                                   "--planner", "nav2"])
    words = " ".join(re.sub("[│╭╮╰╯─]", " ", bad.output).split())     # typer boxes and wraps the message
    assert bad.exit_code == 2 and "known: baseline (chronav), departure (chronav), inflation (chronav)" in words
    both = CliRunner().invoke(app, ["path", str(TINY), "--at", "10:01", "--from", "0.8,1.2", "--to", "5.2,1.2",
                                    "--planner", "static", "--baseline"])
    assert both.exit_code == 2 and "contradicts" in " ".join(re.sub("[│╭╮╰╯─]", " ", both.output).split())
