"""Replanning to one goal on a changing map, reusing an earlier backward search as the heuristic.

The situation: the robot replans several times a second; its goal stays, its start moves along
the path, people move anywhere in the building, and R(t) creeps. The arrival-time costs
(search.py) are defined by the length travelled *from the start*, so the plan itself has to stay a
forward A* from the robot. What can carry over between plans is the heuristic.

Scheme (Reverse Resumable A*'s exact cost-to-go, Silver 2005, kept consistent under cost decreases
by Generalized Adaptive A*'s repair, Sun, Koenig and Yeoh 2008):

1. *Lower-bound grid.* Each cell's cost (for an arrival-time cell, the minimum of its table row)
   is truncated to 6 significant bits (so 1, 1.5, 2, 3.5 and 4 stay exact and R(t) creeping by a
   thousandth does not count as a change), giving a grid ``b`` that is <= the search's costs.
2. *Refresh* (first plan to a goal, or when reuse stopped paying): one A* from the goal towards the
   robot on ``b``, continued after reaching the robot until every cell with a key up to
   ``C_b + m`` is closed (C_b: the cost found, m: ``margin_cells``). Every closed cell gets
   ``X(n) = g_b(n)``, its exact cost to the goal on ``b``; every other cell gets
   ``X(n) = (C_b + m) / w - c_b octile(n, robot)`` (c_b: the cheapest cost of ``b``, w = 1 + 1e-9
   the tie-break weight): a cell the weighted A* did not close has
   ``w (d(n) + c_b octile(n, robot)) >= C_b + m``, so this is a lower bound too. The margin is
   why the plans below stay on the exact values: without it the cells beside the old path that
   A* never closed would carry a bound tied with the optimum and be expanded by the thousand.
3. *Plan* (every time): forward A* from the robot with ``H(n) = max(c_min octile(n, goal), X(n))``
   on the real costs (search.py's kernel). Near the old path H is the exact remaining cost, so the
   search walks along the new path and expands only cells whose cost-to-go rose.
4. *Repair* (on reuse): cells whose bound in ``b`` fell may break X's consistency; around each,
   ``X(n) = min_m c_b(n, m) + X(m)`` is recomputed and lowered values propagate Dijkstra-like in
   increasing X (GAA*'s consistency procedure), which restores consistency with the least change.

Why the result is optimal (static cost grids; the tests compare with scipy):
  * X is consistent on ``b`` (``X(n) <= c_b(n, m) + X(m)``): between closed cells by the triangle
    inequality of exact distances; from a closed to an unclosed cell because closed cells had a
    key <= C_b + m; between unclosed cells because ``c_b octile`` changes by at most ``c_b L`` per
    step.
    A cost increase keeps it; the repair restores it after decreases. With ``X(goal) = 0``
    consistency implies admissibility, and both carry over from ``b`` to the real costs (>= b).
    ``c_min octile`` is consistent, and so is the maximum of two consistent heuristics. So each
    plan is an A* with a consistent heuristic: optimal like plain A*. The tie-break weight w makes
    the backward values, and so these inequalities, hold only within a factor w, so a plan is
    optimal within about w^2 = 1 + 2e-9; nothing accumulates over replans (a refresh starts from
    the grid itself, a repair only lowers values).
  * A new goal, grid shape or ``c_min`` starts afresh.

Cost: a pass comparing bounds (over the whole grid, 0.3 ms at 1000^2; over the windows that changed
when the grid is the one the replanner's ``costs`` (incremental.py) built from its previous grid,
plus the interaction spaces' windows when the table's row minima moved), the repair (proportional
to the cells whose cost-to-go fell), and A* expanding the path plus the cells whose old
cost-to-go lies within the cost increase of the optimum (tools/bench/bench_planner.py: replan_*; building
the arrival-time grid from the map, also incremental, is timed there too). When a plan expands
(or repairs) more than ``refresh_fraction`` of what the last refresh closed, the next plan
refreshes: about 2.5 plain A*s at 1000^2 (from the goal's side, plus the margin), paid once per
goal and after far-reaching changes.

Arrival-time costs (TimeCosts): X comes from lower bounds (each space at its cheapest over the
table's horizon), so it stays admissible whatever the arrival times, and when no space changes
cost during the trip the plan is the optimum as above (tested against scipy). Otherwise the
time-dependent search is itself a label-setting approximation (search.py) whose result depends
on the order of expansion: a replan may then settle an interaction-space cell through another
first-found path than a fresh plan. The tests check that its cost is its path's own (each space
charged at the length travelled along it) and never below the optimum at the spaces' cheapest.
"""

