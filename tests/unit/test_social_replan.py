"""Replanning (replan.py) against scipy's csgraph on random grids with random local changes, the
arrival-time variant, and the work it saves."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from agents.lib.planning.reference_graph import reference_cost
from agents.lib.planning.replan import Replanner, truncate_down, warm_up
from agents.lib.planning.search import GridPath, NoPathFound, search_cells
from agents.lib.socialmap.grid import TimeCosts

SQRT2 = math.sqrt(2.0)
VALUES = (1.0, 1.5, 2.0, 3.5, 4.0)


@pytest.fixture(scope="module", autouse=True)
def _compiled() -> None:
    warm_up()


def path_cost(cost: np.ndarray, path: GridPath) -> float:
    """The planner's semantics recomputed along the returned cells (also checks they are 8-steps)."""
    steps = np.diff(path.cells, axis=0)
    assert np.all(np.abs(steps).max(axis=1) == 1)
    c = cost[path.cells[:, 0], path.cells[:, 1]].astype(np.float64)
    assert np.all(np.isfinite(c))
    lengths = np.where(np.abs(steps).sum(axis=1) == 2, SQRT2, 1.0)
    return float(np.sum(lengths * (c[:-1] + c[1:]) / 2))


def random_grid(rng: np.random.Generator, rows: int, cols: int, blocked: float) -> np.ndarray:
    cost = rng.choice(VALUES, size=(rows, cols)) * rng.uniform(1.0, 1.2, size=(rows, cols))
    cost[rng.random((rows, cols)) < blocked] = np.inf
    return cost.astype(np.float32)


def random_change(rng: np.random.Generator, cost: np.ndarray, goal: tuple[int, int]) -> None:
    """A local change: a small window gets new costs (cheaper, dearer, blocked or opened)."""
    rows, cols = cost.shape
    r, c = int(rng.integers(rows)), int(rng.integers(cols))
    h, w = (int(v) for v in rng.integers(1, 5, size=2))
    window = cost[r:r + h, c:c + w]
    window[...] = rng.choice((*VALUES, np.inf), size=window.shape).astype(np.float32)
    cost[goal] = 1.0


@st.composite
def replan_problems(draw: st.DrawFn) -> tuple[np.ndarray, tuple[int, int], int, float]:
    rows = draw(st.integers(2, 20))
    cols = draw(st.integers(2, 20))
    seed = draw(st.integers(0, 2**32 - 1))
    blocked = draw(st.floats(0.0, 0.4))
    refresh_fraction = draw(st.sampled_from((0.25, 1e9)))   # 1e9: never refresh, always repair
    rng = np.random.default_rng(seed)
    cost = random_grid(rng, rows, cols, blocked)
    goal = (int(rng.integers(rows)), int(rng.integers(cols)))
    cost[goal] = 1.0
    return cost, goal, seed, refresh_fraction


@settings(max_examples=100, deadline=None)
@given(replan_problems(), st.integers(2, 8))
def test_replans_cost_what_scipy_finds(problem, steps) -> None:  # type: ignore[no-untyped-def]
    """A sequence of plans to one goal from moving starts, with local changes between them (cheaper
    and dearer cells, walls appearing and vanishing): every result is scipy's optimum."""
    cost, goal, seed, refresh_fraction = problem
    rng = np.random.default_rng(seed + 1)
    replanner = Replanner(refresh_fraction=refresh_fraction, margin_cells=float(rng.choice((0.5, 3.0, 10.0))))
    rows, cols = cost.shape
    start = (int(rng.integers(rows)), int(rng.integers(cols)))
    for step in range(steps):
        if step:
            random_change(rng, cost, goal)
            start = (min(max(start[0] + int(rng.integers(-2, 3)), 0), rows - 1),
                     min(max(start[1] + int(rng.integers(-2, 3)), 0), cols - 1))
        cost[start] = min(float(cost[start]), 2.0)
        expected = reference_cost(cost, start, goal)
        if math.isinf(expected):
            with pytest.raises(NoPathFound):
                replanner.search(cost, start, goal, c_min=1.0)
            continue
        found = replanner.search(cost, start, goal, c_min=1.0)
        assert found.cost_cells == pytest.approx(expected, rel=1e-7)
        assert path_cost(cost, found) == pytest.approx(found.cost_cells, rel=1e-9)
        assert tuple(found.cells[0]) == start and tuple(found.cells[-1]) == goal


