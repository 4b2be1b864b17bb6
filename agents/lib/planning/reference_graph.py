"""An independent reference for the planner: the same grid as a scipy sparse graph.

Why it exists: the tests check A*/Dijkstra costs against scipy.sparse.csgraph, and the benchmark
times scipy on the same grid. Both need the grid turned into a graph with *our* semantics: edge
a-b weighs L (c_a + c_b) / 2 (L = 1 or sqrt 2, in cells), blocked cells have no edges, and a
diagonal edge is left out when both cells it squeezes between are blocked (scipy itself has no
notion of a grid, so without this rule it would not be the same problem).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

# (d_row, d_col) of the four "forward" neighbours; each edge is added in both directions.
_FORWARD = ((0, 1), (1, 0), (1, 1), (1, -1))


def grid_graph(cost: NDArray[np.floating]) -> csr_matrix:
    """The 8-connected grid graph of ``cost`` (inf = blocked) with the planner's edge rule."""
    grid = np.asarray(cost, dtype=np.float64)
    rows, cols = grid.shape
    free = np.isfinite(grid)
    index = np.arange(rows * cols, dtype=np.int32 if rows * cols < 2**31 else np.int64).reshape(rows, cols)
    sources, targets, weights = [], [], []
    for d_row, d_col in _FORWARD:
        r0, r1 = 0, rows - d_row
        c0, c1 = max(0, -d_col), cols - max(0, d_col)
        a = (slice(r0, r1), slice(c0, c1))
        b = (slice(r0 + d_row, r1 + d_row), slice(c0 + d_col, c1 + d_col))
        ok = free[a] & free[b]
        length = 1.0
        if d_row and d_col:
            length = math.sqrt(2.0)
            side_1 = free[(slice(r0, r1), slice(c0 + d_col, c1 + d_col))]     # (row_a, col_b)
            side_2 = free[(slice(r0 + d_row, r1 + d_row), slice(c0, c1))]     # (row_b, col_a)
            ok &= side_1 | side_2
        w = length * (grid[a] + grid[b]) * 0.5
        sources.append(index[a][ok])
        targets.append(index[b][ok])
        weights.append(w[ok])
    src = np.concatenate(sources + targets)
    dst = np.concatenate(targets + sources)
    wgt = np.concatenate(weights + weights)
    return csr_matrix((wgt, (src, dst)), shape=(rows * cols, rows * cols))


def reference_cost(cost: NDArray[np.floating], start: tuple[int, int], goal: tuple[int, int],
                   graph: csr_matrix | None = None) -> float:
    """Cost (cell units) of the cheapest start-goal path by scipy's Dijkstra; inf if unreachable."""
    cols = np.asarray(cost).shape[1]
    graph = grid_graph(cost) if graph is None else graph
    distances = dijkstra(graph, directed=True, indices=start[0] * cols + start[1])
    return float(distances[goal[0] * cols + goal[1]])
