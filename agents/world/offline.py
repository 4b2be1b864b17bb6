"""The world the agents would hold at a sim time, built without any process: the offline commands.

Why through a DSR graph: `chronav path`, `plan` and `metrics --at t` must see exactly what the
live agents see.  So this module does not derive a map from the scene itself; it writes the
scripted world at ``t`` (``agents/world/timeline.py``) into an in-memory DSR with the agents' own
writer functions (``agents/world/dsr_writers.py``, perception without noise), then reads it back
with the agents' own readers: the navigation's map (``navigation.py``) and the executive's
symbolic graph (``dsr_readers.symbolic_view``).  ``tests/unit/test_world_parity.py`` checks that
the result equals, cell for cell and edge for edge, what the agents hold at that time.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import shapely
from shapely.geometry.base import BaseGeometry

from agents.lib.agenda.chronemics import ChronemicsParams
from agents.lib.metrics.dynamic_metrics import PeopleTracks
from agents.lib.metrics.metrics import MetricsReport, compute_metrics, read_people_csv, read_trajectory_csv
from agents.lib.planning.search import PlanningError
from agents.lib.socialmap.social_map import SocialMap
from agents.lib.planning.plan import PlannerFailed, plan
from agents.world.building import footprint_polygons
from agents.world.dsr_readers import running_activities, symbolic_view
from agents.world.dsr_writers import (write_activities, write_building, write_clock, write_interactions,
                                      write_object, write_object_r, write_person, write_robot)
from agents.world.interactions import interaction_pairs, observed_conversations, scene_conversations
from agents.world.navigation import NavigationMaps
from agents.world.scene_world import SceneWorld, load_world
from agents.world.people import world_at
from dsr import DSRGraph
from scenes.clock import format_clock
from scenes.loader import LoadedScene
from scenes.model import Scene
from scenes.yamlio import SourceError


class OfflineError(Exception):
    """A scene or request that cannot be planned or measured; ``no_path`` when only the plan failed."""

    def __init__(self, message: str, no_path: bool = False) -> None:
        super().__init__(message)
        self.no_path = no_path


def graph_at(world: SceneWorld, t_s: float, robot_pose: tuple[float, float, float] | None = None) -> DSRGraph:
    """The DSR at ``t_s`` as the perceiving agents write it (people without sensor noise).

    ``robot_pose`` puts the robot elsewhere than its scene pose (where a plan starts)."""
    scene = world.scene
    state = world_at(world, t_s)
    graph = DSRGraph(agent="offline")
    write_building(graph, scene, state.doors_open)
    write_clock(graph, scene, t_s, scene.clock.rate)
    spec = scene.robot
    pose = robot_pose or (spec.pose.x, spec.pose.y, spec.pose.theta)
    write_robot(graph, spec, pose, scene.room_at(pose[0], pose[1]), laser_angles=[])
    for obj in scene.objects:
        write_object(graph, obj, scene.room_at(obj.pose.x, obj.pose.y))
    for person in state.people:
        write_person(graph, person.name, person.role, (person.x, person.y, person.theta),
                     scene.room_at(person.x, person.y), t_s, (person.vx, person.vy))
    write_activities(graph, state.agenda)
    write_object_r(graph, state.agenda, t_s, ChronemicsParams())
    positions = {p.name: (p.x, p.y) for p in state.people}
    seen = {p.name: (p.x, p.y, p.theta, math.hypot(p.vx, p.vy)) for p in state.people}
    write_interactions(graph, interaction_pairs(positions, running_activities(graph),
                                                [*scene_conversations(scene), *observed_conversations(seen)]))
    return graph


@dataclass
class SceneMaps:
    """A scene and its navigation maps, reused across many times (reports, tests)."""

    world: SceneWorld
    nav: NavigationMaps
    _graphs: dict[float, DSRGraph] = field(default_factory=dict, repr=False)

    @classmethod
    def load(cls, scene: str | Path | LoadedScene | SceneWorld) -> SceneMaps:
        try:
            world = scene if isinstance(scene, SceneWorld) else load_world(scene)
        except SourceError as exc:
            raise OfflineError(str(exc)) from None
        return cls(world, NavigationMaps.for_scene(world.scene))

    @property
    def cruise_speed(self) -> float:
        return self.nav.cruise_speed_mps

    def graph(self, t_s: float) -> DSRGraph:
        if t_s not in self._graphs:
            self._graphs[t_s] = graph_at(self.world, t_s)
        return self._graphs[t_s]

    def at(self, t_s: float) -> SocialMap:
        return self.nav.build(self.graph(t_s), t_s)

    def symbolic(self, t_s: float) -> Any:
        return symbolic_view(self.graph(t_s))

    def measure(self, trajectory: np.ndarray, t_s: float, people_tracks: PeopleTracks | None = None, *,
                goal_xy: tuple[float, float] | None = None,
                goal_missing: str = "") -> MetricsReport:
        """Seed-table metrics of a trajectory against the people and agenda at ``t_s`` (Psi on the
        zones the planner drew then, adapted to walls, and beside it the unadapted ones), and with
        ``people_tracks`` (a run's people.csv) the metrics among the moving people; ``goal_xy`` the
        target (``goal_missing``: why there is none, for the table)."""
        smap = self.at(t_s)
        report = compute_metrics(trajectory,
                                 people={p.name: (p.x, p.y) for p in smap.people},
                                 objects={s.name: s.footprint for s in smap.object_spaces},
                                 zones=smap.zone_polygons(), unadapted_zones=smap.unadapted_zone_polygons(),
                                 interaction_spaces=smap.interaction_polygons(),
                                 people_tracks=people_tracks, robot_radius_m=self.world.scene.robot.radius,
                                 obstacles=self.obstacles, goal_xy=goal_xy)
        if goal_missing and report.dynamic is not None and goal_xy is None:
            why = {key: goal_missing for key in report.dynamic.missing if "target" in key or key == "completed"}
            report = report.model_copy(update={"dynamic": report.dynamic.model_copy(
                update={"missing": {**report.dynamic.missing, **why}})})
        return report

    @property
    def obstacles(self) -> BaseGeometry:
        """Walls and object footprints: what pushes the robot in the social force model."""
        if "_obstacles" not in self.__dict__:
            self.__dict__["_obstacles"] = scene_obstacles(self.world.scene)
        return self.__dict__["_obstacles"]


def scene_obstacles(scene: Scene) -> BaseGeometry:
    """A scene's walls and object footprints as one geometry (what pushes in the social force model)."""
    walls = [shapely.LineString(w) for w in scene.walls if len(w) >= 2]
    return shapely.union_all([*walls, *footprint_polygons(scene)])


def path_as_trajectory(points: np.ndarray, t0_s: float, speed_mps: float) -> np.ndarray:
    """A planned polyline driven at constant speed, heading along each segment (for metrics)."""
    seg = np.diff(points, axis=0)
    lengths = np.hypot(seg[:, 0], seg[:, 1])
    t = t0_s + np.concatenate([[0.0], np.cumsum(lengths)]) / speed_mps
    heading = np.arctan2(seg[:, 1], seg[:, 0]) if len(seg) else np.zeros(0)
    theta = np.concatenate([heading[:1], heading]) if len(heading) else np.zeros(len(points))
    return np.column_stack([t, points[:, 0], points[:, 1], theta])


def check_within_day(world: SceneWorld, t_s: float, option: str = "--at") -> None:
    """Refuse a time outside the scene's day (its clock's start to end).

    Why: nobody and nothing is simulated there (the people and the agenda start with the day), so a
    plan at 08:00 on a 09:00-18:00 scene silently showed the world at 09:00."""
    clock = world.scene.clock
    if not clock.start_s <= t_s <= clock.end_s:
        raise OfflineError(f"{option} {format_clock(t_s)} is outside the day of scene {world.scene.name!r}, which "
                           f"runs {format_clock(clock.start_s)}-{format_clock(clock.end_s)} (its clock: start, end); "
                           "give a time within it")


def plan_offline(scene: str | Path, t_s: float, start: tuple[float, float], goal: tuple[float, float], *,
                 planner: str = "social", method: str = "astar", controller: str | None = None) -> dict[str, Any]:
    """One plan with ``planner`` (agents/lib/planning/planners.py) plus its metrics, as a JSON-ready
    dict; with ``controller``, that local controller driven along it (offline_drive.py). ``t_s``
    must lie within the scene's day."""
    maps = SceneMaps.load(scene)
    check_within_day(maps.world, t_s)
    smap = maps.at(t_s)
    try:
        path = plan(smap, start, goal, method=method, planner=planner, cruise_speed_mps=maps.cruise_speed)
    except PlanningError as exc:
        raise OfflineError(f"no path from ({start[0]:g}, {start[1]:g}) to ({goal[0]:g}, {goal[1]:g}) m at "
                           f"{format_clock(t_s)}: {exc}", no_path=True) from None
    except PlannerFailed as exc:
        raise OfflineError(f"plug-in refused: {exc}", no_path=True) from None
    points = np.vstack([path.points_m])
    report = maps.measure(path_as_trajectory(points, t_s, maps.cruise_speed), t_s)
    metrics: dict[str, Any] = {"psi_percent": report.psi_zone_percent,
                               "psi_interaction_percent": report.psi_object_percent,
                               "d_min_person_m": report.d_min_person_m, "d_min_object_m": report.d_min_object_m}
    if report.psi_unadapted_zone_percent:  # the wall adaptation changed someone's space (docs/metrics.md)
        metrics["psi_unadapted_zone_percent"] = report.psi_unadapted_zone_percent
    return {
        "scene": maps.world.scene.name, "t_s": t_s, "planner": planner, "baseline": planner == "baseline",
        "arrival_time": planner == "social",
        "method": method, "cost": path.cost, "length_m": path.length_m, "expanded": path.expanded,
        "points": points.round(3).tolist(),
        "objects": {s.name: {"R": s.r, "band": s.band, "active": s.active} for s in smap.object_spaces},
        "metrics": metrics,
        **({} if controller is None else
           {"controller": {"name": controller, **_driven(controller, maps, smap, points, t_s)}}),
    }


def _driven(controller: str, maps: SceneMaps, smap: SocialMap, points: np.ndarray, t_s: float) -> dict[str, Any]:
    """The controller driven along the path, with the path's metrics on what it drove."""
    from agents.world.offline_drive import drive   # only `chronav path --controller` needs it

    driven = drive(controller, maps.nav, smap, points, t_s)
    out = driven.as_dict()
    if len(driven.trajectory) >= 2:
        report = maps.measure(driven.trajectory, t_s)
        out["metrics"] = {"psi_percent": report.psi_zone_percent,
                          "psi_interaction_percent": report.psi_object_percent,
                          "d_min_person_m": report.d_min_person_m, "d_min_object_m": report.d_min_object_m}
    return out


def _check_on_map(world: SceneWorld, traj: np.ndarray, source: Path) -> None:
    """A trajectory none of whose samples is in the scene's rooms belongs to another scene (or
    another frame): measuring it would report distances to people it never met."""
    scene = world.scene
    building = shapely.union_all([shapely.Polygon(r.polygon) for r in scene.rooms])
    inside = shapely.intersects_xy(building, traj[:, 1], traj[:, 2])
    if not inside.any():
        xmin, ymin, xmax, ymax = scene.bounds
        raise OfflineError(f"{source}: no sample of the trajectory lies in a room of {scene.name!r} (samples span "
                           f"x {traj[:, 1].min():g}..{traj[:, 1].max():g} m, y {traj[:, 2].min():g}.."
                           f"{traj[:, 2].max():g} m; the building spans x {xmin:g}..{xmax:g} m, y {ymin:g}..{ymax:g} m); "
                           "is it a trajectory of this scene?")


def metrics_offline(scene: str | Path, trajectory_csv: Path, at_s: float | None,
                    people_csv: Path | None = None, *, definitions: str = "published",
                    goal_xy: tuple[float, float] | None = None, robot_radius_m: float | None = None,
                    person_radius_m: float | None = None) -> dict[str, Any]:
    """`chronav metrics`: the metrics of a trajectory (``definitions`` "published", the papers', or
    "hunav", HuNavSim's evaluator with its quirks and metric names: dynamic_metrics.py), with the
    people's trajectories when known (``people_csv``, by default the run's people.csv beside it).
    ``goal_xy``: the target (completed, distances to target); radii default to the scene's robot and
    0.25 m people (published) or HuNavSim's 0.35 m for both (hunav)."""
    from agents.lib.metrics.dynamic_metrics import HUNAV_RADIUS_M, PERSON_RADIUS_M, hunav_metrics

    if definitions not in ("published", "hunav"):
        raise OfflineError(f"--definitions: expected published or hunav, got {definitions!r}")
    try:    # the scene alone (its navigation maps only for the published definitions' Psi and d_min)
        world = scene if isinstance(scene, SceneWorld) else load_world(scene)
    except SourceError as exc:
        raise OfflineError(str(exc)) from None
    traj = read_trajectory_csv(trajectory_csv)
    _check_on_map(world, traj, trajectory_csv)
    if people_csv is None and (trajectory_csv.parent / "people.csv").exists():
        people_csv = trajectory_csv.parent / "people.csv"
    tracks = read_people_csv(people_csv) if people_csv is not None else None
    if at_s is None:
        first = float(traj[0, 0])
        at_s = first if first >= 3600.0 else world.scene.clock.start_s
    if not math.isfinite(at_s):
        raise OfflineError("--at must be a finite time")
    head = {"scene": world.scene.name, "at_s": at_s, "definitions": definitions,
            "people": None if people_csv is None else str(people_csv)}
    if definitions == "hunav":
        values, missing = hunav_metrics(traj, tracks, robot_radius_m=robot_radius_m or HUNAV_RADIUS_M,
                                        person_radius_m=person_radius_m or HUNAV_RADIUS_M, goal_xy=goal_xy,
                                        obstacles=scene_obstacles(world.scene))
        return {**head, "robot_radius_m": robot_radius_m or HUNAV_RADIUS_M,
                "person_radius_m": person_radius_m or HUNAV_RADIUS_M, "metrics": values, "missing": missing,
                "table": hunav_table(values, missing)}
    maps = SceneMaps.load(world)
    report = maps.measure(traj, at_s, tracks, goal_xy=goal_xy)
    if tracks is not None and (robot_radius_m is not None or person_radius_m is not None):
        from agents.lib.metrics.dynamic_metrics import dynamic_metrics

        report = report.model_copy(update={"dynamic": dynamic_metrics(
            traj, tracks, robot_radius_m or maps.world.scene.robot.radius, maps.obstacles,
            person_radius_m=person_radius_m or PERSON_RADIUS_M, goal_xy=goal_xy)})
    return {**head, "metrics": report.model_dump(), "table": report.to_table()}


def hunav_table(values: dict[str, Any], missing: dict[str, str]) -> list[tuple[str, str]]:
    """(HuNavSim metric name with chronav's label and unit, value) rows for `--definitions hunav`."""
    from agents.lib.metrics.metric_catalog import BY_HUNAV

    rows = []
    for key, value in values.items():
        metric = BY_HUNAV.get(key)
        label = f"{key} ({metric.unit})" if metric and metric.unit else key
        if value is None:
            rows.append((label, f"- ({missing.get(key, 'not measurable')})"))
        elif isinstance(value, bool):
            rows.append((label, "yes" if value else "no"))
        elif isinstance(value, int):
            rows.append((label, str(value)))
        else:
            rows.append((label, f"{value:.4f}"))
    return rows
