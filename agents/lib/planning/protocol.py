"""The global planner interface: a social map and a request in, a path out.

Why a protocol: chronav's planners (social, departure, static, baseline, inflation) and a
researcher's own are chosen by name (``--planner NAME``, ``chronav evaluate --planners A,B``)
through the ``chronav.planners`` entry point group, so the navigation agent, ``chronav path`` and
the evaluation plan with whichever is installed without knowing which.

Frames and units: the world frame is the scene's map frame (x, y in metres); the map's grid is
``smap.spec`` (row 0 at ``y0``, cells of ``spec.resolution`` m); costs are chronav's (1 = free
floor, inf = blocked, people's zones and interaction spaces above 1); times in seconds.

An entry point names a FACTORY: ``factory() -> GlobalPlanner`` (a class with a no-argument
constructor is one).  The easiest planner is a ``planners.GridPlanner`` subclass that only
says which cost grid to search (``grid``); chronav's A* searches it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol, runtime_checkable

from pydantic import BaseModel, ConfigDict, Field

from agents.lib.socialmap.grid import CostArray

if TYPE_CHECKING:
    from agents.lib.planning.replan import Replanner
    from agents.lib.planning.search import Path, SearchWorkspace
    from agents.lib.socialmap.social_map import SocialMap


class PlannerParams(BaseModel):
    """What every planning call shares (defaults and sources in docs/internals.md):

    =====================  =========  ===================================================
    parameter              default    source
    =====================  =========  ===================================================
    cruise_speed_mps       0.25 m/s   ours: mean speeds (d_t / tau) in the seed's Tables 1-2
                                      are 0.13-0.26 m/s; the agent passes 0.7 x max speed
    arrival_time           True       ours (beyond the seeds; False = the seeds' departure)
    time_step_s            1 s        ours (R changes over minutes)
    horizon_factor         3          ours: the arrival table covers 3 x (width + height)
    =====================  =========  ===================================================
    """

    model_config = ConfigDict(extra="forbid", frozen=True)

    cruise_speed_mps: float = Field(0.25, gt=0, description="converts distance travelled to arrival time")
    arrival_time: bool = Field(True, description="R at arrival time (False: at departure, as the seeds)")
    time_step_s: float = Field(1.0, gt=0, description="time resolution of the arrival-time table")
    horizon_factor: float = Field(3.0, gt=0, description="table covers trips up to this x (width + height)")


@dataclass(frozen=True)
class PlanRequest:
    """One planning call.

    start_xy, goal_xy: world frame, metres.
    cruise_speed_mps:  the speed the robot is expected to average (prices R at arrival time).
    params:            the shared planning parameters.
    method:            "astar" or "dijkstra" (grid planners).
    workspace, replanner: search buffers and the incremental searcher to reuse (grid planners may
                       ignore them; one replanner per planner).
    """

    start_xy: tuple[float, float]
    goal_xy: tuple[float, float]
    cruise_speed_mps: float
    params: PlannerParams = PlannerParams()
    method: str = "astar"
    workspace: SearchWorkspace | None = None
    replanner: Replanner | None = None


@runtime_checkable
class GlobalPlanner(Protocol):
    """A global planner.

    ``grid(smap)``: the planner's cost grid at the map's time (``smap.spec`` layout, inf =
    blocked): what the navigation judges a current path on when it considers replanning.
    ``plan(smap, request)``: a search.Path from start to goal (cells, points in metres, cost);
    raise search.StartOccupied / GoalOccupied / NoPathFound when there is none.  A path off the
    map or with non-finite points is refused (the mission fails naming the planner).
    """

    def grid(self, smap: SocialMap) -> CostArray: ...

    def plan(self, smap: SocialMap, request: PlanRequest) -> Path: ...
