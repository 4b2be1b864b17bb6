"""chronav's social costs as Nav2 costmap-filter masks (OccupancyGrid values 0..100).

Why two masks: Nav2 takes extra costs through its costmap filters.  The *keepout* filter (type 0)
writes each mask cell into the costmap as ``round(value * 254 / 100)`` (100 is lethal; values in
between are "preferred lanes" costs), so it can carry chronav's graded costs; the *speed* filter
(type 1: percent of the robot's top speed, ``limit = base + multiplier * value``, 0 = no limit)
makes the robot slow down where chronav's costs say people are.

Only the social layers are exported (people's bodies and zones, object footprints and interaction
spaces at R(t)); the building's walls are already in the map Nav2 loads, and Nav2 inflates them
itself.  The mapping (docs/maps.md has the table):

* keepout: ``value = rint(99 (c - c_free) / (c_max - c_free))`` for a traversable cost c, 100 for a
  forbidden cell (intimate zone, body, footprint, forbidden-while-active space); c_max is the
  largest traversable cost the map can hold (max of the personal cost and R's maximum: 4 by
  default, so free 0, social 33, personal 99, R from 1.5 to 3.5 is 16..82).  Reading it back gives
  ``c_free + value (c_max - c_free) / 99``: the bands exactly, R within half a step (0.015).
* speed: free cells 0 (no limit); a cell costing c per metre ``rint(100 c_free / c)`` percent (a
  cell twice as costly is driven at half speed: social 50 %, personal 25 %); forbidden cells
  FORBIDDEN_SPEED_PERCENT.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numba
import numpy as np
from numpy.typing import NDArray

from agents.lib.socialmap.grid import COST_DTYPE, CostArray, compose
from agents.lib.socialmap.social_map import SocialMap, SocialMapParams

KEEPOUT_FILTER_TYPE = 0        # nav2_msgs/CostmapFilterInfo: keepout / preferred lanes
SPEED_FILTER_PERCENT_TYPE = 1  # speed limit in % of the robot's maximum speed
KEEPOUT_STEPS = 99             # traversable costs take 0..99; 100 is lethal
LETHAL = 100
FORBIDDEN_SPEED_PERCENT = 10   # where chronav forbids the robot to be: crawl out


@dataclass(frozen=True)
class MaskScale:
    """How chronav costs become keepout values and back: ``cost = base + multiplier * value``."""

    free_cost: float
    max_cost: float

    @classmethod
    def for_params(cls, params: SocialMapParams) -> MaskScale:
        grid, chron = params.grid, params.chronemics
        return cls(free_cost=grid.free_cost, max_cost=max(grid.social_cost, grid.personal_cost, chron.r_max,
                                                          grid.free_cost + 1e-6))

    @property
    def base(self) -> float:
        return self.free_cost

    @property
    def multiplier(self) -> float:
        return (self.max_cost - self.free_cost) / KEEPOUT_STEPS


def social_costs(smap: SocialMap) -> CostArray:
    """The social layers of a map (departure-time: R at the map's time) over free floor, no walls."""
    free = np.full(smap.spec.shape, smap.params.grid.free_cost, dtype=COST_DTYPE)
    return compose(free, (*smap.obstacle_patches, *smap.zone_patches, *smap.interaction_patches))


def keepout_values(costs: CostArray, scale: MaskScale) -> NDArray[np.int8]:
    """Keepout mask values (0..99 traversable, 100 forbidden) of a cost grid.

    One compiled pass (the ROS bridge converts a 1000 x 600 grid several times a second; six
    numpy passes took 14 ms of CPU), in the grid's own float type as numpy would compute it."""
    costs = np.ascontiguousarray(costs)
    if costs.dtype not in (np.float32, np.float64):
        costs = costs.astype(np.float64)
    out = np.empty(costs.shape, dtype=np.int8)
    _keepout_kernel(costs.reshape(-1), costs.dtype.type(scale.free_cost), costs.dtype.type(scale.multiplier),
                    out.reshape(-1))
    return out


@numba.njit(cache=True, nogil=True)
def _keepout_kernel(costs: Any, free: Any, multiplier: Any, out: Any) -> None:
    for i in range(costs.size):
        c = costs[i]
        if not np.isfinite(c):
            out[i] = LETHAL
        else:
            graded = np.rint((c - free) / multiplier)
            out[i] = 0 if graded < 0 else (KEEPOUT_STEPS if graded > KEEPOUT_STEPS else np.int8(graded))


def costs_from_keepout(values: NDArray[np.integer], scale: MaskScale) -> NDArray[np.float64]:
    """The inverse of :func:`keepout_values` (inf where the mask is lethal or unknown)."""
    values = np.asarray(values)
    costs = scale.base + scale.multiplier * values.astype(np.float64)
    return np.where((values >= LETHAL) | (values < 0), math.inf, costs)


def speed_values(costs: CostArray, scale: MaskScale) -> NDArray[np.int8]:
    """Speed mask values, percent of the top speed (0: no limit)."""
    finite = np.isfinite(costs)
    with np.errstate(divide="ignore"):
        percent = np.rint(100.0 * scale.free_cost / np.where(finite, costs, 1.0))
    percent = np.clip(percent, 1, 100)
    out = np.where(finite, percent, FORBIDDEN_SPEED_PERCENT)
    out[finite & (costs <= scale.free_cost)] = 0
    return out.astype(np.int8)