def test_a_replan_reuses_the_search_and_expands_a_fraction() -> None:
    """200 x 200 with a wall: after the robot moved along the path and a far cell changed, the
    replan expands little more than its path (the fresh search expands thousands of cells)."""
    cost = np.ones((200, 200), dtype=np.float32)
    cost[20:180, 100] = np.inf
    cost[150:160, 20:30] = 4.0
    replanner = Replanner()
    first = replanner.search(cost, (100, 5), (100, 195))
    assert replanner.last is not None and replanner.last.refreshed
    cost[10, 190] = 2.0                 # far from the path: dearer
    cost[150:160, 20:30] = 1.0          # a person left: cheaper (repaired)
    start = tuple(first.cells[8])
    again = replanner.search(cost, start, (100, 195))
    stats = replanner.last
    fresh = search_cells(cost, start, (100, 195))
    assert not stats.refreshed and stats.cheaper_cells == 100
    assert again.cost_cells == pytest.approx(fresh.cost_cells, rel=1e-9)
    assert again.expanded < len(again.cells) + 50 < fresh.expanded / 10


def test_an_opened_door_is_found_by_the_repair() -> None:
    """Cells becoming free (a door opening) lower the learned bounds: the shortcut is taken."""
    cost = np.ones((60, 80), dtype=np.float32)
    cost[:, 40] = np.inf
    cost[55:, 40] = 1.0                  # the long way round, at the bottom
    replanner = Replanner(refresh_fraction=1e9)
    around = replanner.search(cost, (5, 5), (5, 75))
    cost[4:7, 40] = 1.0                  # the door next to the straight line opens
    through = replanner.search(cost, (5, 5), (5, 75))
    assert replanner.last is not None and not replanner.last.refreshed and replanner.last.repaired > 0
    assert through.cost_cells == pytest.approx(70.0) and around.cost_cells > 100.0
    assert through.cost_cells == pytest.approx(reference_cost(cost, (5, 5), (5, 75)), rel=1e-9)


def test_a_new_goal_or_grid_starts_afresh() -> None:
    cost = np.ones((30, 30), dtype=np.float32)
    replanner = Replanner()
    replanner.search(cost, (0, 0), (29, 29))
    replanner.search(cost, (1, 1), (29, 29))
    assert replanner.last is not None and not replanner.last.refreshed
    replanner.search(cost, (1, 1), (29, 28))
    assert replanner.last.refreshed
    replanner.search(np.ones((30, 31), dtype=np.float32), (1, 1), (29, 28))
    assert replanner.last.refreshed
    replanner.reset()
    replanner.search(np.ones((30, 31), dtype=np.float32), (1, 1), (29, 28))
    assert replanner.last.refreshed


def test_truncated_bounds_never_exceed_the_cost() -> None:
    values = np.array([1.0, 1.5, 2.0, 3.5, 4.0, 1.1, 2.37, 1e-3, 0.3, 1e30, np.inf, 1.0000001])
    bounds = truncate_down(values)
    assert np.all(bounds <= values)
    assert np.array_equal(bounds[:5], values[:5])           # the map's usual costs stay exact
    assert np.all(bounds[5:10] >= values[5:10] * (1 - 1 / 32))
    assert bounds[10] == np.inf


