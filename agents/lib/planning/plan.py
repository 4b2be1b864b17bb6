"""Plan on the social map with a planner chosen by name: the one front door of the navigation
agent, ``chronav path``, the evaluation and the tests.

    path = plan(smap, start_xy, goal_xy)                               # chronav's social planner
    base = plan(smap, start_xy, goal_xy, planner="baseline")           # non-social baseline
    path = plan(smap, robot_xy, goal_xy, replanner=replanner)          # again, reusing earlier searches

What it adds to a planner's own ``plan``: a docked start (inside a wall's planning margin) leaves
the margin the cheapest way first; a blocked start or goal says why in metres; and a path a
plug-in returns off the map or with non-finite points is refused (PlannerFailed names the
planner), so the agent stops the robot and fails the mission instead of driving it.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import shapely

from agents.lib import registry
from agents.lib.planning.planners import DEFAULT_PLANNER, planner as lookup
from agents.lib.planning.protocol import GlobalPlanner, PlannerParams, PlanRequest
from agents.lib.planning.replan import Replanner
from agents.lib.planning.search import GoalOccupied, Path, PlanningError, SearchWorkspace, StartOccupied
from agents.lib.socialmap.social_map import SocialMap


class PlannerFailed(RuntimeError):
    """A planner raised something other than a planning error, or returned a path that is not
    one (off the map, non-finite); ``str`` names the planner and its package."""

    def __init__(self, name: str, reason: str) -> None:
        package = registry.extensions("planner").get(name)
        where = f" from package {package.package!r}" if package is not None else ""
        super().__init__(f"planner {name!r}{where} failed: {reason}")
        self.name, self.reason = name, reason


def plan(social_map: SocialMap, start_xy: tuple[float, float], goal_xy: tuple[float, float], *,
         method: str = "astar", planner: str | GlobalPlanner = DEFAULT_PLANNER,
         params: PlannerParams | None = None, cruise_speed_mps: float | None = None,
         workspace: SearchWorkspace | None = None, replanner: Replanner | None = None) -> Path:
    """Plan on the social map with ``planner`` (a registered name, agents/lib/planning/planners.py,
    or an instance).

    ``social`` prices each interaction space at the time the robot would reach it at
    ``cruise_speed_mps``; ``departure`` at the map's time (the seeds); ``baseline`` plans on the
    physical grid (walls, bodies, footprints).
    Pass the same ``workspace`` to repeated plans to reuse the search buffers (search.py), or the
    same ``replanner`` to repeated A* plans to one goal on successive maps to reuse what the earlier
    searches learned (replan.py: same optimal costs, far fewer cells expanded; keep one replanner
    per planner)."""
    params = params or PlannerParams()
    name = planner if isinstance(planner, str) else type(planner).__name__
    chosen = lookup(planner) if isinstance(planner, str) else planner
    speed = params.cruise_speed_mps if cruise_speed_mps is None else cruise_speed_mps
    if not speed > 0.0:
        raise ValueError(f"cruise speed must be > 0, got {speed}")
    request = PlanRequest(start_xy=start_xy, goal_xy=goal_xy, cruise_speed_mps=speed, params=params, method=method,
                          workspace=workspace, replanner=replanner)
    try:
        try:
            return checked(social_map, _call(chosen, name, social_map, request), name)
        except StartOccupied:
            exit_xy = dock_exit(social_map, chosen.grid(social_map), start_xy)
            if exit_xy is None:
                raise
            rest = checked(social_map, _call(chosen, name, social_map, replace(request, start_xy=exit_xy)), name)
            first = np.asarray([social_map.spec.cell_of(*start_xy)], dtype=rest.cells.dtype)
            step = math.hypot(exit_xy[0] - start_xy[0], exit_xy[1] - start_xy[1])
            return Path(cells=np.vstack([first, rest.cells]),
                        points_m=np.vstack([np.asarray([start_xy], dtype=float), rest.points_m]),
                        cost=rest.cost + step * social_map.params.grid.free_cost, expanded=rest.expanded)
    except (StartOccupied, GoalOccupied) as exc:
        xy = start_xy if isinstance(exc, StartOccupied) else goal_xy
        raise type(exc)(f"{exc}: {blocked_reason(social_map, xy)}") from None


def _call(chosen: GlobalPlanner, name: str, social_map: SocialMap, request: PlanRequest) -> Path:
    try:
        return chosen.plan(social_map, request)
    except (PlanningError, ValueError):
        raise
    except Exception as exc:
        raise PlannerFailed(name, f"raised {type(exc).__name__}: {exc}") from exc


def checked(social_map: SocialMap, path: object, name: str) -> Path:
    """``path`` if it is a search.Path of finite points inside the map, else PlannerFailed."""
    if not isinstance(path, Path):
        raise PlannerFailed(name, f"returned a {type(path).__name__}, not a search.Path")
    points = np.asarray(path.points_m, dtype=float)
    if points.ndim != 2 or points.shape[1:] != (2,) or len(points) == 0:
        raise PlannerFailed(name, f"returned points of shape {points.shape}, expected (n, 2)")
    if not np.all(np.isfinite(points)) or not math.isfinite(path.cost):
        raise PlannerFailed(name, "returned a path with NaN or infinite points or cost")
    xmin, ymin, xmax, ymax = social_map.spec.bounds
    outside = (points[:, 0] < xmin) | (points[:, 0] > xmax) | (points[:, 1] < ymin) | (points[:, 1] > ymax)
    if np.any(outside):
        x, y = points[int(np.argmax(outside))]
        raise PlannerFailed(name, f"returned a path off the map: ({x:.2f}, {y:.2f}) m is outside "
                                  f"[{xmin:g}, {xmax:g}] x [{ymin:g}, {ymax:g}]")
    return path


def dock_exit(social_map: SocialMap, grid: np.ndarray, xy: tuple[float, float]) -> tuple[float, float] | None:
    """Where a robot that starts inside the planning margin of a wall (docked: collision-free
    but nearer a wall than its radius plus the margin) leaves the margin: of the traversable cells
    within the robot's inflated radius, the one with the least distance x cost to step onto (the
    cheapest way out, straight off the wall as from a charging dock).  None when the start is not
    in a wall's margin (a body, an object or a forbidden space blocks it) or no cell is near."""
    spec = social_map.spec
    row, col = spec.cell_of(*xy)
    if not (0 <= row < grid.shape[0] and 0 <= col < grid.shape[1]) or np.isfinite(social_map.static[row, col]):
        return None
    reach = int(math.ceil(social_map.params.grid.robot_radius_m / spec.resolution))
    r0, r1 = max(0, row - reach), min(grid.shape[0], row + reach + 1)
    c0, c1 = max(0, col - reach), min(grid.shape[1], col + reach + 1)
    window = np.asarray(grid[r0:r1, c0:c1], dtype=float)
    rows, cols = np.nonzero(np.isfinite(window) & (window > 0))
    if not rows.size:
        return None
    xs = spec.x0 + (cols + c0 + 0.5) * spec.resolution
    ys = spec.y0 + (rows + r0 + 0.5) * spec.resolution
    distance = np.hypot(xs - xy[0], ys - xy[1])
    score = np.where(distance <= social_map.params.grid.robot_radius_m, distance * window[rows, cols], np.inf)
    best = int(np.argmin(score))
    return None if not np.isfinite(score[best]) else (float(xs[best]), float(ys[best]))


def blocked_reason(social_map: SocialMap, xy: tuple[float, float]) -> str:
    """Why a point is not traversable, in metres and in the map's own terms."""
    x, y = xy
    grid = social_map.params.grid
    point = shapely.Point(x, y)
    static = social_map.static[social_map.spec.cell_of(x, y)]
    if not np.isfinite(static):
        return (f"it is outside every room or within {grid.robot_radius_m:.2f} m (the robot's radius plus "
                "margin) of a wall")
    for space in social_map.object_spaces:
        if space.footprint.distance(point) <= grid.robot_radius_m:
            return f"it is {space.footprint.distance(point):.2f} m from the footprint of object {space.name!r}"
    for person in social_map.people:
        distance = math.hypot(person.x - x, person.y - y)
        if distance <= grid.person_radius_m + grid.robot_radius_m + 0.5:
            return f"it is {distance:.2f} m from {person.name!r} (a body or intimate zone)"
    for space in social_map.object_spaces:
        if space.interaction.covers(point):
            return f"it is in the interaction space of {space.name!r}, forbidden while its activity runs"
    return "a person's or an object's space covers it"
