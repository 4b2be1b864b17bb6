"""The grids chronav shows ROS 2, built once here for the live bridge and the MCAP export.

- the building (``/map``): the walls and closed doors as the planner rasterises them, without the
  robot's inflation (what a map_server would serve): 100 occupied, 0 free;
- the social costmap (``/social_costmap``): the navigation's departure-time social grid
  (``SocialMap.cost``) in the keepout scale of ``chronav map export`` (0 free .. 99, 100 lethal,
  walls included);
- the keepout filter mask (``/keepout_filter_mask``): the social layers only, exactly the mask
  ``chronav map export`` writes (agents/lib/socialmap/nav2.py).

And the one question the bridge asks of a goal before it becomes a mission: can the robot ever
stand there (:meth:`RosMaps.goal_problem`)?
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import shapely

from agents.lib.socialmap.nav2 import MaskScale, keepout_values, social_costs
from agents.lib.socialmap.objects import object_geometry
from agents.lib.socialmap.social_map import SocialMap
from agents.world.dsr_readers import dsr_objects
from agents.world.navigation import NavigationMaps
from dsr.protocols import GraphReader
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

    def goal_problem(self, graph: GraphReader, x: float, y: float, closed: Sequence[str] = ()) -> str | None:
        """Why the robot can never stand at (x, y), or None: outside every room of the building,
        within the robot's radius plus the planning margin of a wall or a closed door (the
        navigation's own static map), or of an object's footprint (where the objects are in the
        DSR).  People and activities are not reasons: they move and end."""
        scene, radius = self.nav.scene, self.nav.params.grid.robot_radius_m
        if scene.rooms and scene.room_at(x, y) is None:
            return f"({x:.2f}, {y:.2f}) is outside the building (in no room of scene {scene.name!r})"
        static = self.nav.static(closed=tuple(closed))
        if not static.spec.contains_xy(x, y) or not np.isfinite(static.grid[static.spec.cell_of(x, y)]):
            return (f"({x:.2f}, {y:.2f}) is within {radius:.2f} m (the robot's radius plus margin) of a wall "
                    "or a closed door")
        point = shapely.Point(x, y)
        for obj in dsr_objects(graph):
            distance = object_geometry(obj).footprint.distance(point)
            if distance <= radius:
                return f"({x:.2f}, {y:.2f}) is {distance:.2f} m from the footprint of object {obj.name!r}"
        return None
