"""chronav's global planners, and the lookup of any installed planner by name.

Why one navigation parameter: a study (``chronav evaluate``) compares planners on the same scenes
and seeds, so the planner must be chosen per run without touching anything else.  The live
navigation agent (``-o planner=NAME``), ``chronav path --planner NAME`` and the evaluation all
resolve the name here (``planner(name)``, through the ``chronav.planners`` entry points, where
chronav registers the five below exactly as an outside package registers its own) and plan with
``plan.plan``, so a name means the same planner everywhere.

=============  ===================================================================================
planner        cost grid (walls, bodies and footprints are obstacles for all of them)
=============  ===================================================================================
``social``     chronav's: people's zones + every interaction space priced by R(t) at the time the
               robot would reach it (``arrival.py``)
``departure``  people's zones + every interaction space at R(t) of the departure time, as the
               seeds plan (time-dependent-social-navigation-framework 5.2.2)
``static``     social spaces without the agenda: people's zones + every interaction space at a
               fixed R = ``chronemics.r_min`` (1.5), never forbidden.  Why r_min: it is what R(t)
               is when nothing is scheduled, so this is the seeds' map with the agenda switched
               off (a planner that knows where objects are used but not when); a mid value would
               invent a schedule.
``baseline``   non-social shortest path: free floor everywhere else (the seeds' comparison planner)
``inflation``  Nav2-style: ``baseline`` plus a circular exponential cost decay around each person,
               the formula of Nav2's inflation layer (below); no zones, no interaction spaces
=============  ===================================================================================

Nav2's inflation layer (nav2_costmap_2d ``InflationLayer::computeCost``, documented at
docs.nav2.org "Inflation Layer Parameters"): at distance ``d`` from an obstacle cell, cost is
lethal (254) at ``d = 0``, inscribed (253) for ``d <= inscribed_radius`` and otherwise
``(253 - 1) * exp(-cost_scaling_factor * (d - inscribed_radius))``, up to ``inflation_radius``.
Here the obstacle is a person's body (``grid.person_radius_m``), the inscribed radius is the
planning radius (``grid.robot_radius_m``: the body patches already make ``d <= inscribed``
impassable), and Nav2's 0..252 scale maps linearly onto chronav's traversable costs,
``free + (personal - free) * c / 252``, so the peak equals the social planner's personal-zone cost.
``cost_scaling_factor`` 3.0 is the value in Nav2's shipped nav2_params.yaml; ``inflation_radius``
1.2 m is ours: Nav2's 0.55 m ends before the robot's own inscribed radius (0.45 m with the planning
margin), and 1.2 m reaches as far as chronav's personal zone extends in front of a person.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from agents.lib import registry
from agents.lib.planning.protocol import GlobalPlanner, PlanRequest
from agents.lib.planning.search import Path, plan_on_grid
from agents.lib.socialmap.grid import COST_DTYPE, CostArray, CostPatch, GridParams, GridSpec, TimeCosts, compose
from agents.lib.socialmap.layers import interaction_patches
from agents.lib.socialmap.types import Person

if TYPE_CHECKING:
    from agents.lib.socialmap.social_map import SocialMap

DEFAULT_PLANNER = "social"
NAV2_INSCRIBED_MINUS_ONE = 252.0   # INSCRIBED_INFLATED_OBSTACLE - 1: Nav2's highest traversable cost


class InflationParams(BaseModel):
    """Nav2 inflation layer around people (module doc)."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    cost_scaling_factor: float = Field(3.0, gt=0, description="1/m, Nav2's nav2_params.yaml value")
    inflation_radius_m: float = Field(1.2, gt=0, description="from the body's edge (ours, module doc)")




def planner_names() -> tuple[str, ...]:
    """Every installed planner's name (entry point metadata only: imports nothing)."""
    return registry.names("planner")


def check_planner(name: str) -> str:
    """``name`` if a package registers a planner of that name, else registry.UnknownExtension
    listing the known ones and their packages (metadata only: imports nothing)."""
    registry.entry("planner", name)
    return name


def planner(name: str) -> GlobalPlanner:
    """The planner ``name``, built once per process by its factory and checked against the
    protocol; UnknownExtension or RefusedExtension (plug-in, package, reason) otherwise."""
    return registry.built_once("planner", name, GlobalPlanner, "grid() and plan()")


