"""The grids chronav shows ROS 2, built once here for the live bridge and the MCAP export.

- the building (``/map``): the walls and closed doors as the planner rasterises them, without the
  robot's inflation (what a map_server would serve): 100 occupied, 0 free;
- the social costmap (``/social_costmap``): the navigation's departure-time social grid
  (``SocialMap.cost``) in the keepout scale of ``chronav map export`` (0 free .. 99, 100 lethal,
  walls included);
- the keepout filter mask (``/keepout_filter_mask``): the social layers only, exactly the mask
  ``chronav map export`` writes (agents/lib/socialmap/nav2.py).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from agents.lib.socialmap.nav2 import MaskScale, keepout_values, social_costs
from agents.lib.socialmap.social_map import SocialMap
from agents.world.navigation import NavigationMaps
from scenes.model import Scene


@dataclass(frozen=True)
class Grid:
    values: np.ndarray                 # int8 (rows along +y, columns along +x)
    origin: tuple[float, float]
    resolution: float


class RosMaps:
    """The navigation's maps of one scene, and the building without inflation."""

    def __init__(self, scene: Scene) -> None:
        self.nav = NavigationMaps.for_scene(scene)
        self._walls = NavigationMaps.for_scene(scene, margin_m=-scene.robot.radius)
        self.scale = MaskScale.for_params(self.nav.params)

    def building(self, closed: Sequence[str] = ()) -> Grid:
        static = self._walls.static(closed=closed)
        values = np.where(np.isfinite(static.grid), 0, 100).astype(np.int8)
        return Grid(values, (static.spec.x0, static.spec.y0), static.spec.resolution)

    def social(self, smap: SocialMap) -> tuple[Grid, Grid]:
        """(social costmap, keepout filter mask) of a social map."""
        origin, res = (smap.spec.x0, smap.spec.y0), smap.spec.resolution
        return (Grid(keepout_values(smap.cost, self.scale), origin, res),
                Grid(keepout_values(social_costs(smap), self.scale), origin, res))
