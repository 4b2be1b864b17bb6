"""From a mission string to executable steps, and from a step to an intention's attributes.

Why steps resolve their goal pose only when issued: a plan made at 11:00 may be executed at
11:02; the person to approach has moved and an activity may have started.  Each step therefore
keeps its *symbolic* bindings and computes (x, y, theta) from the live DSR when it is issued, and
says when the world has diverged enough to need a new plan.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import shapely

from agents.missions.goals import (FreeSpace, GoalError, GoalPose, pose_facing_group, pose_facing_person,
                                    pose_in_room, pose_near_object, pose_past_door)
from scenes.geometry import posed_polygon
from agents.world.dsr_readers import dsr_objects, dsr_people, symbolic_view
from scenes.model import Scene

PERSON_MOVED_REPLAN_M = 1.0


class StepFailed(Exception):
    """A step (or the whole mission) cannot be carried out; the message says why."""


@dataclass
class PlanStep:
    """One rule application: ``rule`` names what to do, ``bindings`` with what (DSR names)."""

    rule: str
    bindings: dict[str, str]
    scene: Scene = field(repr=False)
    issued_goal: GoalPose | None = field(default=None, repr=False)

    @property
    def navigates(self) -> bool:
        """Does this step end with the robot driving somewhere (as opposed to waiting)?"""
        return self.rule not in ("waitFor", "waitForPassage")

    def describe(self) -> str:
        args = ", ".join(f"{k}={v}" for k, v in sorted(self.bindings.items()))
        return f"{self.rule}({args})"

    # ------------------------------------------------------------ resolution against the live DSR
    def intention_attrs(self, graph: Any, now_s: float) -> dict[str, Any]:
        if self.rule in ("waitFor", "waitForPassage"):
            name = self.bindings.get("a") or f"activity/{self.bindings.get('activity', '')}"
            activity = graph.get_node_by_name(name)
            if activity is None:
                raise StepFailed(f"unknown activity {name!r}")
            return {"kind": "wait", "until_s": float(activity.attrs["end_s"])}
        goal = self._goal_pose(graph, now_s)
        self.issued_goal = goal
        return {"kind": "navigate", **goal.as_attrs(), "target": self.bindings.get("target", ""),
                "pass_through": self.rule == "changeRoom"}

    def _goal_pose(self, graph: Any, now_s: float) -> GoalPose:
        del now_s
        robot = graph.get_node_by_name(self.scene.robot.name)
        rx, ry, _ = graph.world_pose(robot.id)
        objects = dsr_objects(graph)
        people = dsr_people(graph)
        free = FreeSpace(self.scene, objects)
        busy = _busy_spaces(graph, objects)
        b = self.bindings
        try:
            if self.rule == "goToPose":
                return GoalPose(float(b["x"]), float(b["y"]), float(b["theta"]))
            if self.rule == "goToRoom":
                return pose_in_room(b["room"], self.scene, free, people, busy, (rx, ry))
            if self.rule == "changeRoom":
                return pose_past_door(b["d"], b["r2"], self.scene, free, people)
            if self.rule == "goToObject":
                obj = next((o for o in objects if o.name == b.get("object", b.get("o"))), None)
                if obj is None:
                    raise StepFailed(f"object {b.get('object', b.get('o'))!r} is not in the DSR")
                return pose_near_object(obj, free, people, busy, (rx, ry), self.scene.robot.radius)
            if self.rule == "approachPerson":
                person = next((p for p in people if p.name == b.get("person", b.get("p"))), None)
                if person is None:
                    raise StepFailed(f"person {b.get('person', b.get('p'))!r} is not in the DSR")
                return pose_facing_person(person, free, people, (rx, ry))
            if self.rule == "takeTheAttention":
                names = set(b["group"].split("+")) if "group" in b else _group_of(graph, {b["p"], b["q"]})
                members = [p for p in people if p.name in names]
                if len(members) != len(names):
                    raise StepFailed(f"group members not all seen: {sorted(names)}")
                return pose_facing_group(members, free, people, (rx, ry))
        except GoalError as exc:
            raise StepFailed(str(exc)) from None
        raise StepFailed(f"rule {self.rule!r} has no executable action")

    def diverged(self, graph: Any, now_s: float) -> bool:
        """Has the world changed under this step enough that its goal pose is no longer right?"""
        del now_s
        if self.issued_goal is None:
            return False
        if self.rule == "approachPerson":
            person = graph.get_node_by_name(self.bindings["person"])
            if person is None:
                return True
            px, py, _ = graph.world_pose(person.id)
            expected = self._goal_distance_reference(graph)
            return expected is not None and math.hypot(px - expected[0], py - expected[1]) > PERSON_MOVED_REPLAN_M
        if self.rule == "goToObject":
            busy = _busy_spaces(graph, dsr_objects(graph))
            point = shapely.Point(self.issued_goal.x, self.issued_goal.y)
            return any(space.contains(point) for space in busy)
        return False

    def _goal_distance_reference(self, graph: Any) -> tuple[float, float] | None:
        if not hasattr(self, "_person_at_issue"):
            person = graph.get_node_by_name(self.bindings["person"])
            if person is None:
                return None
            x, y, _ = graph.world_pose(person.id)
            self._person_at_issue = (x, y)
        return self._person_at_issue


def _group_of(graph: Any, seeds: set[str]) -> set[str]:
    """The seeds plus everyone linked to them by `interacting` edges (transitively)."""
    names = set(seeds)
    changed = True
    while changed:
        changed = False
        for edge in graph.edges_of_type("interacting"):
            src, dst = graph.get_node(edge.src), graph.get_node(edge.dst)
            if src is None or dst is None or src.type != "person" or dst.type != "person":
                continue
            if (src.name in names) != (dst.name in names):
                names |= {src.name, dst.name}
                changed = True
    return names


def _busy_spaces(graph: Any, objects: list) -> list[shapely.Geometry]:
    """Interaction spaces of objects with a running activity: no goal pose inside them."""
    running = {str(n.attrs.get("object")) for n in graph.nodes_of_type("activity") if n.attrs.get("state") == "running"}
    return [posed_polygon(o.interaction, o.x, o.y, o.theta) for o in objects if o.name in running]


def direct_steps(goal_text: str, scene: Scene) -> list[PlanStep]:
    """Mission string -> one step, without symbolic planning (used when no grammar is configured)."""
    kind, _, arg = goal_text.partition(":")
    if kind == "pose":
        try:
            x, y, theta = (float(v) for v in arg.split(","))
        except ValueError:
            raise StepFailed(f"bad pose mission {goal_text!r}; expected pose:x,y,theta") from None
        return [PlanStep("goToPose", {"x": str(x), "y": str(y), "theta": str(theta)}, scene)]
    rule = {"room": "goToRoom", "object": "goToObject", "person": "approachPerson", "group": "takeTheAttention",
            "wait": "waitFor"}.get(kind)
    if rule is None or not arg:
        raise StepFailed(f"unknown mission {goal_text!r}")
    key = {"goToRoom": "room", "goToObject": "object", "approachPerson": "person", "takeTheAttention": "group",
           "waitFor": "activity"}[rule]
    return [PlanStep(rule, {key: arg, "target": arg}, scene)]


PASS_THROUGH_M = 0.7   # changeRoom: aim this far past the door, inside the next room


class MissionPlanner:
    """Plans missions with the AGGL grammar on the symbolic DSR (docs/grammar.md).

    Mission strings are the grammar's (``room:``, ``object:``, ``person:``, ``group:``, ``wait:``)
    plus ``pose:x,y,theta``, planned as ``room:<room of the pose>`` followed by ``goToPose``.
    The last ``changeRoom`` of a room mission becomes ``goToRoom`` (stop well inside the room);
    other ``changeRoom`` steps are pass-through waypoints just past their door.
    """

    def __init__(self, scene: Scene, grammar_file: str | None = None) -> None:
        from grammar import default_grammar_path, load_grammar

        self.scene = scene
        self.grammar_file = Path(grammar_file) if grammar_file else default_grammar_path()
        self.grammar = load_grammar(self.grammar_file)

    def plan(self, graph: Any, goal_text: str, now_s: float) -> list[PlanStep]:
        from grammar import MissionError, plan_mission

        del now_s
        kind, _, arg = goal_text.partition(":")
        final: list[PlanStep] = []
        target = goal_text
        if kind == "pose":
            final = direct_steps(goal_text, self.scene)
            x, y = float(final[0].bindings["x"]), float(final[0].bindings["y"])
            room = self.scene.room_at(x, y)
            if room is None:
                raise StepFailed(f"pose ({x:g}, {y:g}) is in no room")
            target = f"room:{room}"
        try:
            result = plan_mission(self.grammar, symbolic_view(graph), target, robot=self.scene.robot.name)
        except MissionError as exc:
            raise StepFailed(str(exc)) from None
        if not result.found:
            raise StepFailed(result.reason)
        steps = [PlanStep(step.rule, dict(step.bindings), self.scene) for step in result.steps]
        if kind == "room" and steps and steps[-1].rule == "changeRoom":
            steps[-1] = PlanStep("goToRoom", {"room": steps[-1].bindings["r2"], "target": arg}, self.scene)
        return steps + final
