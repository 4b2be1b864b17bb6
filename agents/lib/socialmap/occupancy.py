"""Walls given as grid cells (a building's occupancy map): inflation, rays and clearance.

Why a layer of its own: polyline walls are exact segments, but a SLAM map's walls are thousands of
cells.  Turning them into segments would make every laser scan and every personal-space ray test
thousands of segments; instead each question is answered on the grid itself:

* :meth:`OccupancyLayer.inflated` - cells a robot of radius r cannot have its centre in: those whose
  centre lies within ``r + resolution / 2`` of a wall cell's centre (a wall cell is a square: for a
  straight wall that is exactly "within r of its face", the rule polyline walls follow in grid.py).
  A disc dilation done as one 1-D maximum filter per row offset (O(cells), not O(cells x disc)).
* :meth:`OccupancyLayer.ray_ranges` - distance along rays to the first wall cell: a march at a
  quarter cell, then the exact entry into the cell that stopped it (a ray that only clips a
  cell's corner over less than a quarter cell is missed).
* :meth:`OccupancyLayer.clearance` - distance from a point to the nearest wall cell's square.

Outside the map counts as wall when ``outside_blocked`` (the map's unknown cells are walls: what
lies beyond the map is unknown too).
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from agents.lib.socialmap.grid import GridSpec
from agents.lib.socialmap.types import SocialMapInputError

RAY_STEP_CELLS = 0.25


@dataclass(frozen=True, eq=False)
class OccupancyLayer:
    """Wall cells on a grid: ``blocked[row, col]``, row 0 at ``spec.y0`` (as every chronav grid)."""

    spec: GridSpec
    blocked: NDArray[np.bool_]
    outside_blocked: bool = True
    name: str = ""
    _inflated: dict[float, NDArray[np.bool_]] = field(default_factory=dict, repr=False)
    key: str = field(init=False, default="")   # content digest: static maps built on it are cached by it

    def __post_init__(self) -> None:
        if self.blocked.shape != self.spec.shape or self.blocked.dtype != np.bool_:
            raise SocialMapInputError(f"occupancy {self.name!r}: mask of shape {self.blocked.shape} and type "
                                      f"{self.blocked.dtype} does not fit a {self.spec.shape} grid of booleans")
        object.__setattr__(self, "key", hashlib.blake2b(np.packbits(self.blocked).tobytes(), digest_size=16,
                                                        person=b"chronav-occ").hexdigest()
                           + f"/{self.spec}/{self.outside_blocked}")

    # ------------------------------------------------------------------ inflation
    def inflated(self, radius_m: float) -> NDArray[np.bool_]:
        """Cells whose centre is within ``radius_m + res / 2`` of a wall cell's centre (cached)."""
        radius_m = float(radius_m)
        if radius_m not in self._inflated:
            self._inflated[radius_m] = dilate_disc(self.blocked, radius_m / self.spec.resolution + 0.5)
        return self._inflated[radius_m]

    def sample(self, mask: NDArray[np.bool_], spec: GridSpec) -> NDArray[np.bool_]:
        """``mask`` (on this layer's grid) read at the centres of ``spec``'s cells; outside the map
        it is ``outside_blocked``.  The identity when ``spec`` is this layer's grid."""
        if spec == self.spec:
            return mask
        cols = np.floor((spec.xs() - self.spec.x0) / self.spec.resolution).astype(np.int64)
        rows = np.floor((spec.ys() - self.spec.y0) / self.spec.resolution).astype(np.int64)
        col_ok = (cols >= 0) & (cols < self.spec.cols)
        row_ok = (rows >= 0) & (rows < self.spec.rows)
        out = np.full(spec.shape, self.outside_blocked, dtype=bool)
        inner = mask[np.ix_(rows[row_ok], cols[col_ok])]
        out[np.ix_(np.nonzero(row_ok)[0], np.nonzero(col_ok)[0])] = inner
        return out

    def inflated_at(self, x: float, y: float, radius_m: float) -> bool:
        """Is (x, y) in a cell :meth:`inflated` by ``radius_m`` (or outside a blocked-outside map)?"""
        cell = self._cell(x, y)
        return self.outside_blocked if cell is None else bool(self.inflated(radius_m)[cell])

    def blocked_at(self, x: float, y: float) -> bool:
        cell = self._cell(x, y)
        return self.outside_blocked if cell is None else bool(self.blocked[cell])

    def _cell(self, x: float, y: float) -> tuple[int, int] | None:
        col = math.floor((x - self.spec.x0) / self.spec.resolution)
        row = math.floor((y - self.spec.y0) / self.spec.resolution)
        if 0 <= row < self.spec.rows and 0 <= col < self.spec.cols:
            return row, col
        return None

    # ------------------------------------------------------------------ rays
    def ray_ranges(self, x: float, y: float, angles: NDArray[np.float64], max_range_m: float) -> NDArray[np.float64]:
        """Distance from (x, y) along each angle (rad, world frame) to the first wall cell; inf when
        none lies within ``max_range_m``; 0 when (x, y) is itself in a wall cell."""
        angles = np.asarray(angles, dtype=np.float64)
        out = np.full(angles.shape, np.inf)
        if len(angles) == 0:
            return out
        if self.blocked_at(x, y):
            return np.zeros(angles.shape)
        res = self.spec.resolution
        step = RAY_STEP_CELLS * res
        ts = np.arange(1, math.ceil(max_range_m / step) + 1) * step
        dx, dy = np.cos(angles), np.sin(angles)
        cols = np.floor((x + dx[:, None] * ts - self.spec.x0) / res).astype(np.int64)
        rows = np.floor((y + dy[:, None] * ts - self.spec.y0) / res).astype(np.int64)
        inside = (rows >= 0) & (rows < self.spec.rows) & (cols >= 0) & (cols < self.spec.cols)
        hit = np.full(rows.shape, self.outside_blocked)
        hit[inside] = self.blocked[rows[inside], cols[inside]]
        any_hit = hit.any(axis=1)
        first = np.argmax(hit, axis=1)
        ray = np.nonzero(any_hit)[0]
        if len(ray) == 0:
            return out
        k = first[ray]
        # Exact entry into the cell that stopped the march (slab method), not before the last free sample.
        cx0 = self.spec.x0 + cols[ray, k] * res
        cy0 = self.spec.y0 + rows[ray, k] * res
        with np.errstate(divide="ignore", invalid="ignore"):
            tx = np.where(dx[ray] > 0, (cx0 - x) / dx[ray], np.where(dx[ray] < 0, (cx0 + res - x) / dx[ray], -np.inf))
            ty = np.where(dy[ray] > 0, (cy0 - y) / dy[ray], np.where(dy[ray] < 0, (cy0 + res - y) / dy[ray], -np.inf))
        previous = np.where(k > 0, ts[np.maximum(k - 1, 0)], 0.0)
        entry = np.clip(np.maximum(tx, ty), previous, ts[k])
        within = entry <= max_range_m
        out[ray[within]] = entry[within]
        return out

    # ------------------------------------------------------------------ clearance
    def clearance(self, x: float, y: float, reach_m: float) -> float:
        """Distance from (x, y) to the nearest wall cell's square (0 inside one); inf when none lies
        within ``reach_m``.  Outside a blocked-outside map, the map's border is a wall too."""
        spec, res = self.spec, self.spec.resolution
        nearest = math.inf
        if self.outside_blocked:
            xmin, ymin, xmax, ymax = spec.bounds
            if not (xmin <= x <= xmax and ymin <= y <= ymax):
                return 0.0
            border = min(x - xmin, xmax - x, y - ymin, ymax - y)
            if border <= reach_m:
                nearest = border
        c0 = max(0, math.floor((x - reach_m - spec.x0) / res))
        c1 = min(spec.cols, math.floor((x + reach_m - spec.x0) / res) + 1)
        r0 = max(0, math.floor((y - reach_m - spec.y0) / res))
        r1 = min(spec.rows, math.floor((y + reach_m - spec.y0) / res) + 1)
        if c1 <= c0 or r1 <= r0:
            return nearest
        rows, cols = np.nonzero(self.blocked[r0:r1, c0:c1])
        if len(rows) == 0:
            return nearest
        gap_x = np.maximum(np.abs(spec.x0 + (cols + c0 + 0.5) * res - x) - res / 2, 0.0)
        gap_y = np.maximum(np.abs(spec.y0 + (rows + r0 + 0.5) * res - y) - res / 2, 0.0)
        found = float(np.min(np.hypot(gap_x, gap_y)))
        return min(nearest, found) if found <= reach_m else nearest


