"""What the executive would issue for a mission at a time, without running it (`chronav plan SCENE`).

Why a preview of intentions and not only the grammar's plan: a person asking "what would the robot
do?" needs the steps the executive carries out (a pose mission ends with ``goToPose``, a room
mission with ``goToRoom``) and where it would drive.  The preview groups the steps into intentions
as the executive does and resolves each intention's goal pose on the same DSR, with the robot
where the previous intention left it (the world is otherwise taken as it is at the plan's time).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from agents.missions.goals import GoalPose
from agents.missions.planning import MissionPlan, MissionPlanner, intention_end, route_rooms
from agents.missions.steps import PlanStep, StepFailed
from dsr.protocols import GraphReader


@dataclass(frozen=True)
class StepPreview:
    """One executable step; the last step of each intention carries what the intention does."""

    step: PlanStep
    intention: int
    last_of_intention: bool
    goal: GoalPose | None = None
    pass_through: bool = False
    rooms: tuple[str, ...] = ()
    until_s: float | None = None
    error: str | None = None

    def as_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {"rule": self.step.rule, "bindings": dict(self.step.bindings), "cost": self.step.cost,
                               "intention": self.intention}
        if self.goal is not None:
            out["goal"] = {"x": round(self.goal.x, 3), "y": round(self.goal.y, 3),
                           "theta": None if self.goal.theta is None else round(self.goal.theta, 4)}
            out["pass_through"] = self.pass_through
        if self.rooms:
            out["rooms"] = list(self.rooms)
        if self.until_s is not None:
            out["until_s"] = self.until_s
        if self.error is not None:
            out["goal_error"] = self.error
        return out


def preview_mission(planner: MissionPlanner, graph: GraphReader, goal_text: str) -> tuple[MissionPlan, list[StepPreview]]:
    """Plan ``goal_text`` on ``graph`` exactly as the executive would, and resolve each intention."""
    plan = planner.plan(graph, goal_text)
    steps = plan.steps
    robot_xy: tuple[float, float] | None = None
    out: list[StepPreview] = []
    first, intention = 0, 0
    while first < len(steps):
        last = intention_end(steps, first)
        out += [StepPreview(steps[i], intention, False) for i in range(first, last)]
        step = steps[last]
        rooms = tuple(route_rooms(steps, first, last))
        try:
            attrs = step.intention_attrs(graph, planner.scene, robot_xy)
        except StepFailed as exc:
            out.append(StepPreview(step, intention, True, rooms=rooms, error=str(exc)))
        else:
            if step.navigates:
                goal = step.issued_goal
                assert goal is not None
                robot_xy = (goal.x, goal.y)
                out.append(StepPreview(step, intention, True, goal=goal, pass_through=bool(attrs["pass_through"]),
                                       rooms=rooms))
            else:
                out.append(StepPreview(step, intention, True, rooms=rooms, until_s=float(attrs["until_s"])))
        first, intention = last + 1, intention + 1
    return plan, out
