"""The navigation's view of a scene: map parameters, static maps, and the social map from the DSR.

Why one class for the agent and the offline commands: ``chronav path`` promises the map the
navigation agent sees.  Both build it here, from a DSR graph, with the same parameters (grid
resolution, the robot's radius plus a clearance margin, the cruise speed the arrival-time pricing
assumes), so the margin or the cruise factor cannot drift between them.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Sequence
from dataclasses import dataclass, field

from agents.lib.socialmap.adaptive import AdaptiveParams
from agents.lib.socialmap.grid import GridParams
from agents.lib.socialmap.types import Room, Wall
from agents.lib.planning.planners import DEFAULT_PLANNER, check_planner
from agents.lib.planning.protocol import PlannerParams
from agents.lib.socialmap.social_map import SocialMap, SocialMapParams, StaticMap, build_social_map, build_static_map
from agents.world.building import PLANNING_MARGIN_M, closed_door_walls, scene_occupancy, scene_rooms, scene_walls
from agents.world.dsr_readers import closed_doors, dsr_activity_windows, dsr_objects, dsr_people
from dsr.protocols import GraphReader
from scenes.model import Scene

#: static maps kept (the most recently used): a day's missions confine their maps to ever other
#: rooms, and each kept map holds its grids and what the planner derived from them (MBs); kept
#: unbounded, the navigation grew a few MB with each new route all day (docs/long_runs.md)
STATIC_MAPS_KEPT = 4

# PLANNING_MARGIN_M (building.py, where the scene check reads it without importing the planner).
# The navigation expects to average this fraction of the robot's top speed (arrival-time R(t)).
CRUISE_FRACTION = 0.7


@dataclass
class NavigationMaps:
    """Everything needed to build the robot's social map of one scene; static maps are cached per
    (rooms the route is confined to, closed doors), since rasterising the building is the costly
    part: the STATIC_MAPS_KEPT most recently used."""

    scene: Scene
    params: SocialMapParams
    cruise_speed_mps: float
    #: the run's planner (a registered name): what the navigation plans with and judges paths on
    planner: str = DEFAULT_PLANNER
    _statics: OrderedDict[tuple[tuple[str, ...], tuple[str, ...]], StaticMap] = field(default_factory=OrderedDict,
                                                                                      repr=False)

    @classmethod
    def for_scene(cls, scene: Scene, margin_m: float = PLANNING_MARGIN_M,
                  planner: str = DEFAULT_PLANNER) -> NavigationMaps:
        """``planner`` (a registered name, agents/lib/planning/planners.py) is the one navigation
        parameter a study varies: the navigation plans with it and judges paths on its grid;
        registry.UnknownExtension names the choices and their packages."""
        robot = scene.robot
        # the wall adaptation makes room for the robot's body (the seed's d_r: its diameter plus the
        # adaptation's own margin), not for the planning radius, which holds a clearance margin already
        params = SocialMapParams(grid=GridParams(resolution_m=scene.resolution, robot_radius_m=robot.radius + margin_m),
                                 adaptive=AdaptiveParams(robot_diameter_m=2.0 * robot.radius))
        return cls(scene, params, CRUISE_FRACTION * robot.max_speed, check_planner(planner))

    @property
    def planner_params(self) -> PlannerParams:
        """The planning parameters of this scene's navigation (its cruise speed)."""
        return PlannerParams(cruise_speed_mps=self.cruise_speed_mps)

    def __post_init__(self) -> None:
        self._walls = scene_walls(self.scene)
        self._rooms = scene_rooms(self.scene)
        self._occupancy = scene_occupancy(self.scene)

    def _layout(self, route_rooms: Sequence[str], closed: Sequence[str]) -> tuple[list[Wall], list[Room]]:
        rooms = [room for room in self._rooms if room.name in route_rooms] if route_rooms else self._rooms
        return [*self._walls, *closed_door_walls(self.scene, closed)], rooms

    def static(self, route_rooms: Sequence[str] = (), closed: Sequence[str] = ()) -> StaticMap:
        key = (tuple(sorted(route_rooms)), tuple(sorted(closed)))
        found = self._statics.get(key)
        if found is not None:
            self._statics.move_to_end(key)
            return found
        walls, rooms = self._layout(route_rooms, closed)
        found = self._statics[key] = build_static_map(self.scene.bounds, walls, rooms, self.params,
                                                      occupancy=self._occupancy)
        while len(self._statics) > STATIC_MAPS_KEPT:
            self._statics.popitem(last=False)
        return found

    def walls_of_scene(self) -> list[Wall]:
        """The scene's walls (doors open)."""
        return list(self._walls)

    def walls(self, graph: GraphReader) -> list[Wall]:
        """The walls now: the scene's and the closed doors' leaves (what a local controller avoids)."""
        return self._layout((), closed_doors(graph))[0]

    def build(self, graph: GraphReader, now_s: float, route_rooms: Sequence[str] = ()) -> SocialMap:
        """The social map at ``now_s`` from the DSR: people, objects, activities and closed doors
        (a closed door is a wall).  With ``route_rooms`` (the symbolic plan's rooms) other rooms are
        walls, so the metric planner picks doors and way but never crosses a room the plan avoided."""
        closed = closed_doors(graph)
        walls, rooms = self._layout(route_rooms, closed)
        return build_social_map(self.scene.bounds, walls, dsr_people(graph), dsr_objects(graph),
                                dsr_activity_windows(graph), now_s, self.params, rooms=rooms,
                                static=self.static(route_rooms, closed), occupancy=self._occupancy)