def dilate_disc(mask: NDArray[np.bool_], radius_cells: float) -> NDArray[np.bool_]:
    """Cells whose centre is within ``radius_cells`` (centre to centre) of a True cell.

    A disc is a stack of horizontal runs: for each row offset dy the run's half width is
    floor(sqrt(r^2 - dy^2)).  One prefix sum along the rows gives every run width at the cost of a
    subtraction (a run holds a True cell iff its window sum is positive); the runs are then shifted
    up and down.  O(cells x radius), with small constants: ~15 passes over the grid at r = 9.5."""
    if radius_cells < 1.0 or not mask.any():
        return mask.copy()
    reach = math.floor(radius_cells)
    rows, cols = mask.shape
    # padded[:, j] = number of True cells in the row before column j - reach - 1 (clipped to the row).
    count_dtype = np.uint16 if cols < 65535 else np.uint32
    padded = np.empty((rows, cols + 2 * reach + 1), dtype=count_dtype)
    padded[:, :reach + 1] = 0
    np.cumsum(mask, axis=1, dtype=count_dtype, out=padded[:, reach + 1:reach + 1 + cols])
    padded[:, reach + 1 + cols:] = padded[:, reach + cols:reach + cols + 1]
    out = mask.copy()
    widened: dict[int, NDArray[np.bool_]] = {}
    for dy in range(reach + 1):
        half = math.floor(math.sqrt(max(0.0, radius_cells * radius_cells - dy * dy)) + 1e-9)
        if half not in widened:
            widened[half] = (padded[:, reach + half + 1:reach + half + 1 + cols]
                             != padded[:, reach - half:reach - half + cols])
        run = widened[half]
        if dy == 0:
            out |= run
        elif dy < rows:
            out[dy:] |= run[:-dy]
            out[:-dy] |= run[dy:]
    return out
