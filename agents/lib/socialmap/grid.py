"""The cost grid: geometry, rasterisation and Nav2-style layer composition.

A cell's cost is what the robot pays per metre through it: 1 free, 2 social, 4 personal, R(t) in
an interaction space, ``inf`` where it may not go (walls inflated by the robot radius, outside
every room, object footprints, people's bodies, intimate zones). Layers do not write into the
master grid directly: each returns ``CostPatch`` windows (only the cells it touches, like a Nav2
layer's update bounds) and ``compose`` takes the cell-wise maximum. Maximum is the rule the seeds
imply: an interaction space inside a personal zone costs max(R, 4), a forbidden cell stays
forbidden whatever else covers it.

Cells are indexed (row, col); row r spans y in [y0 + r res, y0 + (r+1) res), col c spans x.
A cell belongs to a shape when its centre does. Costs are float32 (16 MB at 2000^2).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import shapely
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field
from shapely.geometry.base import BaseGeometry

from agents.lib.socialmap.types import Room, SocialMapInputError, Wall
from scenes.limits import GRID_CELLS
from scenes.raster import cells_in_polygon

if TYPE_CHECKING:
    from agents.lib.socialmap.occupancy import OccupancyLayer

COST_DTYPE = np.float32
CostArray = NDArray[np.float32]
BLOCKED = math.inf


class GridParams(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)

    resolution_m: float = Field(0.05, gt=0, le=1.0, description="cell size")
    robot_radius_m: float = Field(0.3, ge=0, description="walls, footprints and bodies are inflated by it")
    person_radius_m: float = Field(0.25, ge=0, description="a person's body: an obstacle even for the baseline")
    inflate_footprints: bool = Field(True, description="inflate object footprints by the robot radius too")
    free_cost: float = Field(1.0, gt=0)
    social_cost: float = Field(2.0, gt=0, description="seed 5.2.1: twice the free cost")
    personal_cost: float = Field(4.0, gt=0, description="seed 5.2.1: four times the free cost")


class GridTooLargeError(SocialMapInputError):
    """The area and cell size ask for more cells than GRID_CELLS; raised before anything is allocated."""


def grid_shape(bounds: Sequence[float], resolution: float, max_cells: int | None = None) -> tuple[int, int]:
    """(rows, cols) of the grid covering ``bounds`` at ``resolution``, checked against the cell limit.

    Why here, before any array exists: a 2 km x 2 km room at 5 cm is 1.6e9 cells (6.4 GB per
    layer), and 10^6 m asks numpy for petabytes; the check costs nothing and says what to change."""
    if len(bounds) != 4:
        raise SocialMapInputError(f"bounds must be (xmin, ymin, xmax, ymax), got {bounds!r}")
    xmin, ymin, xmax, ymax = (float(b) for b in bounds)
    if not all(math.isfinite(v) for v in (xmin, ymin, xmax, ymax)) or xmax <= xmin or ymax <= ymin:
        raise SocialMapInputError(f"bounds must be finite with xmin < xmax and ymin < ymax, got {bounds!r}")
    if not (math.isfinite(resolution) and resolution > 0):
        raise SocialMapInputError(f"resolution must be a positive number of metres, got {resolution!r}")
    width, height = xmax - xmin, ymax - ymin
    limit = GRID_CELLS.value() if max_cells is None else max_cells
    cols_f, rows_f = width / resolution, height / resolution   # inf for 1e308 m or 5e-324 m cells
    if not (math.isfinite(cols_f) and math.isfinite(rows_f)):
        raise GridTooLargeError(
            f"the map is {_metres(width)} m x {_metres(height)} m; at {resolution:g} m cells that is "
            f"{cols_f:.3g} x {rows_f:.3g} cells, more than the limit of {limit:,} ({GRID_CELLS.env}); "
            + (f"use cells of at least {coarsest:.3g} m (the scene's `resolution`)"
               if math.isfinite(coarsest := math.sqrt(width * height / limit)) else "draw a building of real size"))
    cols = max(1, math.ceil(cols_f - 1e-9))
    rows = max(1, math.ceil(rows_f - 1e-9))
    if rows * cols > limit:
        coarsest = math.sqrt(width * height / limit)
        raise GridTooLargeError(
            f"the map is {_metres(width)} m x {_metres(height)} m; at {resolution:g} m cells that is {cols:,} x {rows:,} = "
            f"{rows * cols:,} cells, more than the limit of {limit:,} ({GRID_CELLS.env}); use cells of at least "
            f"{coarsest:.3g} m (the scene's `resolution`), a smaller building, or raise the limit")
    return rows, cols


def _metres(value: float) -> str:
    if value >= 1e9:   # 1e308 m: a number, not 300 digits
        return f"{value:.3g}"
    return f"{value:,.0f}" if value >= 100 else f"{value:g}"


@functools.lru_cache(maxsize=32)
def cell_centres(origin: float, resolution: float, count: int) -> NDArray[np.float64]:
    """origin + (k + 0.5) resolution for k < count, read-only.  Why cached: every patch of every
    person at every replan asked for its window's centres (GridSpec.xs, ys): a slice of these is the
    same numbers without the arithmetic."""
    centres = origin + (np.arange(count, dtype=np.float64) + 0.5) * resolution
    centres.flags.writeable = False
    return centres


@dataclass(frozen=True, slots=True)
class GridSpec:
    """Where the grid lies: lower-left corner, cell size and shape."""

    x0: float
    y0: float
    resolution: float
    rows: int
    cols: int

    @classmethod
    def from_bounds(cls, bounds: Sequence[float], resolution: float) -> GridSpec:
        """The grid over ``bounds``; GridTooLargeError when it would exceed GRID_CELLS."""
        rows, cols = grid_shape(bounds, resolution)
        return cls(x0=float(bounds[0]), y0=float(bounds[1]), resolution=float(resolution), rows=rows, cols=cols)

    @property
    def shape(self) -> tuple[int, int]:
        return (self.rows, self.cols)

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        return (self.x0, self.y0, self.x0 + self.cols * self.resolution, self.y0 + self.rows * self.resolution)

    def xs(self, cols: slice = slice(None)) -> NDArray[np.float64]:
        """x of the cell centres of ``cols`` (a read-only view of the whole row's, computed once)."""
        start, stop, _ = cols.indices(self.cols)
        return cell_centres(self.x0, self.resolution, self.cols)[start:stop]

    def ys(self, rows: slice = slice(None)) -> NDArray[np.float64]:
        start, stop, _ = rows.indices(self.rows)
        return cell_centres(self.y0, self.resolution, self.rows)[start:stop]

    def contains_xy(self, x: float, y: float) -> bool:
        xmin, ymin, xmax, ymax = self.bounds
        return xmin <= x < xmax and ymin <= y < ymax

    def cell_of(self, x: float, y: float) -> tuple[int, int]:
        """(row, col) of the cell containing (x, y); raises ValueError outside the grid."""
        if not self.contains_xy(x, y):
            raise ValueError(f"({x:g}, {y:g}) is outside the grid {self.bounds}")
        row = min(int((y - self.y0) / self.resolution), self.rows - 1)
        col = min(int((x - self.x0) / self.resolution), self.cols - 1)
        return row, col

    def clipped_cells(self, points: NDArray[np.float64]) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
        """Rows and columns of the cells containing (n, 2) x, y points, a point outside the grid
        taking the nearest border cell (samples of a polyline looked up on the grid)."""
        rows = np.clip(((points[:, 1] - self.y0) / self.resolution).astype(np.intp), 0, self.rows - 1)
        cols = np.clip(((points[:, 0] - self.x0) / self.resolution).astype(np.intp), 0, self.cols - 1)
        return rows, cols

    def centres(self, cells: NDArray[np.integer]) -> NDArray[np.float64]:
        """(n, 2) x, y of the centres of (n, 2) row, col cells."""
        cells = np.asarray(cells)
        return np.column_stack([self.x0 + (cells[:, 1] + 0.5) * self.resolution,
                                self.y0 + (cells[:, 0] + 0.5) * self.resolution])

    def window(self, xmin: float, ymin: float, xmax: float, ymax: float) -> tuple[slice, slice] | None:
        """Rows and cols whose centres may lie in the box, clipped to the grid; None if empty."""
        c0 = max(0, math.floor((xmin - self.x0) / self.resolution - 0.5))
        c1 = min(self.cols, math.ceil((xmax - self.x0) / self.resolution + 0.5))
        r0 = max(0, math.floor((ymin - self.y0) / self.resolution - 0.5))
        r1 = min(self.rows, math.ceil((ymax - self.y0) / self.resolution + 0.5))
        if c1 <= c0 or r1 <= r0:
            return None
        return slice(r0, r1), slice(c0, c1)


@dataclass(frozen=True, slots=True)
class CostPatch:
    """A layer's costs on a window of the grid. 0 means "this layer says nothing here"."""

    rows: slice
    cols: slice
    values: CostArray


def compose(base: CostArray, patches: Iterable[CostPatch]) -> CostArray:
    """A new grid: cell-wise maximum of ``base`` and every patch."""
    out = base.copy()
    compose_into(out, patches)
    return out


def compose_into(out: CostArray, patches: Iterable[CostPatch]) -> None:
    """In-place variant of ``compose`` for the rebuild loop (no extra copy of the grid)."""
    for patch in patches:
        view = out[patch.rows, patch.cols]
        np.maximum(view, patch.values, out=view)


def geometry_mask(spec: GridSpec, geometry: BaseGeometry) -> tuple[slice, slice, NDArray[np.bool_]] | None:
    """Cells whose centre lies in ``geometry`` (boundary included), on the geometry's window."""
    if geometry.is_empty:
        return None
    window = spec.window(*geometry.bounds)
    if window is None:
        return None
    rows, cols = window
    xs, ys = spec.xs(cols), spec.ys(rows)
    shapely.prepare(geometry)
    mask = shapely.intersects_xy(geometry, xs[np.newaxis, :], ys[:, np.newaxis])
    return rows, cols, mask


def geometry_patch(spec: GridSpec, geometry: BaseGeometry, value: float) -> CostPatch | None:
    """``value`` on the cells of ``geometry``, 0 elsewhere in its window."""
    found = geometry_mask(spec, geometry)
    if found is None:
        return None
    rows, cols, mask = found
    return CostPatch(rows, cols, np.where(mask, value, 0.0).astype(COST_DTYPE))


def disc_patch(spec: GridSpec, x: float, y: float, radius: float, value: float) -> CostPatch | None:
    """``value`` on the cells whose centre is within ``radius`` of (x, y)."""
    window = spec.window(x - radius, y - radius, x + radius, y + radius)
    if window is None:
        return None
    rows, cols = window
    dx = spec.xs(cols)[np.newaxis, :] - x
    dy = spec.ys(rows)[:, np.newaxis] - y
    inside = dx * dx + dy * dy <= radius * radius
    return CostPatch(rows, cols, np.where(inside, value, 0.0).astype(COST_DTYPE))


def segment_patch(spec: GridSpec, a: tuple[float, float], b: tuple[float, float], radius: float,
                  value: float) -> CostPatch | None:
    """``value`` on the cells whose centre is within ``radius`` of the segment a-b (an inflated wall)."""
    (ax, ay), (bx, by) = a, b
    window = spec.window(min(ax, bx) - radius, min(ay, by) - radius, max(ax, bx) + radius, max(ay, by) + radius)
    if window is None:
        return None
    rows, cols = window
    px = spec.xs(cols)[np.newaxis, :] - ax
    py = spec.ys(rows)[:, np.newaxis] - ay
    vx, vy = bx - ax, by - ay
    length_sq = vx * vx + vy * vy
    if length_sq == 0.0:
        t = np.zeros(np.broadcast_shapes(px.shape, py.shape))
    else:
        t = np.clip((px * vx + py * vy) / length_sq, 0.0, 1.0)
    dx, dy = px - t * vx, py - t * vy
    inside = dx * dx + dy * dy <= radius * radius + 1e-12
    return CostPatch(rows, cols, np.where(inside, value, 0.0).astype(COST_DTYPE))


def walls_geometry(walls: Sequence[Wall]) -> BaseGeometry | None:
    """All walls as one shapely geometry (for rays and display)."""
    if not walls:
        return None
    return shapely.MultiLineString([list(w.points) for w in walls])


def static_grid(spec: GridSpec, walls: Sequence[Wall], rooms: Sequence[Room], params: GridParams,
                occupancy: OccupancyLayer | None = None) -> CostArray:
    """The part of the grid that only changes when the building does: free cost inside the rooms
    (everywhere if no room is given), blocked outside them and within the robot radius of a wall
    (polylines, and the wall cells of a building map: ``occupancy``, inflated the same way)."""
    if rooms:
        building = shapely.union_all([shapely.Polygon(r.polygon) for r in rooms])
        grid = np.full(spec.shape, BLOCKED, dtype=COST_DTYPE)
        window = None if building.is_empty else spec.window(*building.bounds)
        if window is not None:
            rows, cols = window
            # The same cells as geometry_mask (centre in the polygon), by scan line: rooms cover the map.
            mask = cells_in_polygon(building, spec.xs(cols), spec.ys(rows))
            view = grid[rows, cols]
            view[mask] = params.free_cost
    else:
        grid = np.full(spec.shape, params.free_cost, dtype=COST_DTYPE)
    # At least half a cell diagonal, so that every cell a wall passes through is blocked and the
    # blocked cells form a 4-connected chain that no (non-squeezing) diagonal step can cross.
    radius = max(params.robot_radius_m, spec.resolution * math.sqrt(0.5))
    patches = []
    for wall in walls:
        for a, b in zip(wall.points, wall.points[1:], strict=False):
            patch = segment_patch(spec, a, b, radius, BLOCKED)
            if patch is not None:
                patches.append(patch)
    compose_into(grid, patches)
    if occupancy is not None:
        grid[occupancy.sample(occupancy.inflated(params.robot_radius_m), spec)] = BLOCKED
    return grid


def blocked_core(static: CostArray, spec: GridSpec, depth_m: float) -> NDArray[np.bool_]:
    """The blocked cells of a static grid that stay blocked after peeling ``depth_m`` off every
    blocked region: where the robot's centre would be less than (inflation - depth_m) from a wall.

    Why: the static grid inflates walls by the robot radius, and a local planner (the elastic
    band) legitimately grazes that margin at corners; what it must never do is cut through a wall
    or a door jamb, which this core still marks however thin the wall is."""
    from scipy import ndimage

    blocked = np.isinf(static)
    cells = int(depth_m / spec.resolution)
    if cells <= 0:
        return blocked
    return ndimage.binary_erosion(blocked, iterations=cells, border_value=1)


@dataclass(frozen=True, slots=True)
class TimeCosts:
    """A cost grid in which some cells have arrival-time costs.

    ``grid[r, c]`` > 0 is an ordinary cost (inf: blocked); < 0 is ``-(k + 1)``: the cell costs
    ``table[k, j]`` when reached after travelling between ``j`` and ``j + 1`` bins of
    ``cells_per_bin`` cells (the last column holds for longer trips)."""

    grid: NDArray[np.float32]
    table: NDArray[np.float64]
    cells_per_bin: float
