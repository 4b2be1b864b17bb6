"""Social maps and metrics straight from a scene file, without any process or DSR.

Why here: `chronav path`, `chronav metrics`, the demo's report and the system tests must see
the map the navigation agent sees (same parameters from the scene: resolution, robot radius,
cruise speed), built from the scene's ground truth at a given time.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from agents.social_navigation.grid import GridParams
from agents.social_navigation.metrics import MetricsReport, compute_metrics, read_trajectory_csv
from agents.social_navigation.search import PlanningError
from agents.social_navigation.social_map import (SocialMap, SocialMapParams, StaticMap, build_social_map,
                                                  build_static_map, plan)
from agents.world_model import scene_objects, scene_people, scene_rooms, scene_walls
from scenes.loader import LoadedScene, load_scene
from scenes.yamlio import SourceError

CRUISE_FRACTION = 0.7  # the navigation agent expects to average 70 % of the robot's top speed


class OfflineError(Exception):
    """A scene or request that cannot be planned or measured; ``no_path`` when only the plan failed."""

    def __init__(self, message: str, no_path: bool = False) -> None:
        super().__init__(message)
        self.no_path = no_path


@dataclass
class SceneMaps:
    """A loaded scene and its static map, reused across many times (reports, tests)."""

    loaded: LoadedScene
    params: SocialMapParams
    static: StaticMap

    @classmethod
    def load(cls, scene: str | Path | LoadedScene) -> SceneMaps:
        try:
            loaded = scene if isinstance(scene, LoadedScene) else load_scene(scene)
        except SourceError as exc:
            raise OfflineError(str(exc)) from None
        robot = loaded.scene.robot
        params = SocialMapParams(grid=GridParams(resolution_m=loaded.scene.resolution, robot_radius_m=robot.radius))
        static = build_static_map(loaded.scene.bounds, scene_walls(loaded.scene), scene_rooms(loaded.scene), params)
        return cls(loaded, params, static)

    @property
    def cruise_speed(self) -> float:
        return CRUISE_FRACTION * self.loaded.scene.robot.max_speed

    def at(self, t_s: float) -> SocialMap:
        scene = self.loaded.scene
        return build_social_map(scene.bounds, scene_walls(scene), scene_people(scene, t_s), scene_objects(scene),
                                self.loaded.agenda_day.windows(), t_s, self.params, rooms=scene_rooms(scene),
                                static=self.static)

    def measure(self, trajectory: np.ndarray, t_s: float) -> MetricsReport:
        """Seed-table metrics of a trajectory against the people and agenda at ``t_s``."""
        smap = self.at(t_s)
        return compute_metrics(trajectory,
                               people={p.name: (p.x, p.y) for p in smap.people},
                               objects={s.name: s.footprint for s in smap.object_spaces},
                               zones=smap.zone_polygons(),
                               interaction_spaces=smap.interaction_polygons())


def path_as_trajectory(points: np.ndarray, t0_s: float, speed_mps: float) -> np.ndarray:
    """A planned polyline driven at constant speed, heading along each segment (for metrics)."""
    seg = np.diff(points, axis=0)
    lengths = np.hypot(seg[:, 0], seg[:, 1])
    t = t0_s + np.concatenate([[0.0], np.cumsum(lengths)]) / speed_mps
    heading = np.arctan2(seg[:, 1], seg[:, 0]) if len(seg) else np.zeros(0)
    theta = np.concatenate([heading[:1], heading]) if len(heading) else np.zeros(len(points))
    return np.column_stack([t, points[:, 0], points[:, 1], theta])


def plan_offline(scene: str | Path, t_s: float, start: tuple[float, float], goal: tuple[float, float], *,
                 baseline: bool = False, arrival_time: bool = True, method: str = "astar") -> dict[str, Any]:
    """One plan plus its metrics, as a JSON-ready dict."""
    maps = SceneMaps.load(scene)
    smap = maps.at(t_s)
    try:
        path = plan(smap, start, goal, method=method, baseline=baseline, arrival_time=arrival_time,
                    cruise_speed_mps=maps.cruise_speed)
    except PlanningError as exc:
        raise OfflineError(f"no path from {start} to {goal} at {t_s:.0f} s: {exc}", no_path=True) from None
    points = np.vstack([path.points_m])
    report = maps.measure(path_as_trajectory(points, t_s, maps.cruise_speed), t_s)
    return {
        "scene": maps.loaded.scene.name, "t_s": t_s, "baseline": baseline, "arrival_time": arrival_time,
        "method": method, "cost": path.cost, "length_m": path.length_m, "expanded": path.expanded,
        "points": points.round(3).tolist(),
        "objects": {s.name: {"R": s.r, "band": s.band, "active": s.active} for s in smap.object_spaces},
        "metrics": {"psi_percent": report.psi_zone_percent, "psi_interaction_percent": report.psi_object_percent,
                    "d_min_person_m": report.d_min_person_m, "d_min_object_m": report.d_min_object_m},
    }


def metrics_offline(scene: str | Path, trajectory_csv: Path, at_s: float | None) -> dict[str, Any]:
    maps = SceneMaps.load(scene)
    traj = read_trajectory_csv(trajectory_csv)
    if at_s is None:
        first = float(traj[0, 0])
        at_s = first if first >= 3600.0 else maps.loaded.scene.clock.start_s
    if not math.isfinite(at_s):
        raise OfflineError("--at must be a finite time")
    report = maps.measure(traj, at_s)
    return {"scene": maps.loaded.scene.name, "at_s": at_s, "metrics": report.model_dump(), "table": report.to_table()}