from __future__ import annotations

import heapq
from dataclasses import dataclass

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from agents.lib.socialmap.incremental import IncrementalTimeCosts
from agents.lib.planning.search import (
    _TIE_BREAK,
    SQRT2,
    GridPath,
    LearnedBounds,
    SearchProblem,
    SearchWorkspace,
    TimeCosts,
    prepare,
    run_search,
)

U = np.uint64


# Lower bounds keep 6 significant bits of a float32: sign, exponent and the top 5 stored mantissa
# bits. Clearing bits of a non-negative float truncates it towards zero (and keeps inf), and
# non-negative floats order like their bit patterns, so the pass below works on integers.
_TRUNCATE_MASK = np.uint32(0xFFFC0000)
_SIGN = np.uint32(0x80000000)
_MAX_STAMP = int(np.iinfo(np.uint32).max) - 1


def truncate_down(values: ArrayLike) -> NDArray[np.float32]:
    """float32 values <= ``values`` with 6 significant bits (inf stays inf; values >= 0)."""
    values = np.asarray(values, dtype=np.float64)
    single = values.astype(np.float32)
    single = np.where(single > values, np.nextafter(single, np.float32(-np.inf)), single).astype(np.float32)
    return (single.view(np.uint32) & _TRUNCATE_MASK).view(np.float32)


@numba.njit(cache=True, nogil=True)
def _update_bounds(flat, bits, row_min_bits, bounds, seeds, collect, windows, cols):
    """Write each cell's truncated lower-bound cost (its cost, or its table row's minimum for an
    arrival-time cell) into ``bounds`` (as bits), over the cells of ``windows`` (n, 4: r0, r1,
    c0, c1; overlaps allowed). With ``collect``, return how many fell, their indices first in
    ``seeds``."""
    count = 0
    for w in range(windows.shape[0]):
        for row in range(windows[w, 0], windows[w, 1]):
            for i in range(row * cols + windows[w, 2], row * cols + windows[w, 3]):
                b = bits[U(i)]
                if b & _SIGN:
                    b = row_min_bits[int(-flat[U(i)]) - 1]
                else:
                    b &= _TRUNCATE_MASK
                old = bounds[U(i)]
                if b != old:
                    if collect and b < old:
                        seeds[U(count)] = i
                        count += 1
                    bounds[U(i)] = b
    return count


@numba.njit(cache=True, nogil=True)
def _bound(h_mark, h_stamp, h_g, radius, scale, target_row, target_col, cols, index):
    """X(index): the stored value, or the radius bound."""
    if h_mark[U(index)] == h_stamp:
        return h_g[U(index)]
    row = index // cols
    dr = abs(row - target_row)
    dc = abs(index - row * cols - target_col)
    return radius - scale * (max(dr, dc) + (SQRT2 - 1.0) * min(dr, dc))


