"""Path helpers of the socialmap library (agents/lib/planning/paths.py): the cost of a polyline
by the planner's own step rule, its sampling, and the nearest free cell."""

from __future__ import annotations

import math

import numpy as np
import pytest

from agents.lib.socialmap.grid import GridSpec
from agents.lib.planning.paths import densify, nearest_free, nearest_free_where, path_cost
from agents.lib.planning.search import SQRT2, StartOccupied, plan_on_grid, step_cost, warm_up

SPEC = GridSpec(x0=0.0, y0=0.0, resolution=0.1, rows=30, cols=40)


@pytest.fixture(scope="module", autouse=True)
def _compiled() -> None:
    warm_up()


def test_densify_keeps_the_vertices_and_spaces_points_at_most_one_step() -> None:
    points = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 0.35], [1.0, 0.35]])   # a repeated last vertex too
    dense = densify(points, 0.1)
    gaps = np.hypot(*np.diff(dense, axis=0).T)
    assert gaps.max() <= 0.1 + 1e-12
    for vertex in points:
        assert np.min(np.hypot(*(dense - vertex).T)) < 1e-12
    assert len(dense) == 1 + 10 + 4 + 1          # ceil(length / step) pieces per segment
    assert np.array_equal(densify(points[:1], 0.1), points[:1])


def test_densify_splits_each_gap_into_ceil_length_over_step_parts() -> None:
    """No rounding forgiveness (unlike elastic_band.resample): path costs the agent compares keep
    the sampling they had when densify lived in the agent."""
    rng = np.random.default_rng(7)
    cells = np.cumsum(rng.integers(-1, 2, (60, 2)), axis=0) + 15
    points = SPEC.centres(cells)                   # a grid path: steps of one resolution or sqrt(2)
    gaps = np.hypot(*np.diff(points, axis=0).T)
    expected = sum(max(1, math.ceil(g / 0.05)) for g in gaps)
    assert len(densify(points, 0.05)) == 1 + expected


def test_the_kernel_and_step_cost_price_a_planned_path_alike() -> None:
    """step_cost is the planner's rule: summed along the cells A* returns, it gives Path.cost."""
    rng = np.random.default_rng(3)
    grid = rng.uniform(1.0, 4.0, SPEC.shape).astype(np.float32)
    grid[5:25, 20] = np.inf
    path = plan_on_grid(grid, SPEC, (0.25, 0.25), (3.75, 2.75))
    c = grid[path.cells[:, 0], path.cells[:, 1]].astype(np.float64)
    steps = np.abs(np.diff(path.cells, axis=0)).sum(axis=1)
    lengths = np.where(steps == 2, SQRT2, 1.0) * SPEC.resolution
    assert float(np.sum(step_cost(lengths, c[:-1], c[1:]))) == pytest.approx(path.cost, rel=1e-9)


def test_path_cost_is_length_times_cost_and_inf_through_a_wall() -> None:
    grid = np.full(SPEC.shape, 2.0, dtype=np.float32)
    line = np.array([[0.55, 0.55], [3.05, 0.55], [3.05, 2.05]])
    assert path_cost(grid, SPEC, line) == pytest.approx(2.0 * (2.5 + 1.5))
    assert path_cost(grid, SPEC, line[:1]) == 0.0
    grid[10, 30] = np.inf                          # the cell at (3.05, 1.05)
    assert math.isinf(path_cost(grid, SPEC, line))


def test_path_cost_weighs_each_cell_by_its_share_of_the_line() -> None:
    grid = np.ones(SPEC.shape, dtype=np.float32)
    grid[:, 20:] = 3.0                             # dearer from x = 2 m on
    cost = path_cost(grid, SPEC, np.array([[1.05, 1.05], [3.05, 1.05]]))
    assert 1.0 * 2.0 < cost < 3.0 * 2.0
    assert cost == pytest.approx(1.0 * 0.95 + 3.0 * 1.05, abs=0.1)


def test_nearest_free_cell_and_the_predicate() -> None:
    grid = np.ones(SPEC.shape)
    grid[8:13, 8:13] = np.inf                      # someone stands around (1.05, 1.05)
    assert nearest_free(grid, SPEC, (1.05, 1.05)) == pytest.approx((1.05, 0.75))
    assert nearest_free_where(grid, SPEC, (1.05, 1.05), 1.0, lambda x, y: x > 1.2) == pytest.approx((1.35, 1.05))
    assert nearest_free_where(grid, SPEC, (1.05, 1.05), 0.2, lambda x, y: True) is None
    with pytest.raises(StartOccupied, match="no free cell within 0.2 m"):
        nearest_free(grid, SPEC, (1.05, 1.05), max_m=0.2)
