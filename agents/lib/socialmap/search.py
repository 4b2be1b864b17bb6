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
the tests compare with scipy at a relative 1e-7). One heap entry is (key, cell); stale entries are
skipped when their cell is already closed.

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

import numba
import numpy as np
from numpy.typing import NDArray

from agents.lib.socialmap.grid import GridSpec

SQRT2 = math.sqrt(2.0)
_TIE_BREAK = 1e-9   # A* key g + (1 + 1e-9) c_min h: among equal f, the larger g (closer to the goal) first


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
class TimeCosts:
    """A cost grid in which some cells have arrival-time costs.

    ``grid[r, c]`` > 0 is an ordinary cost (inf: blocked); < 0 is ``-(k + 1)``: the cell costs
    ``table[k, j]`` when reached after travelling between ``j`` and ``j + 1`` bins of
    ``cells_per_bin`` cells (the last column holds for longer trips)."""

    grid: NDArray[np.float32]
    table: NDArray[np.float64]
    cells_per_bin: float


@dataclass(frozen=True, slots=True)
class GridPath:
    """A search result in cells: (n, 2) rows/cols from start to goal, and its cost in cell units."""

    cells: NDArray[np.int64]
    cost_cells: float
    expanded: int


# A 4-ary min-heap of (key, cell) in two parallel arrays: shallower than a binary heap, and the
# four children of a node share a cache line (measured 20 % faster on the 1000^2 benchmark).
@numba.njit(cache=True, nogil=True)
def _sift_up(keys, nodes, i):  # type: ignore[no-untyped-def]
    key, node = keys[i], nodes[i]
    while i > 0:
        parent = (i - 1) >> 2
        if key < keys[parent]:
            keys[i], nodes[i] = keys[parent], nodes[parent]
            i = parent
        else:
            break
    keys[i], nodes[i] = key, node


@numba.njit(cache=True, nogil=True)
def _sift_down(keys, nodes, size):  # type: ignore[no-untyped-def]
    key, node = keys[0], nodes[0]
    i = 0
    while True:
        first = 4 * i + 1
        if first >= size:
            break
        child = first
        best = keys[first]
        last = min(first + 4, size)
        for j in range(first + 1, last):
            if keys[j] < best:
                best = keys[j]
                child = j
        if best < key:
            keys[i], nodes[i] = keys[child], nodes[child]
            i = child
        else:
            break
    keys[i], nodes[i] = key, node


@numba.njit(cache=True, nogil=True)
def _cell_cost(static, table, cells_per_bin, index, length):  # type: ignore[no-untyped-def]
    c = np.float64(static[index])
    if c < 0.0:
        j = int(length / cells_per_bin)
        last = table.shape[1] - 1
        if j > last:
            j = last
        elif j < 0:
            j = 0
        c = table[int(-c) - 1, j]
    return c


@numba.njit(cache=True, nogil=True)
def _search(static, rows, cols, start, goal, c_min, use_heuristic, time_dependent,  # type: ignore[no-untyped-def]
            table, cells_per_bin, g, parent, closed, length, keys, nodes):
    # Buffers come from a SearchWorkspace; only g and closed need a reset (parent and length are
    # written before they are read).
    n = rows * cols
    g[:n] = np.inf
    closed[:n] = False
    d_row = np.array([-1, -1, -1, 0, 0, 1, 1, 1])
    d_col = np.array([-1, 0, 1, -1, 1, -1, 0, 1])
    step = np.array([SQRT2, 1.0, SQRT2, 1.0, 1.0, SQRT2, 1.0, SQRT2])
    goal_row, goal_col = goal // cols, goal % cols

    capacity = keys.shape[0]
    g[start] = 0.0
    if time_dependent:
        length[start] = 0.0
    keys[0], nodes[0] = 0.0, start
    size = 1
    expanded = 0
    found = False
    h_weight = c_min * (1.0 + _TIE_BREAK)
    while size > 0:
        node = nodes[0]
        size -= 1
        if size > 0:
            keys[0], nodes[0] = keys[size], nodes[size]
            _sift_down(keys, nodes, size)
        if closed[node]:
            continue
        closed[node] = True
        expanded += 1
        if node == goal:
            found = True
            break
        node_g = g[node]
        row = node // cols
        col = node - row * cols
        node_len = length[node] if time_dependent else 0.0
        c_a = _cell_cost(static, table, cells_per_bin, node, node_len) if time_dependent else np.float64(static[node])
        for k in range(8):
            r = row + d_row[k]
            c = col + d_col[k]
            if r < 0 or r >= rows or c < 0 or c >= cols:
                continue
            nb = r * cols + c
            if closed[nb]:
                continue
            c_b = np.float64(static[nb])
            if c_b == np.inf:
                continue
            if d_row[k] != 0 and d_col[k] != 0:
                if static[row * cols + c] == np.inf and static[r * cols + col] == np.inf:
                    continue
            nb_len = 0.0
            if time_dependent:
                nb_len = node_len + step[k]
                if c_b < 0.0:
                    c_b = _cell_cost(static, table, cells_per_bin, nb, nb_len)
                    if c_b == np.inf:
                        continue
            new_g = node_g + step[k] * (c_a + c_b) * 0.5
            if new_g < g[nb]:
                g[nb] = new_g
                parent[nb] = node
                if time_dependent:
                    length[nb] = nb_len
                key = new_g
                if use_heuristic:
                    dr = abs(r - goal_row)
                    dc = abs(c - goal_col)
                    if dr > dc:
                        key += h_weight * ((dr - dc) + SQRT2 * dc)
                    else:
                        key += h_weight * ((dc - dr) + SQRT2 * dr)
                if size == capacity:
                    capacity *= 2
                    grown_keys = np.empty(capacity)
                    grown_nodes = np.empty(capacity, dtype=np.int32)
                    grown_keys[:size] = keys[:size]
                    grown_nodes[:size] = nodes[:size]
                    keys, nodes = grown_keys, grown_nodes
                keys[size], nodes[size] = key, nb
                size += 1
                _sift_up(keys, nodes, size - 1)
    if not found:
        return np.empty(0, dtype=np.int64), np.inf, expanded, keys, nodes
    count = 1
    node = goal
    while node != start:
        node = parent[node]
        count += 1
    path = np.empty(count, dtype=np.int64)
    node = goal
    for i in range(count - 1, -1, -1):
        path[i] = node
        node = parent[node]
    return path, g[goal], expanded, keys, nodes


