"""A* and Dijkstra against scipy's csgraph (same edge rule), the no-squeeze rule, typed errors."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from agents.lib.socialmap.grid import GridSpec
from agents.lib.planning.reference_graph import grid_graph, reference_cost
from agents.lib.planning.search import (
    GoalOccupied,
    NoPathFound,
    OutsideMap,
    PlanningError,
    SearchWorkspace,
    StartOccupied,
    TimeCosts,
    plan_on_grid,
    search_cells,
    warm_up,
)


@pytest.fixture(scope="module", autouse=True)
def _compiled() -> None:
    """Compile (or load from numba's disk cache) once for the module, outside any test."""
    warm_up()


@st.composite
def grid_problems(draw: st.DrawFn) -> tuple[np.ndarray, tuple[int, int], tuple[int, int]]:
    rows = draw(st.integers(2, 18))
    cols = draw(st.integers(2, 18))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    cost = rng.choice([1.0, 1.5, 2.0, 3.5, 4.0], size=(rows, cols)) * rng.uniform(1.0, 1.2, size=(rows, cols))
    cost[rng.random((rows, cols)) < draw(st.floats(0.0, 0.45))] = np.inf
    free = np.argwhere(np.isfinite(cost))
    if len(free) < 2:
        cost[0, 0] = cost[-1, -1] = 1.0
        free = np.array([[0, 0], [rows - 1, cols - 1]])
    a, b = rng.choice(len(free), size=2, replace=False)
    return cost.astype(np.float32), tuple(free[a]), tuple(free[b])


@settings(max_examples=120, deadline=None)
@given(grid_problems())
def test_astar_and_dijkstra_costs_equal_scipy(problem) -> None:  # type: ignore[no-untyped-def]
    cost, start, goal = problem
    expected = reference_cost(cost, start, goal)
    for heuristic in (True, False):
        if math.isinf(expected):
            with pytest.raises(NoPathFound):
                search_cells(cost, start, goal, heuristic=heuristic)
            continue
        path = search_cells(cost, start, goal, heuristic=heuristic)
        assert path.cost_cells == pytest.approx(expected, rel=1e-7)
        # The returned cells are a connected 8-path whose own cost is the reported cost.
        steps = np.diff(path.cells, axis=0)
        assert np.all(np.abs(steps).max(axis=1) == 1)
        c = cost[path.cells[:, 0], path.cells[:, 1]].astype(np.float64)
        lengths = np.where(np.abs(steps).sum(axis=1) == 2, math.sqrt(2), 1.0)
        assert float(np.sum(lengths * (c[:-1] + c[1:]) / 2)) == pytest.approx(path.cost_cells, rel=1e-9)


def test_astar_expands_fewer_cells_than_dijkstra() -> None:
    cost = np.ones((60, 80), dtype=np.float32)
    cost[10:50, 40] = np.inf
    astar = search_cells(cost, (30, 2), (30, 77))
    dijkstra = search_cells(cost, (30, 2), (30, 77), heuristic=False)
    assert astar.cost_cells == pytest.approx(dijkstra.cost_cells, rel=1e-9)
    assert astar.expanded < dijkstra.expanded / 3


def test_no_diagonal_squeeze_between_two_blocked_cells() -> None:
    cost = np.ones((2, 2), dtype=np.float32)
    cost[0, 1] = cost[1, 0] = np.inf
    with pytest.raises(NoPathFound):
        search_cells(cost, (0, 0), (1, 1))
    assert math.isinf(reference_cost(cost, (0, 0), (1, 1)))       # the reference graph has the same rule
    cost[1, 0] = 1.0                                                # one side open: the diagonal is allowed
    assert search_cells(cost, (0, 0), (1, 1)).cost_cells == pytest.approx(math.sqrt(2))
    assert grid_graph(cost).nnz == 2 * 3                            # (0,0)-(1,0), (1,0)-(1,1), diagonal


def test_typed_errors() -> None:
    cost = np.ones((5, 5), dtype=np.float32)
    cost[:, 2] = np.inf
    cost[0, 0] = np.inf
    for error, start, goal in ((StartOccupied, (0, 0), (4, 4)), (GoalOccupied, (1, 1), (2, 2)),
                               (NoPathFound, (1, 1), (4, 4)), (OutsideMap, (1, 1), (5, 0))):
        with pytest.raises(error):
            search_cells(cost, start, goal)
        assert issubclass(error, PlanningError)
    with pytest.raises(ValueError, match="costs must be > 0"):
        search_cells(np.zeros((3, 3), dtype=np.float32), (0, 0), (2, 2))


def test_plan_on_grid_in_metres_and_workspace_reuse() -> None:
    spec = GridSpec.from_bounds((0.0, 0.0, 2.0, 1.0), 0.1)
    cost = np.ones(spec.shape, dtype=np.float32)
    workspace = SearchWorkspace()
    path = plan_on_grid(cost, spec, (0.05, 0.55), (1.95, 0.55), workspace=workspace)
    assert path.cost == pytest.approx(1.9) and path.length_m == pytest.approx(1.9)
    assert path.points_m[0] == pytest.approx((0.05, 0.55)) and path.points_m[-1] == pytest.approx((1.95, 0.55))
    bigger = np.ones((30, 30), dtype=np.float32)                     # the workspace grows
    assert search_cells(bigger, (0, 0), (29, 29), workspace=workspace).cost_cells == pytest.approx(29 * math.sqrt(2))
    again = plan_on_grid(cost, spec, (0.05, 0.55), (1.95, 0.55), workspace=workspace)
    assert again.cost == pytest.approx(path.cost)
    with pytest.raises(OutsideMap, match="goal"):
        plan_on_grid(cost, spec, (0.05, 0.55), (2.5, 0.5))


def test_arrival_time_costs_depend_on_distance_travelled() -> None:
    """A corridor of 10 cells; cell 6 costs 1 if reached in the first 5 cells of travel, then 9."""
    grid = np.ones((1, 10), dtype=np.float32)
    grid[0, 6] = -1.0
    early = TimeCosts(grid, np.array([[1.0, 1.0]]), cells_per_bin=100.0)
    late = TimeCosts(grid, np.array([[1.0, 9.0]]), cells_per_bin=5.0)
    assert search_cells(early, (0, 0), (0, 9)).cost_cells == pytest.approx(9.0)
    assert search_cells(late, (0, 0), (0, 9)).cost_cells == pytest.approx(9.0 + 8.0)
    forbidden = TimeCosts(grid, np.array([[1.0, math.inf]]), cells_per_bin=5.0)
    with pytest.raises(NoPathFound):
        search_cells(forbidden, (0, 0), (0, 9))
    start_inside = TimeCosts(grid, np.array([[math.inf, 1.0]]), cells_per_bin=5.0)
    with pytest.raises(StartOccupied, match="forbidden at departure"):
        search_cells(start_inside, (0, 6), (0, 9))


def test_reused_workspace_with_stale_lengths_gives_the_same_arrival_costs() -> None:
    """Regression: the start's travelled length must be reset, not read from a previous search; no
    buffer content left by an earlier search (only the stamps in ``mark``) may matter."""
    grid = np.ones((1, 10), dtype=np.float32)
    grid[0, 6] = -1.0
    late = TimeCosts(grid, np.array([[1.0, 9.0]]), cells_per_bin=5.0)
    workspace = SearchWorkspace()
    workspace.next_stamp(grid.size)   # sizes the buffers
    for junk in (-1e300, 1e300, np.nan):
        for buffer in (workspace.g, workspace.length, workspace.keys):
            buffer.fill(junk)
        workspace.pos.fill(-7)
        workspace.parent.fill(-7)
        assert search_cells(late, (0, 0), (0, 9), workspace=workspace).cost_cells == pytest.approx(17.0)
