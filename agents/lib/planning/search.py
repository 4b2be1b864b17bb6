"""A* and Dijkstra on the cost grid (numba), with optional arrival-time costs.

Semantics (docs: /work/shared/notes/planner.md). 8-connected; a step from cell a to its
neighbour b costs ``L * (c_a + c_b) / 2`` with L = 1 or sqrt(2) cells (times the resolution, so
``Path.cost`` is a cost-weighted length in metres); the start costs nothing. A diagonal step is
refused when both cells it squeezes between are blocked (a robot does not pass through a
corner-to-corner gap; scipy/skimage/pyastar2d all allow it). A* uses ``c_min * octile`` as its
heuristic (admissible because no step is cheaper than ``L c_min``). Its priority key is
``g + (1 + 1e-9) c_min octile``: the tiny weight breaks ties between equal f towards the larger g,
so on open floor it expands little more than the cells along the path, at the price of a result
that may exceed the optimum by a factor of at most 1 + 1e-9 (far below what a cost-map can mean;
the tests compare with scipy at a relative 1e-7). The open list is an indexed 4-ary heap with
decrease-key (one entry per open cell). A* may also take learned per-cell lower bounds of the
cost to the goal (replan.py): its heuristic is then the larger of those and ``c_min`` octile.

Arrival-time costs (``TimeCosts``): some cells (the objects' interaction spaces) do not have one
cost but a cost per distance travelled, i.e. per arrival time t0 + distance / cruise speed. Such a
cell holds a negative code ``-(row + 1)`` into ``table``, whose row gives its cost per distance bin
(arrival.py builds both; one grid, so the kernel reads no extra array). The search charges such a
cell with the value at the length of the best path found to it. This is a label-setting
approximation of a time-dependent shortest path (no waiting, first-found length); it is exact when
no interaction space changes cost during the trip.

numba: compiled on first call (several seconds) and cached on disk (``cache=True``); call
``warm_up()`` once per process to keep compilation out of timed code.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from agents.lib.socialmap.grid import GridSpec, TimeCosts

SQRT2 = math.sqrt(2.0)
_TIE_BREAK = 1e-9   # A* key g + (1 + 1e-9) c_min h: among equal f, the larger g (closer to the goal) first


def step_cost(length: ArrayLike, c_a: ArrayLike, c_b: ArrayLike) -> NDArray[np.float64] | float:
    """The planner's price of a step of ``length`` from a cell of cost ``c_a`` to one of cost
    ``c_b``: ``length * (c_a + c_b) / 2`` (module doc).  The kernel below inlines this rule
    (``half[k] * (c_a + c_b)``); paths.path_cost prices any polyline with it, and
    tests/unit/test_social_paths.py checks both agree on a planned path."""
    return np.multiply(length, np.asarray(c_a) + c_b) / 2  # what `length * (...)` calls, typed


class PlanningError(RuntimeError):
    """No path could be planned; subclasses say why."""


class OutsideMap(PlanningError):
    """The start or the goal is outside the grid."""


class StartOccupied(PlanningError):
    """The start cell is not traversable (wall, footprint, body, intimate zone, forbidden space)."""


class GoalOccupied(PlanningError):
    """The goal cell is not traversable."""


class NoPathFound(PlanningError):
    """Start and goal are traversable but not connected."""


@dataclass(frozen=True, slots=True)
class GridPath:
    """A search result in cells: (n, 2) rows/cols from start to goal, and its cost in cell units."""

    cells: NDArray[np.int64]
    cost_cells: float
    expanded: int


# An indexed 4-ary min-heap of (key, cell) in two parallel arrays plus ``pos`` (cell -> slot), so that
# a cheaper path to an open cell moves its entry up (decrease-key) instead of pushing a duplicate:
# on the 1000^2 benchmark half of all pushes were duplicates and half of all pops stale, and the
# indexed heap halved the search time (tools/bench/bench_planner.py, 1000^2: 97.7k cells expanded either way).
# The heap code is written out inside the kernel: numba calls that take arrays cost reference
# counting on every call, which was measured to double the time of this loop.
# Indices into the big arrays are cast to unsigned (U): numba then skips its negative-index check.
U = np.uint64


@numba.njit(cache=True, nogil=True)
def _search(static, rows, cols, start, goal, c_min, use_heuristic, time_dependent,
            table, cells_per_bin, use_learned, h_mark, h_stamp, h_g, h_radius, h_scale, h_target, beyond, mark,
            stamp, g, parent, pos, length, keys, nodes, order):
    # mark[cell] == stamp: open (g, parent, pos, length valid); stamp + 1: closed; anything else:
    # not reached in this search. So no buffer needs a reset between searches (SearchWorkspace).
    open_s = np.uint32(stamp)
    closed_s = np.uint32(stamp + 1)
    # neighbour k: offsets; k < 4 orthogonal, k >= 4 diagonal; half the step length
    offset = np.array([-cols, cols, -1, 1, -cols - 1, -cols + 1, cols - 1, cols + 1])
    d_row = np.array([-1, 1, 0, 0, -1, -1, 1, 1])
    d_col = np.array([0, 0, -1, 1, -1, 1, -1, 1])
    half = np.array([0.5, 0.5, 0.5, 0.5, 0.5 * SQRT2, 0.5 * SQRT2, 0.5 * SQRT2, 0.5 * SQRT2])
    last_bin = table.shape[1] - 1
    goal_row = goal // cols
    goal_col = goal - goal_row * cols
    h_straight = c_min * (1.0 + _TIE_BREAK) if use_heuristic else 0.0
    h_diagonal = h_straight * (SQRT2 - 1.0)
    learned_weight = 1.0 + _TIE_BREAK
    h_stamp = np.uint32(h_stamp)
    target_row = h_target // cols
    target_col = h_target - target_row * cols

    g[U(start)] = 0.0
    if time_dependent:
        length[U(start)] = 0.0
    mark[U(start)] = open_s
    keys[0] = 0.0
    nodes[0] = start
    pos[U(start)] = 0
    size = 1
    expanded = 0
    found = False
    limit = np.inf   # with beyond >= 0: after the goal, close every cell with a key up to goal's + beyond
    while size > 0:
        top_key = keys[0]
        if top_key > limit:
            break
        node = np.int64(nodes[0])
        un = U(node)
        mark[un] = closed_s
        order[U(expanded)] = node
        expanded += 1
        size -= 1
        if size > 0:   # move the last entry to the root and sift it down
            key = keys[U(size)]
            moved = nodes[U(size)]
            i = 0
            while True:
                first = 4 * i + 1
                if first >= size:
                    break
                uf = U(first)
                best = first
                best_key = keys[uf]
                if first + 3 < size:
                    k1 = keys[uf + U(1)]
                    if k1 < best_key:
                        best_key = k1
                        best = first + 1
                    k1 = keys[uf + U(2)]
                    if k1 < best_key:
                        best_key = k1
                        best = first + 2
                    k1 = keys[uf + U(3)]
                    if k1 < best_key:
                        best_key = k1
                        best = first + 3
                else:
                    for j in range(first + 1, size):
                        if keys[U(j)] < best_key:
                            best_key = keys[U(j)]
                            best = j
                if best_key < key:
                    child = nodes[U(best)]
                    keys[U(i)] = best_key
                    nodes[U(i)] = child
                    pos[U(child)] = i
                    i = best
                else:
                    break
            keys[U(i)] = key
            nodes[U(i)] = moved
            pos[U(moved)] = i
        if node == goal:
            found = True
            if beyond < 0.0:
                break
            limit = top_key + beyond
        node_g = g[un]
        row = node // cols
        col = node - row * cols
        node_len = 0.0
        c_a = np.float64(static[un])
        if time_dependent:
            node_len = length[un]
            if c_a < 0.0:   # arrival-time cell: its cost at the length travelled to it
                j = int(node_len / cells_per_bin)
                c_a = table[int(-c_a) - 1, min(max(j, 0), last_bin)]
        interior = 0 < row < rows - 1 and 0 < col < cols - 1
        for k in range(8):
            if not interior:
                r = row + d_row[k]
                c = col + d_col[k]
                if r < 0 or r >= rows or c < 0 or c >= cols:
                    continue
            nb = node + offset[k]
            ub = U(nb)
            m = mark[ub]
            if m == closed_s:
                continue
            c_b = np.float64(static[ub])
            if c_b == np.inf:
                continue
            if k >= 4:   # no diagonal squeeze between two blocked cells
                if static[U(node + d_col[k])] == np.inf and static[U(node + d_row[k] * cols)] == np.inf:
                    continue
            nb_len = 0.0
            if time_dependent:
                nb_len = node_len + 2.0 * half[k]
                if c_b < 0.0:
                    j = int(nb_len / cells_per_bin)
                    c_b = table[int(-c_b) - 1, min(max(j, 0), last_bin)]
                    if c_b == np.inf:
                        continue
            new_g = node_g + half[k] * (c_a + c_b)
            if m != open_s:
                i = size
                size += 1
            elif new_g < g[ub]:
                i = np.int64(pos[ub])  # type: ignore[assignment]  # numba kernel: numba types it, not mypy
            else:
                continue
            g[ub] = new_g
            parent[ub] = node
            if time_dependent:
                length[ub] = nb_len
            mark[ub] = open_s
            dr = abs(row + d_row[k] - goal_row)
            dc = abs(col + d_col[k] - goal_col)
            if dr > dc:
                h = h_straight * dr + h_diagonal * dc
            else:
                h = h_straight * dc + h_diagonal * dr
            if use_learned:   # LearnedBounds (replan.py): a stored value, else the radius bound
                if h_mark[ub] == h_stamp:
                    h_l = h_g[ub]
                else:
                    tr = abs(row + d_row[k] - target_row)
                    tc = abs(col + d_col[k] - target_col)
                    h_l = h_radius - h_scale * (max(tr, tc) + (SQRT2 - 1.0) * min(tr, tc))
                h_l *= learned_weight
                if h_l > h:
                    h = h_l
            key = new_g + h
            while i > 0:   # sift up (a new entry, or an open one whose key decreased)
                up = (i - 1) >> 2
                up_key = keys[U(up)]
                if key < up_key:
                    above = nodes[U(up)]
                    keys[U(i)] = up_key
                    nodes[U(i)] = above
                    pos[U(above)] = i
                    i = up
                else:
                    break
            keys[U(i)] = key
            nodes[U(i)] = nb
            pos[ub] = i
    if not found:
        return np.empty(0, dtype=np.int64), np.inf, expanded
    count = 1
    node = goal
    while node != start:
        node = parent[U(node)]
        count += 1
    path = np.empty(count, dtype=np.int64)
    node = goal
    for i in range(count - 1, -1, -1):
        path[i] = node
        node = parent[U(node)]
    return path, g[U(goal)], expanded


class SearchWorkspace:
    """Reusable search buffers for grids up to the largest seen.

    Why: a 1000^2 search needs tens of MB of buffers, and on these VMs first-touching that much
    fresh memory was measured at 15-20 ms (page faults), close to the search itself; glibc may hand
    freed blocks of that size back to the OS, so this can recur. Nothing is reset between
    searches: each search gets a new stamp, and a cell's entries count only when its ``mark``
    holds that stamp (so a search touches only the cells it reaches). An agent that plans
    repeatedly keeps one workspace; without one, each search allocates its own (lazily mapped
    zero pages, touched only where the search goes). Not thread-safe: one per planning thread."""

    def __init__(self) -> None:
        self._cells = 0
        self._stamp = 0
        self.mark = np.zeros(0, dtype=np.uint32)
        self.g = np.empty(0)
        self.parent = np.empty(0, dtype=np.int32)
        self.pos = np.empty(0, dtype=np.int32)
        self.length = np.empty(0)
        self.keys = np.empty(0)
        self.nodes = np.empty(0, dtype=np.int32)
        self.order = np.empty(0, dtype=np.int32)

    def next_stamp(self, cells: int) -> int:
        """Buffers for ``cells`` cells, and the stamp of the next search (``stamp + 1`` marks its
        closed cells). The heap holds at most one entry per cell, so it never grows."""
        if cells > self._cells:
            self._cells = cells
            self.mark = np.zeros(cells, dtype=np.uint32)
            self.g = np.empty(cells)
            self.parent = np.empty(cells, dtype=np.int32)
            self.pos = np.empty(cells, dtype=np.int32)
            self.length = np.empty(cells)
            self.keys = np.empty(cells)
            self.nodes = np.empty(cells, dtype=np.int32)
            self.order = np.empty(cells, dtype=np.int32)
            self._stamp = 0
        self._stamp += 2
        if self._stamp >= np.iinfo(np.uint32).max - 2:   # after 2^31 searches: start the stamps again
            self.mark[:] = 0
            self._stamp = 2
        return self._stamp

    @property
    def stamp(self) -> int:
        """The stamp of the last search (0 before any)."""
        return self._stamp


_NO_TABLE = np.zeros((1, 1))
_NO_LEARNED = np.zeros(1)
_NO_MARK = np.zeros(1, dtype=np.uint32)


@dataclass(frozen=True, slots=True)
class SearchProblem:
    """A validated search: the flat float32 grid, start and goal indices, c_min, the arrival table."""

    flat: NDArray[np.float32]
    rows: int
    cols: int
    start: int
    goal: int
    c_min: float
    table: NDArray[np.float64] | None
    cells_per_bin: float


def prepare(cost: NDArray[np.floating] | TimeCosts, start: tuple[int, int], goal: tuple[int, int],
            c_min: float | None = None) -> SearchProblem:
    """Check a search's inputs (raises the PlanningError subclasses) and lay them out for the kernel.

    ``cost`` is a 2-D array of cell costs > 0 (``inf`` for blocked cells; used as float32) or a
    TimeCosts. ``c_min`` must not exceed any traversable cost; by default it is found by scanning
    the grid (which also rejects costs <= 0); callers that know it pass it and skip the scan."""
    table = cost.table if isinstance(cost, TimeCosts) else None
    # float32 like every grid of the map: one compiled specialisation (compiling takes seconds).
    grid = np.ascontiguousarray(cost.grid if isinstance(cost, TimeCosts) else cost, dtype=np.float32)
    if grid.ndim != 2:
        raise ValueError(f"cost must be a 2-D array, got shape {grid.shape}")
    rows, cols = grid.shape
    if rows * cols >= 2**31:
        raise ValueError(f"a {rows} x {cols} grid has too many cells for the search (at most 2^31)")
    for name, (r, c), error in (("start", start, StartOccupied), ("goal", goal, GoalOccupied)):
        if not (0 <= r < rows and 0 <= c < cols):
            raise OutsideMap(f"{name} cell ({r}, {c}) is outside the {rows} x {cols} grid")
        if not np.isfinite(grid[r, c]):
            raise error(f"{name} cell ({r}, {c}) is not traversable")
    if table is not None and grid[start] < 0 and not np.isfinite(table[int(-grid[start]) - 1, 0]):
        raise StartOccupied(f"start cell {start} is in an interaction space forbidden at departure")
    if c_min is None:
        finite = grid[np.isfinite(grid)]
        if table is not None:
            finite = np.concatenate([finite[finite > 0], table[np.isfinite(table)].ravel()])
        c_min = float(finite.min()) if finite.size else 1.0
    if not c_min > 0.0:
        raise ValueError(f"costs must be > 0 (smallest is {c_min})")
    return SearchProblem(flat=grid.reshape(-1), rows=rows, cols=cols, start=int(start[0] * cols + start[1]),
                         goal=int(goal[0] * cols + goal[1]), c_min=float(c_min),
                         table=None if table is None else np.ascontiguousarray(table, dtype=np.float64),
                         cells_per_bin=float(cost.cells_per_bin) if isinstance(cost, TimeCosts) else 1.0)


@dataclass(frozen=True, slots=True)
class LearnedBounds:
    """Lower bounds of each cell's cost to the goal, learned by earlier searches (replan.py).

    A cell whose ``mark`` equals ``stamp`` has the bound ``g``; any other cell has
    ``radius - scale * octile(cell, target)``. The search's heuristic is the larger of this and
    ``c_min * octile(cell, goal)``; the caller guarantees it is consistent."""

    mark: NDArray[np.uint32]
    stamp: int
    g: NDArray[np.float64]
    radius: float
    scale: float
    target: int


def run_search(problem: SearchProblem, workspace: SearchWorkspace, *, heuristic: bool = True,
               learned: LearnedBounds | None = None, beyond: float = -1.0) -> GridPath:
    """The kernel on a prepared problem, optionally with learned lower bounds (replan.py). With
    ``beyond`` >= 0 the search goes on after reaching the goal until it has closed every cell whose
    key is at most the goal's plus ``beyond`` (``expanded`` counts them all)."""
    stamp = workspace.next_stamp(problem.rows * problem.cols)
    time_dependent = problem.table is not None
    table = problem.table if problem.table is not None else _NO_TABLE
    if learned is None:
        bounds = (False, _NO_MARK, 1, _NO_LEARNED, -np.inf, 0.0, 0)
    else:
        bounds = (True, learned.mark, learned.stamp, learned.g, learned.radius, learned.scale, learned.target)
    indices, cost_cells, expanded = _search(
        problem.flat, problem.rows, problem.cols, problem.start, problem.goal, problem.c_min, heuristic,
        time_dependent, table, problem.cells_per_bin, *bounds, float(beyond), workspace.mark, stamp, workspace.g,
        workspace.parent, workspace.pos, workspace.length, workspace.keys, workspace.nodes, workspace.order)
    if indices.size == 0:
        raise NoPathFound(f"no path from cell {divmod(problem.start, problem.cols)} to cell "
                          f"{divmod(problem.goal, problem.cols)}")
    cells = np.column_stack([indices // problem.cols, indices % problem.cols])
    return GridPath(cells=cells, cost_cells=float(cost_cells), expanded=int(expanded))


def search_cells(cost: NDArray[np.floating] | TimeCosts, start: tuple[int, int], goal: tuple[int, int], *,
                 heuristic: bool = True, c_min: float | None = None,
                 workspace: SearchWorkspace | None = None) -> GridPath:
    """A* (``heuristic=True``) or Dijkstra from ``start`` to ``goal`` (row, col).

    ``cost`` is a 2-D array of cell costs > 0 (``inf`` for blocked cells; used as float32) or a
    TimeCosts.
    ``c_min`` must not exceed any traversable cost; by default it is found by scanning the grid
    (which also rejects costs <= 0); callers that know it pass it and skip the scan. Raises the
    PlanningError subclasses."""
    problem = prepare(cost, start, goal, c_min)
    return run_search(problem, workspace if workspace is not None else SearchWorkspace(), heuristic=heuristic)


@dataclass(frozen=True, slots=True)
class Path:
    """A planned path: cells (n, 2) row/col, their centres ``points_m`` (n, 2) x/y from start to
    goal, and ``cost``, the cost-weighted length in metres (sum of L (c_a + c_b) / 2, L in m)."""

    cells: NDArray[np.int64]
    points_m: NDArray[np.float64]
    cost: float
    expanded: int

    @property
    def length_m(self) -> float:
        """Geometric length of the polyline through the cell centres."""
        if len(self.points_m) < 2:
            return 0.0
        return float(np.sum(np.hypot(*np.diff(self.points_m, axis=0).T)))


class GridSearcher(Protocol):
    """Something that searches a grid like ``search_cells`` (replan.Replanner)."""

    def search(self, cost: NDArray[np.floating] | TimeCosts, start: tuple[int, int], goal: tuple[int, int], *,
               c_min: float | None = None) -> GridPath: ...


def plan_on_grid(cost: NDArray[np.floating] | TimeCosts, spec: GridSpec, start_xy: tuple[float, float],
                 goal_xy: tuple[float, float], *, method: str = "astar", c_min: float | None = None,
                 workspace: SearchWorkspace | None = None, searcher: GridSearcher | None = None) -> Path:
    """Plan between two points in metres on ``cost`` laid out by ``spec`` (A* or Dijkstra).
    ``searcher`` (A* only) replaces the one-off search, e.g. by a replan.Replanner that reuses
    earlier searches to the same goal."""
    if method not in ("astar", "dijkstra"):
        raise ValueError(f"method must be 'astar' or 'dijkstra', got {method!r}")
    if searcher is not None and method != "astar":
        raise ValueError("a replanning searcher needs method='astar'")
    cells = []
    for name, (x, y) in (("start", start_xy), ("goal", goal_xy)):
        if not spec.contains_xy(x, y):
            raise OutsideMap(f"{name} ({x:g}, {y:g}) is outside the map {spec.bounds}")
        cells.append(spec.cell_of(x, y))
    try:
        if searcher is not None:
            found = searcher.search(cost, cells[0], cells[1], c_min=c_min)
        else:
            found = search_cells(cost, cells[0], cells[1], heuristic=method == "astar", c_min=c_min,
                                 workspace=workspace)
    except StartOccupied as exc:  # messages in metres: the (row, col) of a cell means nothing to a user
        why = "forbidden at departure" if "departure" in str(exc) else "blocked"
        raise StartOccupied(f"start ({start_xy[0]:.2f}, {start_xy[1]:.2f}) m is {why}") from None
    except GoalOccupied:
        raise GoalOccupied(f"goal ({goal_xy[0]:.2f}, {goal_xy[1]:.2f}) m is blocked") from None
    except NoPathFound:
        raise NoPathFound(f"no path from ({start_xy[0]:g}, {start_xy[1]:g}) to "
                          f"({goal_xy[0]:g}, {goal_xy[1]:g})") from None
    return Path(cells=found.cells, points_m=spec.centres(found.cells), cost=found.cost_cells * spec.resolution,
                expanded=found.expanded)


def warm_up() -> None:
    """Compile (or load from the on-disk cache) the search kernel: one specialisation serves A*,
    Dijkstra and arrival-time costs (all float32 grids, float64 tables)."""
    grid = np.ones((4, 4), dtype=np.float32)
    search_cells(grid, (0, 0), (3, 3))
    coded = grid.copy()
    coded[1, 1] = -1.0
    search_cells(TimeCosts(coded, np.full((1, 2), 2.0), 1.0), (0, 0), (3, 3), heuristic=False)
