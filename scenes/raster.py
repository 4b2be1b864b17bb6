"""Which cell centres of a regular grid lie in a polygon: shapely's answer, at scan-line speed.

Why: "a cell belongs to a shape when its centre does" is the grid's rule (agents/lib/socialmap/
grid.py), and shapely's ``intersects_xy`` decides it exactly, boundary included.  On a building map
of 2,000 x 1,200 cells that test costs about half a second, most of the time it takes to load the
map.  Here an even-odd scan line classifies every cell, and shapely decides only the cells the
boundary passes through (the only ones whose centre can be on or within float noise of it), so the
result is the same cell for cell (``tests/unit/test_occupancy_map.py`` compares them).
"""

from __future__ import annotations

import numpy as np
import shapely
from numpy.typing import NDArray
from shapely.geometry.base import BaseGeometry

_MAX_CROSSING_ENTRIES = 4_000_000   # rows x edges per scan-line chunk (memory bound)


def _edges(geometry: BaseGeometry) -> NDArray[np.float64]:
    """(E, 4) x1, y1, x2, y2 of every ring of every polygon."""
    rings = []
    for polygon in getattr(geometry, "geoms", [geometry]):
        if polygon.is_empty:
            continue
        for ring in (polygon.exterior, *polygon.interiors):
            coords = np.asarray(ring.coords, dtype=np.float64)
            rings.append(np.hstack([coords[:-1], coords[1:]]))
    return np.vstack(rings) if rings else np.empty((0, 4))


def cells_in_polygon(geometry: BaseGeometry, xs: NDArray[np.float64], ys: NDArray[np.float64]) -> NDArray[np.bool_]:
    """``shapely.intersects_xy(geometry, xs[None, :], ys[:, None])`` for a (Multi)Polygon and evenly
    spaced cell centres ``xs`` (columns) and ``ys`` (rows)."""
    xs = np.asarray(xs, dtype=np.float64)
    ys = np.asarray(ys, dtype=np.float64)
    if geometry.is_empty or len(xs) == 0 or len(ys) == 0:
        return np.zeros((len(ys), len(xs)), dtype=bool)
    if geometry.geom_type not in ("Polygon", "MultiPolygon") or len(xs) < 2 or len(ys) < 2:
        shapely.prepare(geometry)
        return shapely.intersects_xy(geometry, xs[np.newaxis, :], ys[:, np.newaxis])
    step_x, step_y = float(xs[1] - xs[0]), float(ys[1] - ys[0])
    edges = _edges(geometry)
    n_rows, n_cols = len(ys), len(xs)
    toggles = np.zeros((n_rows, n_cols + 1), dtype=np.uint8)   # parity survives uint8 wrap-around
    ax, ay, bx, by = edges.T
    chunk = max(1, _MAX_CROSSING_ENTRIES // max(1, len(edges)))
    for start in range(0, n_rows, chunk):
        y = ys[start:start + chunk, np.newaxis]
        crosses = ((ay <= y) & (y < by)) | ((by <= y) & (y < ay))     # half-open: vertices count once
        rows, which = np.nonzero(crosses)
        if len(rows) == 0:
            continue
        yr = ys[start + rows]
        x = ax[which] + (yr - ay[which]) * (bx[which] - ax[which]) / (by[which] - ay[which])
        first_right = np.clip(np.floor((x - xs[0]) / step_x).astype(np.int64) + 1, 0, n_cols)
        np.add.at(toggles, (start + rows, first_right), 1)
    inside = (np.cumsum(toggles[:, :n_cols], axis=1, dtype=np.uint8) & 1).astype(bool)
    # Cells the boundary passes through: their centre may lie on it, let shapely decide those.
    # A centre within float noise of an edge has the edge crossing its cell over about a cell's
    # length, so samples half a cell apart along every edge find all such cells.
    lengths = np.hypot(bx - ax, by - ay)
    samples = np.maximum(2, np.ceil(lengths / (0.5 * min(abs(step_x), abs(step_y)))).astype(np.int64) + 1)
    owner = np.repeat(np.arange(len(edges)), samples)
    offsets = np.concatenate([[0], np.cumsum(samples)[:-1]])
    fractions = (np.arange(int(samples.sum())) - offsets[owner]) / (samples[owner] - 1)
    px = ax[owner] + fractions * (bx - ax)[owner]
    py = ay[owner] + fractions * (by - ay)[owner]
    cols = np.floor((px - xs[0]) / step_x + 0.5).astype(np.int64)
    rows = np.floor((py - ys[0]) / step_y + 0.5).astype(np.int64)
    keep = (cols >= 0) & (cols < n_cols) & (rows >= 0) & (rows < n_rows)
    rows, cols = np.divmod(np.unique(rows[keep] * n_cols + cols[keep]), n_cols)
    shapely.prepare(geometry)
    inside[rows, cols] = shapely.intersects_xy(geometry, xs[cols], ys[rows])
    return inside