class SearchWorkspace:
    """Reusable search buffers (g, parent, closed, lengths, heap) for grids up to the largest seen.

    Why: a 1000^2 search needs 13 MB of buffers, and on these VMs first-touching that much fresh
    memory was measured at 15-20 ms (page faults), close to the search itself; glibc may hand
    freed blocks of that size back to the OS, so this can recur. An agent that plans repeatedly
    keeps one workspace; without one, each search allocates its own. Not thread-safe: one
    workspace per planning thread."""

    def __init__(self) -> None:
        self._cells = 0
        self._g = np.empty(0)
        self._parent = np.empty(0, dtype=np.int32)
        self._closed = np.empty(0, dtype=np.bool_)
        self._length = np.empty(0)
        self.heap_keys = np.empty(1 << 14)
        self.heap_nodes = np.empty(1 << 14, dtype=np.int32)

    def buffers(self, cells: int, time_dependent: bool) -> tuple[np.ndarray, ...]:
        if cells > self._cells:
            self._cells = cells
            self._g = np.empty(cells)
            self._parent = np.empty(cells, dtype=np.int32)
            self._closed = np.empty(cells, dtype=np.bool_)
            self._length = np.empty(0)
        if time_dependent and self._length.shape[0] < cells:
            self._length = np.empty(self._cells)
        length = self._length if time_dependent else _NO_LENGTH
        return self._g, self._parent, self._closed, length, self.heap_keys, self.heap_nodes


_NO_LENGTH = np.zeros(1)
_NO_TABLE = np.zeros((1, 1))


def search_cells(cost: NDArray[np.floating] | TimeCosts, start: tuple[int, int], goal: tuple[int, int], *,
                 heuristic: bool = True, c_min: float | None = None,
                 workspace: SearchWorkspace | None = None) -> GridPath:
    """A* (``heuristic=True``) or Dijkstra from ``start`` to ``goal`` (row, col).

    ``cost`` is a 2-D array of cell costs > 0 (``inf`` for blocked cells; used as float32) or a
    TimeCosts.
    ``c_min`` must not exceed any traversable cost; by default it is found by scanning the grid
    (which also rejects costs <= 0); callers that know it pass it and skip the scan. Raises the
    PlanningError subclasses."""
    table = cost.table if isinstance(cost, TimeCosts) else None
    # float32 like every grid of the map: one compiled specialisation (compiling takes seconds).
    grid = np.ascontiguousarray(cost.grid if isinstance(cost, TimeCosts) else cost, dtype=np.float32)
    if grid.ndim != 2:
        raise ValueError(f"cost must be a 2-D array, got shape {grid.shape}")
    rows, cols = grid.shape
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
    flat = grid.reshape(-1)
    start_index = start[0] * cols + start[1]
    goal_index = goal[0] * cols + goal[1]
    workspace = workspace if workspace is not None else SearchWorkspace()
    buffers = workspace.buffers(rows * cols, table is not None)
    if table is not None:
        result = _search(flat, rows, cols, start_index, goal_index, float(c_min), heuristic, True,
                         np.ascontiguousarray(table, dtype=np.float64), float(cost.cells_per_bin), *buffers)
    else:
        result = _search(flat, rows, cols, start_index, goal_index, float(c_min), heuristic, False,
                         _NO_TABLE, 1.0, *buffers)
    indices, cost_cells, expanded, workspace.heap_keys, workspace.heap_nodes = result
    if indices.size == 0:
        raise NoPathFound(f"no path from cell {start} to cell {goal}")
    cells = np.column_stack([indices // cols, indices % cols])
    return GridPath(cells=cells, cost_cells=float(cost_cells), expanded=int(expanded))


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


def plan_on_grid(cost: NDArray[np.floating] | TimeCosts, spec: GridSpec, start_xy: tuple[float, float],
                 goal_xy: tuple[float, float], *, method: str = "astar", c_min: float | None = None,
                 workspace: SearchWorkspace | None = None) -> Path:
    """Plan between two points in metres on ``cost`` laid out by ``spec`` (A* or Dijkstra)."""
    if method not in ("astar", "dijkstra"):
        raise ValueError(f"method must be 'astar' or 'dijkstra', got {method!r}")
    cells = []
    for name, (x, y) in (("start", start_xy), ("goal", goal_xy)):
        if not spec.contains_xy(x, y):
            raise OutsideMap(f"{name} ({x:g}, {y:g}) is outside the map {spec.bounds}")
        cells.append(spec.cell_of(x, y))
    try:
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
