"""Gain tuning: the generic coordinate descent on toy costs, the G terms by hand, the real search."""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest
import shapely
from pydantic import ValidationError

from agents.lib.control.elastic_band import ElasticBandParams
from agents.lib.control.tuning import (
    CostTerms,
    CostWeights,
    Scenario,
    SimulatedRun,
    TuningError,
    coordinate_descent,
    cost_terms,
    default_scenarios,
    evaluate_gains,
    mean_visible_person_distance,
    simulate,
    tune_gains,
)


def toy(point: dict[str, float]) -> float:
    """Coupled quadratic with its minimum at (3.3, -1.7), which is not on any sampling grid."""
    dx, dy = point["x"] - 3.3, point["y"] + 1.7
    return dx * dx + 2.0 * dy * dy + 0.5 * dx * dy + 4.0


def test_coordinate_descent_finds_the_known_optimum_of_a_toy_cost() -> None:
    result = coordinate_descent(toy, {"x": 8.0, "y": 8.0}, {"x": (-10.0, 10.0), "y": (-10.0, 10.0)},
                                samples=7, max_rounds=200)
    assert result.best["x"] == pytest.approx(3.3, abs=0.02)
    assert result.best["y"] == pytest.approx(-1.7, abs=0.02)
    assert result.best_cost == pytest.approx(4.0, abs=1e-3)
    assert result.start_cost == pytest.approx(toy({"x": 8.0, "y": 8.0}))
    assert result.evaluations == len(result.history)
    costs = [c for _, c in result.history]
    assert min(costs) == result.best_cost


def test_coordinate_descent_stays_inside_bounds_and_budget() -> None:
    result = coordinate_descent(toy, {"x": 0.0, "y": 0.0}, {"x": (-1.0, 1.0), "y": (0.0, 5.0)},
                                samples=5, max_evaluations=12)
    assert result.evaluations <= 12
    assert -1.0 <= result.best["x"] <= 1.0 and 0.0 <= result.best["y"] <= 5.0
    assert result.best["y"] == 0.0  # the optimum y = -1.7 is outside: the bound is best
    assert result.best_cost < result.start_cost


@pytest.mark.parametrize(("kwargs", "fragment"), [
    ({"start": {"x": 0.0}, "bounds": {"x": (1.0, 0.0)}}, "bounds['x']"),
    ({"start": {}, "bounds": {"x": (0.0, 1.0)}}, "start: missing 'x'"),
    ({"start": {"x": 5.0}, "bounds": {"x": (0.0, 1.0)}}, "outside its bounds"),
    ({"start": {"x": 0.5}, "bounds": {"x": (0.0, 1.0)}, "samples": 1}, "samples"),
    ({"start": {}, "bounds": {}}, "nothing to search"),
])
def test_coordinate_descent_rejects_bad_input(kwargs: dict, fragment: str) -> None:
    with pytest.raises(TuningError, match=re.escape(fragment)):
        coordinate_descent(toy, **kwargs)


def test_tune_gains_rejects_unknown_gain() -> None:
    with pytest.raises(TuningError, match="k_x"):
        tune_gains(bounds={"k_x": (0.0, 1.0)})


def test_cost_terms_by_hand() -> None:
    """Person at (3, 0), a wall hides it from (0, 0); samples at (0,0), (0,1), (0,2) heading
    0, pi/2, pi/2, 1 s apart: H = pi/2, D = 2, Q = 2, P = mean(sqrt 10, sqrt 13)."""
    scenario = Scenario(name="hand", obstacles=(shapely.box(1.0, -0.3, 2.0, 0.3),), people=((3.0, 0.0),),
                        start=(0.0, 0.0, 0.0), goal=(0.0, 2.0), global_path=((0.0, 0.0), (0.0, 2.0)),
                        time_limit_s=10.0)
    traj = np.array([[0.0, 0.0, 0.0, 0.0], [1.0, 0.0, 1.0, math.pi / 2], [2.0, 0.0, 2.0, math.pi / 2]])
    terms = cost_terms(SimulatedRun(traj, reached=True, collided=False, min_clearance_m=1.0), scenario, 4.0)
    assert terms == CostTerms(H=pytest.approx(math.pi / 2), D=pytest.approx(2.0), Q=pytest.approx(2.0),
                              P=pytest.approx((math.sqrt(10) + math.sqrt(13)) / 2), failed=False)
    # Out of sensor range counts as not visible.
    assert mean_visible_person_distance(traj[:, 1:3], scenario, 3.5) == pytest.approx(math.sqrt(10))
    weights = CostWeights(a=1.0, b=2.0, c=3.0, d=-4.0, failure_penalty=100.0)
    assert terms.cost(weights) == pytest.approx(math.pi / 2 + 4.0 + 6.0 - 4.0 * terms.P)
    failed = cost_terms(SimulatedRun(traj, reached=False, collided=False, min_clearance_m=1.0), scenario, 4.0)
    assert failed.failed and failed.Q == 10.0  # a failed run is charged the time limit
    assert failed.cost(weights) == pytest.approx(terms.cost(weights) + 3.0 * 8.0 + 100.0)


def test_simulated_corridor_needs_repulsion() -> None:
    """Band + controller reach the goal past the person with the seed's gains; without repulsion
    the band keeps the planned line through the person and the robot runs into them."""
    corridor = default_scenarios()[0]
    ok = simulate(corridor)
    assert ok.reached and not ok.collided
    assert ok.min_clearance_m > 0.35
    assert ok.trajectory[-1, 1] == pytest.approx(corridor.goal[0], abs=0.15)
    bad = simulate(corridor, ElasticBandParams(k_r=0.0))
    assert bad.collided and not bad.reached


def test_real_search_improves_g_over_its_start() -> None:
    """From a poor start (no contraction, strong repulsion) a small budget already lowers G."""
    result = tune_gains(start={"k_c": 0.0, "k_r": 300.0}, samples=3, max_rounds=1, max_evaluations=4)
    descent = result.descent
    assert descent.evaluations <= 4
    assert descent.best_cost < descent.start_cost - 1.0
    assert descent.best != descent.start
    assert set(result.terms) == {"corridor_person", "doorway", "obstacle"}
    assert not any(t.failed for t in result.terms.values())


def test_evaluate_gains_validates_the_gains() -> None:
    with pytest.raises(TuningError, match="k_x"):
        evaluate_gains({"k_x": 1.0}, default_scenarios()[:1])
    with pytest.raises(ValidationError, match="k_r"):
        evaluate_gains({"k_r": -1.0}, default_scenarios()[:1])


def test_tune_gains_tool_prints_one_json_object_and_reports_bad_options() -> None:
    from typer.testing import CliRunner

    from tools.plan.tune_gains import app

    runner = CliRunner()
    ok = runner.invoke(app, ["--max-evaluations", "1", "--json"])
    assert ok.exit_code == 0, ok.output
    summary = json.loads(ok.stdout)
    assert summary["k_c"] == 120.0 and summary["k_r"] == 60.0 and summary["evaluations"] == 1
    assert summary["G"] == summary["start_G"]
    bad = runner.invoke(app, ["--start-k-c", "500", "--json"])
    assert bad.exit_code == 2
    assert "start['k_c'] = 500.0 is outside its bounds" in bad.stderr
    assert bad.stdout == ""
