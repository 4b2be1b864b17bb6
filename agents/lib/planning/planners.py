"""The global planners a run can use: one name each, and the cost grid each one plans on.

Why one navigation parameter: a study (``chronav evaluate``) compares planners on the same scenes
and seeds, so the planner must be chosen per run without touching anything else.  The live
navigation agent (``-o planner=NAME``), ``chronav path --planner NAME`` and the evaluation all
resolve the name here and plan with ``social_map.plan``, so a name means the same grid everywhere.

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
from typing import TYPE_CHECKING, Literal, get_args

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from agents.lib.socialmap.grid import COST_DTYPE, CostArray, CostPatch, GridParams, GridSpec, compose
from agents.lib.socialmap.layers import interaction_patches
from agents.lib.socialmap.types import Person
from scenes.names import shown

if TYPE_CHECKING:
    from agents.lib.socialmap.social_map import SocialMap

PlannerName = Literal["social", "departure", "static", "baseline", "inflation"]
PLANNERS: tuple[str, ...] = get_args(PlannerName)
DEFAULT_PLANNER: PlannerName = "social"
#: what each planner is, for help texts and reports
PLANNER_HELP: dict[str, str] = {
    "social": "people's zones + interaction spaces priced by R(t) at arrival (chronav)",
    "departure": "people's zones + interaction spaces at R(t) of the departure (the seeds)",
    "static": "people's zones + interaction spaces at a fixed R = r_min (no agenda)",
    "baseline": "non-social shortest path (walls, bodies, footprints)",
    "inflation": "Nav2 inflation layer around people (exponential decay), no agenda",
}
NAV2_INSCRIBED_MINUS_ONE = 252.0   # INSCRIBED_INFLATED_OBSTACLE - 1: Nav2's highest traversable cost


class UnknownPlannerError(ValueError):
    """A planner name that is not one of PLANNERS; the message lists them."""


class InflationParams(BaseModel):
    """Nav2 inflation layer around people (module doc)."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    cost_scaling_factor: float = Field(3.0, gt=0, description="1/m, Nav2's nav2_params.yaml value")
    inflation_radius_m: float = Field(1.2, gt=0, description="from the body's edge (ours, module doc)")


def check_planner(name: str) -> PlannerName:
    """``name`` if it is a planner, else UnknownPlannerError saying which exist."""
    if name not in PLANNERS:
        raise UnknownPlannerError(f"unknown planner {shown(name, 40)!r}; choose one of {', '.join(PLANNERS)}")
    return name  # type: ignore[return-value]  # checked in PLANNERS above; mypy does not narrow str to the Literal


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


def planning_grid(smap: SocialMap, planner: str) -> CostArray:
    """The grid ``planner`` plans on at the map's time (``social``: R at the map's time, i.e. the
    grid the agent judges a current path on; its search prices R at arrival, see social_map.plan)."""
    name = check_planner(planner)
    if name in ("social", "departure"):
        return smap.cost
    if name == "baseline":
        return smap.physical

    def compose_grid() -> CostArray:
        if name == "static":
            fixed = [smap.params.chronemics.r_min] * len(smap.interaction_cells)
            layers = (*smap.obstacle_patches, *smap.zone_patches,
                      *interaction_patches(smap.interaction_cells, fixed))
        else:
            layers = (*smap.obstacle_patches,
                      *inflation_patches(smap.spec, smap.people, smap.params.grid, smap.params.planner.inflation))
        return compose(smap.static, layers)

    return smap.cached(("planning_grid", name), compose_grid)


def cheapest_cell(smap: SocialMap, planner: str) -> float:
    """The lowest traversable cost on ``planner``'s grid: A*'s heuristic must not exceed it."""
    grid = smap.params.grid
    if check_planner(planner) in ("baseline", "inflation"):
        return grid.free_cost
    return min(grid.free_cost, grid.social_cost, grid.personal_cost, smap.params.chronemics.r_min)