def decoded(costs: TimeCosts, column: int) -> np.ndarray:
    """The static grid of an arrival-time grid whose table is constant from ``column`` on."""
    grid = costs.grid.astype(np.float64)
    coded = grid < 0
    grid[coded] = costs.table[(-grid[coded]).astype(int) - 1, column]
    return grid


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(3, 16), st.integers(3, 16))
def test_arrival_time_replans(seed: int, rows: int, cols: int) -> None:
    """Interaction spaces coded into the grid: with costs constant over time a replan is scipy's
    optimum on the decoded grid; with costs changing over time its cost is its path's own
    (charged at the lengths travelled along it) and at least the optimum at the cheapest times."""
    rng = np.random.default_rng(seed)
    base = random_grid(rng, rows, cols, 0.2)
    goal = (rows - 1, cols - 1)
    base[goal] = 1.0
    spaces = [(slice(int(rng.integers(rows)), None), slice(int(rng.integers(cols)), int(rng.integers(cols)) + 3))
              for _ in range(2)]
    bins = 6
    constant = np.repeat(rng.uniform(1.5, 3.5, size=(2, 1)), bins, axis=1)
    varying = np.column_stack([np.linspace(1.5, 3.5, bins), np.r_[np.full(3, np.inf), np.full(bins - 3, 1.5)]]).T
    for table in (constant, varying):
        replanner = Replanner(refresh_fraction=1e9)
        grid = base.copy()
        for k, (r, c) in enumerate(spaces):
            window = grid[r, c]
            window[np.isfinite(window)] = -(k + 1)
        grid[goal] = 1.0
        start = (0, 0)
        for step in range(3):
            if step:
                random_change(rng, grid, goal)
                start = (min(start[0] + 1, rows - 1), min(start[1] + 1, cols - 1))
            grid[start] = 1.0
            costs = TimeCosts(grid.copy(), table, cells_per_bin=2.0)
            cheapest = reference_cost(decoded(TimeCosts(grid, table.min(axis=1)[:, None], 1.0), 0), start, goal)
            try:
                found = replanner.search(costs, start, goal, c_min=1.0)
            except NoPathFound:
                assert table is varying or math.isinf(cheapest)
                continue
            assert found.cost_cells >= cheapest * (1 - 1e-9)
            charged = arrival_cost(costs, found)
            assert found.cost_cells == pytest.approx(charged, rel=1e-9)
            if table is constant:
                assert found.cost_cells == pytest.approx(reference_cost(decoded(costs, 0), start, goal), rel=1e-7)


def arrival_cost(costs: TimeCosts, path: GridPath) -> float:
    """A path's cost with each arrival-time cell charged at the length travelled along the path."""
    total, travelled = 0.0, 0.0
    previous = None
    last = costs.table.shape[1] - 1
    for r, c in path.cells:
        value = float(costs.grid[r, c])
        if previous is not None:
            step = SQRT2 if abs(r - previous[0]) + abs(c - previous[1]) == 2 else 1.0
            travelled += step
        if value < 0:
            value = float(costs.table[int(-value) - 1, min(int(travelled / costs.cells_per_bin), last)])
        if previous is not None:
            total += step * (previous[2] + value) / 2
        previous = (r, c, value)
    return total


def test_social_map_replans_through_plan() -> None:
    """``plan(..., replanner=...)`` on successive social maps (a person walking towards the path,
    R(t) rising before a TV therapy, the robot advancing): the same costs as fresh plans, with the
    arrival-time costs (the default) and at departure time, and less work after the first."""
    from agents.lib.agenda.model import ActivityWindow
    from agents.lib.socialmap.social_map import build_social_map, build_static_map
    from agents.lib.planning.plan import plan
    from agents.lib.socialmap.types import Person, SocialObject, Wall
    from scenes.geometry import Rectangle, Trapezoid

    walls = [Wall(((0, 0), (16, 0), (16, 8), (0, 8), (0, 0)), name="outer"),
             Wall(((8, 0), (8, 5)), name="inner")]
    tv = SocialObject("tv", "tv", 12.0, 0.1, math.pi / 2, Rectangle(0.2, 1.2), Trapezoid(3.0, 1.2, 4.0))
    therapy = [ActivityWindow("tv", 11 * 3600.0 + 600.0, 12 * 3600.0)]
    static = build_static_map((0, 0, 16, 8), walls)
    goal = (15.0, 1.0)
    for planner in ("social", "departure"):
        replanner = Replanner()
        robot = (1.0, 1.0)
        works = []
        for step in range(4):
            t_s = 11 * 3600.0 + 0.2 * step
            people = [Person("ann", 4.0 + 0.2 * step, 4.0, 0.0), Person("bob", 11.0, 6.0 - 0.2 * step, math.pi)]
            smap = build_social_map((0, 0, 16, 8), walls, people, [tv], therapy, t_s, static=static)
            replanned = plan(smap, robot, goal, replanner=replanner, planner=planner)
            fresh = plan(smap, robot, goal, planner=planner)
            assert replanned.cost == pytest.approx(fresh.cost, rel=1e-7)
            assert replanner.last is not None
            works.append(replanner.last.expanded + replanner.last.backward_expanded)
            robot = tuple(replanned.points_m[4])
        assert max(works[1:]) < works[0] / 3
