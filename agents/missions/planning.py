"""From a mission string to executable steps, and from steps to intentions.

Why one planner for the executive and `chronav plan`: the live executive and the offline command
must plan a mission the same way on the same DSR.  Both call :meth:`MissionPlanner.plan` on a DSR
graph (the live replica, or ``agents.world.offline.graph_at``) read through
``agents.world.dsr_readers.symbolic_view``; both group the steps into intentions with
:func:`intention_end` and :func:`route_rooms`.

What the planner adds to the grammar's plan (docs/grammar.md, "Missions"):
- ``pose:x,y,theta`` is planned as ``room:<room of the pose>`` followed by ``goToPose``;
- the last ``changeRoom`` of a ``room:`` mission becomes ``goToRoom`` (stop well inside the room,
  not just past its door); other ``changeRoom`` steps are pass-through waypoints past their door;
- ``wait:ID`` takes the id `chronav agenda list` shows (``activity/`` prefix optional);
- a group mission's ``takeTheAttention`` faces the people the mission named.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from agents.missions.kinds import (ECHO_CHARS, GROUP, POSE, ROOM, MissionRequest, MissionStringError, check_names,
                                   parse_mission)
from agents.missions.steps import PlanStep, Rule, StepFailed, Var
from agents.world.dsr_readers import symbolic_view
from dsr.protocols import GraphReader
from scenes.model import Scene
from scenes.names import shown


class NoMissionPlan(StepFailed):
    """The mission is well formed but cannot be planned now; ``result`` is the grammar's NoPlan
    (None when the names were already wrong)."""

    def __init__(self, message: str, result: Any = None) -> None:
        super().__init__(message)
        self.result = result


@dataclass
class MissionPlan:
    """A mission planned: the request, the grammar mission it became, the grammar's plan and the
    executable steps."""

    request: MissionRequest
    grammar_mission: str
    result: Any            # grammar.planner.Plan
    steps: list[PlanStep]

    @property
    def cost(self) -> float:
        return float(self.result.cost)


class MissionPlanner:
    """Plans missions with the AGGL grammar (docs/grammar.md) on the symbolic part of a DSR graph."""

    def __init__(self, scene: Scene, grammar_file: str | Path | None = None, *, robot: str | None = None,
                 max_expansions: int | None = None) -> None:
        from grammar import default_grammar_path, load_grammar

        self.scene = scene
        self.robot = robot or scene.robot.name
        self.grammar_file = Path(grammar_file) if grammar_file else default_grammar_path()
        self.grammar = load_grammar(self.grammar_file)
        self.max_expansions = max_expansions

    def plan(self, graph: GraphReader, goal_text: str) -> MissionPlan:
        """Plan ``goal_text`` on ``graph`` (a DSR replica). MissionStringError for a malformed
        mission; NoMissionPlan (a StepFailed) when the world offers no plan."""
        from grammar import MissionError, NoPlan, plan_mission
        from grammar.missions import DEFAULT_MAX_EXPANSIONS

        request = parse_mission(goal_text)
        problem = check_names(request, graph)
        if problem is not None:
            raise NoMissionPlan(f"mission {shown(goal_text, ECHO_CHARS)!r}: {problem}")
        room = None
        if request.kind == POSE:
            assert request.pose is not None
            room = self.scene.room_at(request.pose[0], request.pose[1])
            if room is None:
                raise NoMissionPlan(f"mission {shown(goal_text, ECHO_CHARS)!r}: ({request.pose[0]:g}, {request.pose[1]:g}) is in no "
                                    f"room of scene {self.scene.name!r}")
        grammar_mission = request.grammar_mission(room)
        expansions = DEFAULT_MAX_EXPANSIONS if self.max_expansions is None else self.max_expansions
        try:
            result = plan_mission(self.grammar, symbolic_view(graph), grammar_mission, robot=self.robot,
                                  max_expansions=expansions)
        except MissionError as exc:  # the grammar refused a form this module accepted: a bug, said plainly
            raise MissionStringError(str(exc)) from None
        if isinstance(result, NoPlan):
            raise NoMissionPlan(result.reason, result)
        return MissionPlan(request, grammar_mission, result, executable_steps(request, result.steps))


def executable_steps(request: MissionRequest, grammar_steps: Any) -> list[PlanStep]:
    """The grammar's steps as the executive carries them out (see the module docstring)."""
    steps = [PlanStep(step.rule, dict(step.bindings), float(step.cost)) for step in grammar_steps]
    if request.kind == ROOM and steps and steps[-1].rule == Rule.CHANGE_ROOM:
        last = steps[-1]
        steps[-1] = PlanStep(Rule.GO_TO_ROOM, dict(last.bindings), last.cost)
    if request.kind == GROUP:
        for step in steps:
            if step.rule == Rule.TAKE_THE_ATTENTION:
                step.members = request.names
    if request.kind == POSE:
        assert request.pose is not None
        x, y, theta = request.pose
        bindings = {Var.X: repr(x), Var.Y: repr(y), **({} if theta is None else {Var.THETA: repr(theta)})}
        steps.append(PlanStep(Rule.GO_TO_POSE, bindings, 0.0))
    return steps


def intention_end(steps: list[PlanStep], first: int) -> int:
    """Index of the last step of the intention that starts at ``first``: door-to-door hops
    followed by a move become one intention, confined to the route's rooms."""
    index = first
    while index + 1 < len(steps) and steps[index].rule == Rule.CHANGE_ROOM and steps[index + 1].navigates:
        index += 1
    return index


def route_rooms(steps: list[PlanStep], first: int, last: int) -> list[str]:
    """The rooms an intention spanning ``steps[first..last]`` may cross, in order: the room moves'
    (empty when it moves to no other room: unconfined, within the robot's room)."""
    moves = [step for step in steps[first:last + 1] if step.rule in Rule.ROOM_MOVES]
    if not moves:
        return []
    return [moves[0].bindings[Var.FROM_ROOM], *(move.bindings[Var.TO_ROOM] for move in moves)]


def remaining_route(steps: list[PlanStep], here: str | None) -> list[str]:
    """The rooms still to enter (and waits still to do), from the robot's current room on."""
    route = []
    for step in steps:
        if step.rule in Rule.ROOM_MOVES:
            route.append(step.bindings[Var.TO_ROOM])
        elif step.rule == Rule.WAIT_FOR_PASSAGE:
            route.append(f"wait:{step.bindings.get(Var.ACTIVITY, '')}")
    if here in route:
        route = route[route.index(here) + 1:]
    return route
