"""A global planner: the physical map plus a flat "bubble" of extra cost around every person.

Shows the easiest planner: a chronav GridPlanner subclass that only says which cost grid to
search; chronav's A* searches it, checks the path and handles a docked start.
"""

from __future__ import annotations

import numpy as np

from agents.lib.planning.planners import GridPlanner
from agents.lib.socialmap.social_map import SocialMap

BUBBLE_M = 1.2      # radius of the bubble around a person's centre (m)
BUBBLE_COST = 3.0   # cost of a cell inside it (1 = free floor)


class BubblePlanner(GridPlanner):
    """Shortest path that pays 3x inside 1.2 m of anyone (a flat proxemic bubble, no agenda)."""

    def grid(self, smap: SocialMap) -> np.ndarray:
        def build() -> np.ndarray:
            grid = smap.physical.copy()              # walls, bodies, footprints: inf where blocked
            xs = smap.spec.xs()[np.newaxis, :]             # cell centres (m)
            ys = smap.spec.ys()[:, np.newaxis]
            for person in smap.people:
                inside = np.hypot(xs - person.x, ys - person.y) < BUBBLE_M
                grid[inside & np.isfinite(grid)] = np.maximum(grid[inside & np.isfinite(grid)], BUBBLE_COST)
            return grid
        return smap.cached(("example_bubble",), build)

    def cheapest(self, smap: SocialMap) -> float:
        return smap.params.grid.free_cost