class GridPlanner:
    """A planner that says which cost grid to search; chronav's A* (or Dijkstra) searches it.

    Subclasses define ``grid``; ``cheapest`` (A*'s heuristic must not exceed any traversable
    cell's cost) defaults to the grid's smallest traversable cost, exact for any grid; override
    it with a known bound to skip that pass.  ``search_costs`` is what is searched (the social
    planner's arrival-time table); it defaults to ``grid``."""

    def grid(self, smap: SocialMap) -> CostArray:
        raise NotImplementedError

    def cheapest(self, smap: SocialMap) -> float:
        grid = self.grid(smap)
        traversable = grid[np.isfinite(grid) & (grid > 0)]
        return float(traversable.min()) if traversable.size else smap.params.grid.free_cost

    def search_costs(self, smap: SocialMap, request: PlanRequest) -> CostArray | TimeCosts:
        return self.grid(smap)

    def plan(self, smap: SocialMap, request: PlanRequest) -> Path:
        return plan_on_grid(self.search_costs(smap, request), smap.spec, request.start_xy, request.goal_xy,
                            method=request.method, c_min=self.cheapest(smap), workspace=request.workspace,
                            searcher=request.replanner)


def _social_cheapest(smap: SocialMap) -> float:
    grid = smap.params.grid
    return min(grid.free_cost, grid.social_cost, grid.personal_cost, smap.params.chronemics.r_min)


class DeparturePlanner(GridPlanner):
    """People's zones + interaction spaces at R(t) of the departure (the seeds)."""

    def grid(self, smap: SocialMap) -> CostArray:
        return smap.cost

    def cheapest(self, smap: SocialMap) -> float:
        return _social_cheapest(smap)


class SocialPlanner(DeparturePlanner):
    """People's zones + interaction spaces priced by R(t) at arrival (chronav).

    Its ``grid`` (what a current path is judged on) is the departure-time one; its search prices
    each interaction space at the time the robot would reach it (``params.arrival_time`` False:
    at departure, as ``departure``)."""

    def search_costs(self, smap: SocialMap, request: PlanRequest) -> CostArray | TimeCosts:
        if not request.params.arrival_time:
            return smap.cost
        # A replanner composes the arrival-time grid itself, from the one it searched last (replan.py).
        costs = smap.time_costs(request.cruise_speed_mps, time_step_s=request.params.time_step_s,
                                horizon_factor=request.params.horizon_factor,
                                incremental=request.replanner.costs if request.replanner is not None else None)
        return smap.cost if costs is None else costs


class StaticPlanner(GridPlanner):
    """People's zones + interaction spaces at a fixed R = r_min (no agenda)."""

    def grid(self, smap: SocialMap) -> CostArray:
        def compose_grid() -> CostArray:
            fixed = [smap.params.chronemics.r_min] * len(smap.interaction_cells)
            return compose(smap.static, (*smap.obstacle_patches, *smap.zone_patches,
                                         *interaction_patches(smap.interaction_cells, fixed)))
        return smap.cached(("planning_grid", "static"), compose_grid)

    def cheapest(self, smap: SocialMap) -> float:
        return _social_cheapest(smap)


class BaselinePlanner(GridPlanner):
    """Non-social shortest path (walls, bodies, footprints)."""

    def grid(self, smap: SocialMap) -> CostArray:
        return smap.physical

    def cheapest(self, smap: SocialMap) -> float:
        return smap.params.grid.free_cost


class InflationPlanner(GridPlanner):
    """Nav2 inflation layer around people (exponential decay), no agenda."""

    def __init__(self, params: InflationParams | None = None) -> None:
        self.params = params or InflationParams()

    def grid(self, smap: SocialMap) -> CostArray:
        def compose_grid() -> CostArray:
            return compose(smap.static, (*smap.obstacle_patches,
                                         *inflation_patches(smap.spec, smap.people, smap.params.grid, self.params)))
        return smap.cached(("planning_grid", "inflation", self.params), compose_grid)

    def cheapest(self, smap: SocialMap) -> float:
        return smap.params.grid.free_cost


def inflation_patches(spec: GridSpec, people: Sequence[Person], grid: GridParams,
                      params: InflationParams) -> list[CostPatch]:
    """Nav2's exponential decay around each person's body, on chronav's cost scale (module doc)."""
    inscribed = grid.robot_radius_m
    if params.inflation_radius_m <= inscribed:
        return []
    span = grid.personal_cost - grid.free_cost
    reach = grid.person_radius_m + params.inflation_radius_m
    patches = []
    for person in people:
        window = spec.window(person.x - reach, person.y - reach, person.x + reach, person.y + reach)
        if window is None:
            continue
        rows, cols = window
        dx = spec.xs(cols)[np.newaxis, :] - person.x
        dy = spec.ys(rows)[:, np.newaxis] - person.y
        d = np.hypot(dx, dy) - grid.person_radius_m        # distance to the body (Nav2's obstacle cell)
        nav2 = np.floor(NAV2_INSCRIBED_MINUS_ONE * np.exp(-params.cost_scaling_factor * (d - inscribed)))
        cost = grid.free_cost + span * np.minimum(nav2, NAV2_INSCRIBED_MINUS_ONE) / NAV2_INSCRIBED_MINUS_ONE
        inside = (d > inscribed) & (d <= params.inflation_radius_m)
        patches.append(CostPatch(rows, cols, np.where(inside, cost, 0.0).astype(COST_DTYPE)))
    return patches