@numba.njit(cache=True, nogil=True)
def _repair(bounds, rows, cols, goal, seeds, count, h_mark, h_stamp, h_g, radius, scale,
            target, seen, seen_stamp):
    """Restore X's consistency on ``bounds`` after the cells ``seeds[:count]`` became cheaper:
    lower X where a cheaper step allows, then propagate the decreases in increasing X. Lowered
    values are stored (mark = stamp). Each cell next to a seed is looked at once (``seen[n] ==
    seen_stamp`` after; neighbouring seeds share most of them): one lowered later is pushed, and
    its propagation lowers the others as needed. Returns how many values were lowered."""
    h_stamp = np.uint32(h_stamp)
    seen_stamp = np.uint32(seen_stamp)
    target_row = target // cols
    target_col = target - target_row * cols
    heap = [(0.0, np.int64(0)) for _ in range(0)]
    for s in range(count):
        x = np.int64(seeds[U(s)])
        x_row = x // cols
        x_col = x - x_row * cols
        # every step whose cost fell has an end within one cell of x (a diagonal past x too)
        for row in range(max(x_row - 1, 0), min(x_row + 2, rows)):
            for col in range(max(x_col - 1, 0), min(x_col + 2, cols)):
                n = row * cols + col
                if seen[U(n)] == seen_stamp:
                    continue
                seen[U(n)] = seen_stamp
                c_n = np.float64(bounds[U(n)])
                if n == goal or c_n == np.inf:
                    continue
                best = np.inf
                for r in range(max(row - 1, 0), min(row + 2, rows)):
                    for c in range(max(col - 1, 0), min(col + 2, cols)):
                        m = r * cols + c
                        c_m = np.float64(bounds[U(m)])
                        if m == n or c_m == np.inf:
                            continue
                        step = 1.0
                        if r != row and c != col:
                            if bounds[U(row * cols + c)] == np.inf and bounds[U(r * cols + col)] == np.inf:
                                continue
                            step = SQRT2
                        value = 0.5 * step * (c_n + c_m) + _bound(h_mark, h_stamp, h_g, radius, scale, target_row,
                                                                  target_col, cols, m)
                        if value < best:
                            best = value
                if best < _bound(h_mark, h_stamp, h_g, radius, scale, target_row, target_col, cols, n):
                    h_g[U(n)] = best
                    h_mark[U(n)] = h_stamp
                    heapq.heappush(heap, (best, n))
    lowered = 0
    while len(heap) > 0:
        value, n = heapq.heappop(heap)
        if value > h_g[U(n)]:
            continue   # lowered again after this entry was pushed
        lowered += 1
        row = n // cols
        col = n - row * cols
        c_n = np.float64(bounds[U(n)])
        for r in range(max(row - 1, 0), min(row + 2, rows)):
            for c in range(max(col - 1, 0), min(col + 2, cols)):
                p = r * cols + c
                if p == n or p == goal:
                    continue
                c_p = np.float64(bounds[U(p)])
                if c_p == np.inf:
                    continue
                step = 1.0
                if r != row and c != col:
                    if bounds[U(row * cols + c)] == np.inf and bounds[U(r * cols + col)] == np.inf:
                        continue
                    step = SQRT2
                candidate = 0.5 * step * (c_p + c_n) + value
                if candidate < _bound(h_mark, h_stamp, h_g, radius, scale, target_row, target_col, cols, p):
                    h_g[U(p)] = candidate
                    h_mark[U(p)] = h_stamp
                    heapq.heappush(heap, (candidate, p))
    return lowered


@dataclass(frozen=True, slots=True)
class ReplanStats:
    """What the last ``Replanner.search`` did: whether it refreshed (a backward A*, and how many
    cells it closed), how many cells became cheaper, how many bounds the repair lowered, and how
    many cells the forward A* expanded."""

    refreshed: bool
    backward_expanded: int
    cheaper_cells: int
    repaired: int
    expanded: int


