"""Paths on the cost grid after the search: what a polyline costs, and where the nearest free cell is.

Why here and not in the navigation agent: the agent judges its current path against a new one
(``path_cost``) and moves a blocked start or goal to free floor (``nearest_free``); both must mean
what the planner means by cost and by a cell, so they are written once, on the planner's own
step rule (search.step_cost), the polyline splitting the band shares (split_gaps) and its cells
(GridSpec.cell_of / GridSpec.centres).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from agents.lib.socialmap.grid import GridSpec
from agents.lib.planning.search import StartOccupied, step_cost


def densify(points: NDArray[np.float64], step_m: float) -> NDArray[np.float64]:
    """The polyline's vertices and evenly spaced points in between, at most ``step_m`` apart:
    each gap split into ceil(length / step_m) parts.  Why not elastic_band.resample: that one
    forgives 1e-9 of rounding (a cell-to-cell step of exactly one resolution is two half cells
    there, three here when its float length rounds up), and the navigation agent's replan
    decisions compare path_cost values taken with this count; both share the splitting (split_gaps)."""
    if len(points) < 2:
        return points
    gaps = np.hypot(*np.diff(points, axis=0).T)
    return split_gaps(points, np.maximum(np.ceil(gaps / step_m), 1).astype(np.int64))


def path_cost(grid: NDArray[np.floating], spec: GridSpec, points: NDArray[np.float64]) -> float:
    """Cost of a polyline on ``grid`` by the planner's step rule (``step_cost``: L times the mean of
    the two cells), sampled every half cell; inf when it crosses a non-traversable cell.  The same
    units as ``Path.cost`` (cost-weighted metres), so a current path and a new plan compare."""
    if len(points) < 2:
        return 0.0
    dense = densify(points, spec.resolution / 2)
    costs = grid[spec.clipped_cells(dense)]
    if not np.all(np.isfinite(costs)):
        return math.inf
    step = np.hypot(*np.diff(dense, axis=0).T)
    return float(np.sum(step_cost(step, costs[:-1], costs[1:])))


def nearest_free(grid: NDArray[np.floating], spec: GridSpec, xy: tuple[float, float],
                 max_m: float = 1.0) -> tuple[float, float]:
    """The centre of the nearest traversable cell: the way out when someone stepped up to the robot
    (its start lies in their intimate zone) or the robot was pushed against an inflated wall."""
    found = nearest_free_where(grid, spec, xy, max_m, lambda x, y: True)
    if found is None:
        raise StartOccupied(f"no free cell within {max_m} m of ({xy[0]:.2f}, {xy[1]:.2f})")
    return found


def nearest_free_where(grid: NDArray[np.floating], spec: GridSpec, xy: tuple[float, float], max_m: float,
                       inside: Callable[[float, float], bool]) -> tuple[float, float] | None:
    """The centre of the traversable cell nearest to ``xy`` (inside the grid) within ``max_m`` for
    which ``inside(x, y)`` holds, or None."""
    row, col = spec.cell_of(*xy)
    reach = int(max_m / spec.resolution)
    r0, r1 = max(0, row - reach), min(grid.shape[0], row + reach + 1)
    c0, c1 = max(0, col - reach), min(grid.shape[1], col + reach + 1)
    rows, cols = np.nonzero(np.isfinite(grid[r0:r1, c0:c1]))
    squared = (rows + r0 - row) ** 2 + (cols + c0 - col) ** 2
    for k in np.argsort(squared, kind="stable"):
        if squared[k] > reach * reach:
            break
        x, y = spec.centres(np.array([[rows[k] + r0, cols[k] + c0]]))[0]
        if inside(float(x), float(y)):
            return float(x), float(y)
    return None


def split_gaps(points: NDArray[np.float64], pieces: NDArray[np.int64]) -> NDArray[np.float64]:
    """The polyline with gap i split evenly into ``pieces[i]`` (>= 1) parts; the vertices stay.
    (Shared by ``densify`` and elastic_band.resample, which count the pieces their own way.)"""
    if np.all(pieces == 1):
        return points
    segment = np.repeat(np.arange(len(pieces)), pieces)
    first = np.repeat(np.cumsum(pieces) - pieces, pieces)
    frac = (np.arange(len(segment)) - first) / np.repeat(pieces, pieces)
    inner = points[segment] + frac[:, None] * (points[segment + 1] - points[segment])
    return np.vstack([inner, points[-1:]])