class Replanner:
    """Searches to one goal again and again on changing grids (module docstring).

    One per planning thread (it owns two SearchWorkspaces). A new goal, grid shape or ``c_min``
    starts it afresh by itself; ``reset()`` does it explicitly. Use one per kind of grid (the social
    plan and the non-social baseline differ everywhere, so sharing one would refresh every time)."""

    def __init__(self, workspace: SearchWorkspace | None = None, *, refresh_fraction: float = 0.25,
                 margin_cells: float = 10.0) -> None:
        if not 0.0 < refresh_fraction:
            raise ValueError(f"refresh_fraction must be > 0, got {refresh_fraction}")
        if not 0.0 < margin_cells:
            raise ValueError(f"margin_cells must be > 0, got {margin_cells}")
        self.margin_cells = margin_cells
        self.workspace = workspace if workspace is not None else SearchWorkspace()
        self.refresh_fraction = refresh_fraction
        self._backward = SearchWorkspace()   # its g and closed marks are X's stored values
        self._key: tuple[int, int, int, float] | None = None
        self._bounds = np.empty(0, dtype=np.float32)
        # Builds the arrival-time grids of the maps it searches (plan.plan), so that the
        # bounds' pass covers only the windows that changed (incremental.py).
        self.costs = IncrementalTimeCosts()
        self._seeds = np.empty(0, dtype=np.int32)
        self._row_min = np.empty(0, dtype=np.float32)   # the table's truncated row minima at the last pass
        self._seen = np.zeros(0, dtype=np.uint32)
        self._seen_stamp = 0
        self._learned: LearnedBounds | None = None
        self._backward_expanded = 0
        self._stale = True
        self.last: ReplanStats | None = None

    def reset(self) -> None:
        """Forget everything learned (the next search refreshes)."""
        self._key = None

    def search(self, cost: NDArray[np.floating] | TimeCosts, start: tuple[int, int], goal: tuple[int, int], *,
               c_min: float | None = None) -> GridPath:
        """A* from ``start`` to ``goal`` (row, col) like search.search_cells, reusing earlier
        searches to the same goal. Raises the PlanningError subclasses."""
        problem = prepare(cost, start, goal, c_min)
        key = (problem.rows, problem.cols, problem.goal, problem.c_min)
        cells = problem.rows * problem.cols
        reused = key == self._key and self._learned is not None
        if self._bounds.shape[0] != cells:
            self._bounds = np.empty(cells, dtype=np.float32)
            self._seeds = np.empty(cells, dtype=np.int32)
            self._seen, self._seen_stamp = np.zeros(cells, dtype=np.uint32), 0
            self.costs.synced(False)   # the new bounds hold nothing yet: a full pass
        row_min = truncate_down(problem.table.min(axis=1) if problem.table is not None else np.zeros(1))
        self._key = None   # until the bounds and X agree again
        ours = cost is self.costs.current   # its changes since our last pass are known
        windows = self.costs.changes() if ours else None
        if windows is None:
            windows = np.array([[0, problem.rows, 0, problem.cols]], dtype=np.int64)
        elif not np.array_equal(row_min, self._row_min):   # coded cells' bounds moved with the table
            windows = np.concatenate([windows, self.costs.space_windows()])
        cheaper = _update_bounds(problem.flat, problem.flat.view(np.uint32), row_min.view(np.uint32),
                                 self._bounds.view(np.uint32), self._seeds, reused, windows, problem.cols)
        self.costs.synced(ours)
        self._row_min = row_min
        refresh = not reused or self._stale
        repaired, backward_expanded = 0, 0
        if refresh:
            self._learned = None
            backward_expanded = self._refresh(problem)
        else:
            assert self._learned is not None
            learned = self._learned
            repaired = _repair(self._bounds, problem.rows, problem.cols, problem.goal, self._seeds, cheaper,
                               learned.mark, learned.stamp, learned.g, learned.radius, learned.scale, learned.target,
                               *self._next_seen())
        self._key = key
        found = run_search(problem, self.workspace, learned=self._learned)
        self._stale = found.expanded + repaired > self.refresh_fraction * self._backward_expanded
        self.last = ReplanStats(refreshed=refresh, backward_expanded=backward_expanded,
                                cheaper_cells=int(cheaper) if reused else 0, repaired=int(repaired),
                                expanded=found.expanded)
        return found

    def _next_seen(self) -> tuple[NDArray[np.uint32], int]:
        """The repair's marks of the cells it looked at, and a new stamp for them (no reset)."""
        if self._seen_stamp >= _MAX_STAMP:
            self._seen[:] = 0
            self._seen_stamp = 0
        self._seen_stamp += 1
        return self._seen, self._seen_stamp

    def _refresh(self, problem: SearchProblem) -> int:
        """A* from the goal to the robot on the lower-bound grid; its closed cells' costs become X.
        Raises NoPathFound (nothing is then learned) when even the bounds do not connect them."""
        scale = float(truncate_down(problem.c_min))
        backward = SearchProblem(flat=self._bounds, rows=problem.rows, cols=problem.cols, start=problem.goal,
                                 goal=problem.start, c_min=scale, table=None, cells_per_bin=1.0)
        found = run_search(backward, self._backward, beyond=self.margin_cells)
        ws = self._backward
        self._learned = LearnedBounds(mark=ws.mark, stamp=ws.stamp + 1, g=ws.g,
                                      radius=(found.cost_cells + self.margin_cells) / (1.0 + _TIE_BREAK),
                                      scale=scale, target=problem.start)
        self._backward_expanded = found.expanded
        return found.expanded


def warm_up() -> None:
    """Compile (or load from numba's disk cache) the replanning kernels."""
    grid = np.ones((5, 5), dtype=np.float32)
    replanner = Replanner()
    replanner.search(grid, (0, 0), (4, 4))
    grid[2, 2] = 3.0
    replanner.search(grid, (0, 1), (4, 4))
    grid[2, 2] = 1.0
    replanner.search(grid, (1, 0), (4, 4))
    coded = grid.copy()
    coded[3, 3] = -1.0
    replanner.search(TimeCosts(coded, np.full((1, 2), 2.0), 1.0), (1, 1), (4, 4))
