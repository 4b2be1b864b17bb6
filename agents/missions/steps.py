"""Executable steps: a plan's rule applications, each turned into a goal pose or a wait.

Why steps resolve their goal pose only when issued: a plan made at 11:00 may be executed at
11:02; the person to approach has moved and an activity may have started.  Each step therefore
keeps its *symbolic* bindings and computes (x, y, theta) from the DSR when it is issued, and says
when the world has diverged enough to need a new plan.

The rule and variable names below are the shipped grammar's (grammar/social_navigation.aggl),
declared once; ``tests/unit/test_mission_kinds.py`` checks them against the grammar file.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import shapely

from agents.missions.goals import (SOCIAL_DISTANCE_M, FreeSpace, GoalError, GoalPose, pose_facing_group,
                                   pose_facing_person, pose_in_room, pose_near_object, pose_past_door)
from agents.world.dsr_readers import dsr_objects, dsr_people
from agents.world.vocabulary import ActivityView, EdgeType, IntentionKind, NodeType, activities, activity_id_of
from dsr.attr_values import as_float
from dsr.protocols import GraphReader
from scenes.geometry import angle_difference, posed_polygon
from scenes.model import Scene

PERSON_MOVED_REPLAN_M = 1.0   # the approached person (or a group's centre) moved this far: plan again
GOAL_OFF_SOCIAL_M = 0.3       # a standing person is this much nearer or farther than social distance: plan again
GOAL_OFF_FACING_RAD = 0.2     # ... or the goal no longer faces her by this much: plan again
PERSON_STILL_MPS = 0.1


class Rule:
    """Rule names: the grammar's, plus the two steps the executive adds (``goToRoom``, ``goToPose``)."""

    CHANGE_ROOM = "changeRoom"
    GO_TO_OBJECT = "goToObject"
    APPROACH_PERSON = "approachPerson"
    TAKE_THE_ATTENTION = "takeTheAttention"
    WAIT_FOR = "waitFor"
    WAIT_FOR_PASSAGE = "waitForPassage"
    GO_TO_ROOM = "goToRoom"     # the last changeRoom of a room mission (same bindings): stop well inside r2
    GO_TO_POSE = "goToPose"     # the end of a pose mission
    WAITS = (WAIT_FOR, WAIT_FOR_PASSAGE)
    ROOM_MOVES = (CHANGE_ROOM, GO_TO_ROOM)


class Var:
    """Variables the rules bind (names of DSR nodes), and the pose of ``goToPose``."""

    ROBOT = "robot"
    FROM_ROOM = "r1"      # changeRoom (goToRoom), waitForPassage
    TO_ROOM = "r2"        # changeRoom (goToRoom), waitForPassage
    DOOR = "d"            # changeRoom (goToRoom)
    ROOM = "r"            # goToObject, approachPerson, takeTheAttention
    OBJECT = "o"          # goToObject, waitForPassage
    PERSON = "p"          # approachPerson, takeTheAttention
    OTHER_PERSON = "q"    # takeTheAttention
    ACTIVITY = "a"        # waitFor, waitForPassage
    X, Y, THETA = "x", "y", "theta"   # goToPose (THETA absent: any heading)


# What each executable rule reads from its bindings (checked against the grammar by a test).
RULE_VARS: dict[str, tuple[str, ...]] = {
    Rule.CHANGE_ROOM: (Var.FROM_ROOM, Var.TO_ROOM, Var.DOOR),
    Rule.GO_TO_OBJECT: (Var.OBJECT,),
    Rule.APPROACH_PERSON: (Var.PERSON,),
    Rule.TAKE_THE_ATTENTION: (Var.PERSON, Var.OTHER_PERSON),
    Rule.WAIT_FOR: (Var.ACTIVITY,),
    Rule.WAIT_FOR_PASSAGE: (Var.ACTIVITY, Var.FROM_ROOM, Var.TO_ROOM),
}


class StepFailed(Exception):
    """A step (or the whole mission) cannot be carried out; the message says why."""


@dataclass
class PlanStep:
    """One rule application: ``rule`` names what to do, ``bindings`` with what (DSR names).

    ``members``: for ``takeTheAttention`` in a group mission, the people the mission named (the
    group faced is them plus everyone interacting with them)."""

    rule: str
    bindings: dict[str, str]
    cost: float = 0.0
    members: tuple[str, ...] = ()
    issued_goal: GoalPose | None = field(default=None, repr=False)
    reference: tuple[float, float] | None = field(default=None, repr=False)   # person / group centre at issue

    @property
    def navigates(self) -> bool:
        """Does this step end with the robot driving somewhere (as opposed to waiting)?"""
        return self.rule not in Rule.WAITS

    def describe(self) -> str:
        args = ", ".join(f"{k}={v}" for k, v in sorted(self.bindings.items()))
        return f"{self.rule}({args})"

    @property
    def subject(self) -> str:
        """What the step is about, for people reading the intention (room, object, person, group, activity)."""
        b = self.bindings
        if self.rule == Rule.TAKE_THE_ATTENTION:
            return "+".join(self.members or (b.get(Var.PERSON, ""), b.get(Var.OTHER_PERSON, "")))
        if Var.ACTIVITY in b:
            return activity_id_of(b[Var.ACTIVITY])
        for var in (Var.PERSON, Var.OBJECT, Var.TO_ROOM):
            if var in b:
                return b[var]
        if self.rule == Rule.GO_TO_POSE:
            return ",".join(b[v] for v in (Var.X, Var.Y, Var.THETA) if v in b)
        return ""

    # ------------------------------------------------------------------------------------ waits
    def awaited(self, graph: GraphReader) -> ActivityView | None:
        """The activity a wait step waits for, as the DSR holds it now (None: gone from the agenda)."""
        return ActivityView.named(graph, self.bindings.get(Var.ACTIVITY, ""))

    def wait_over(self, graph: GraphReader) -> bool:
        """A wait ends when its activity has finished or was cancelled (or left the agenda)."""
        activity = self.awaited(graph)
        return activity is None or activity.ended

    # ------------------------------------------------------------------ resolution against the DSR
    def intention_attrs(self, graph: GraphReader, scene: Scene, robot_xy: tuple[float, float] | None = None) -> dict[str, Any]:
        """The intention's attributes: a wait until the activity's end, or a goal pose resolved on
        the DSR now (``robot_xy``: where the robot will be, when not where the DSR has it)."""
        if not self.navigates:
            activity = self.awaited(graph)
            if activity is None:
                raise StepFailed(f"activity {self.bindings.get(Var.ACTIVITY)!r} is not on the agenda")
            return {"kind": IntentionKind.WAIT, "until_s": activity.end_s, "target": self.subject}
        goal = self.resolve(graph, scene, robot_xy)
        return {"kind": IntentionKind.NAVIGATE, **goal.as_attrs(), "target": self.subject,
                "pass_through": self.rule == Rule.CHANGE_ROOM}

    def resolve(self, graph: GraphReader, scene: Scene, robot_xy: tuple[float, float] | None = None) -> GoalPose:
        """The goal pose of a navigating step on the DSR as it is now; remembers it (and where the
        approached person or group stood) to tell divergence later."""
        if robot_xy is None:
            robot = graph.get_node_by_name(scene.robot.name)
            if robot is None:
                raise StepFailed(f"robot {scene.robot.name!r} is not in the DSR")
            rx, ry, _ = graph.world_pose(robot.id)
            robot_xy = (rx, ry)
        objects = dsr_objects(graph)
        people = dsr_people(graph)
        free = FreeSpace(scene, objects)
        busy = busy_spaces(graph, objects)
        b = self.bindings
        self.reference = None
        try:
            if self.rule == Rule.GO_TO_POSE:
                theta = b.get(Var.THETA)
                goal = GoalPose(float(b[Var.X]), float(b[Var.Y]), None if theta is None else float(theta))
            elif self.rule == Rule.GO_TO_ROOM:
                goal = pose_in_room(b[Var.TO_ROOM], scene, free, people, busy, robot_xy)
            elif self.rule == Rule.CHANGE_ROOM:
                goal = pose_past_door(b[Var.DOOR], b[Var.TO_ROOM], scene, free, people)
            elif self.rule == Rule.GO_TO_OBJECT:
                obj = next((o for o in objects if o.name == b[Var.OBJECT]), None)
                if obj is None:
                    raise StepFailed(f"object {b[Var.OBJECT]!r} is not in the DSR")
                goal = pose_near_object(obj, free, people, busy, robot_xy, scene.robot.radius)
            elif self.rule == Rule.APPROACH_PERSON:
                person = next((p for p in people if p.name == b[Var.PERSON]), None)
                if person is None:
                    raise StepFailed(f"person {b[Var.PERSON]!r} is not in the DSR")
                goal = pose_facing_person(person, free, people, robot_xy)
                self.reference = (person.x, person.y)
            elif self.rule == Rule.TAKE_THE_ATTENTION:
                names = self.group(graph)
                members = [p for p in people if p.name in names]
                if len(members) != len(names):
                    raise StepFailed(f"group members not all seen: {', '.join(sorted(names))}")
                goal = pose_facing_group(members, free, people, robot_xy)
                self.reference = _centre([(p.x, p.y) for p in members])
            else:
                raise StepFailed(f"rule {self.rule!r} has no executable action")
        except GoalError as exc:
            raise StepFailed(str(exc)) from None
        except KeyError as exc:
            raise StepFailed(f"{self.describe()} binds no {exc.args[0]!r}") from None
        self.issued_goal = goal
        return goal

    def group(self, graph: GraphReader) -> set[str]:
        """The people a takeTheAttention step faces: its members (or p and q) and everyone linked
        to them by ``interacting`` edges, transitively (the F-formation they stand in)."""
        seeds = set(self.members) or {self.bindings[Var.PERSON], self.bindings[Var.OTHER_PERSON]}
        return interacting_closure(graph, seeds)

    def diverged(self, graph: GraphReader) -> bool:
        """Has the world changed under this issued step enough that its goal pose is no longer right?"""
        if self.issued_goal is None:
            return False
        if self.rule in (Rule.APPROACH_PERSON, Rule.TAKE_THE_ATTENTION) and self.reference is not None:
            positions = _positions(graph)
            names = {self.bindings[Var.PERSON]} if self.rule == Rule.APPROACH_PERSON else self.group(graph)
            if not names <= positions.keys():
                return True
            now = _centre([positions[n] for n in names])
            if math.hypot(now[0] - self.reference[0], now[1] - self.reference[1]) > PERSON_MOVED_REPLAN_M:
                return True
            if self.rule == Rule.APPROACH_PERSON and _still(graph, self.bindings[Var.PERSON]):
                # Less than a metre on, but she has stopped, maybe where the goal was (a goal set
                # in front of a walker lies on her way): a goal off social distance, or facing
                # where she was, is wrong.  Only once she stands: while she walks, the metre rule
                # follows her.
                goal = self.issued_goal
                gap = math.hypot(now[0] - goal.x, now[1] - goal.y)
                if abs(gap - SOCIAL_DISTANCE_M) > GOAL_OFF_SOCIAL_M:
                    return True
                bearing = math.atan2(now[1] - goal.y, now[0] - goal.x)
                return goal.theta is not None and abs(angle_difference(goal.theta, bearing)) > GOAL_OFF_FACING_RAD
            return False
        if self.rule == Rule.GO_TO_OBJECT:
            point = shapely.Point(self.issued_goal.x, self.issued_goal.y)
            return any(space.contains(point) for space in busy_spaces(graph, dsr_objects(graph)))
        return False


def _still(graph: GraphReader, name: str) -> bool:
    """Is the person standing (the observer's velocity estimate below PERSON_STILL_MPS)?"""
    node = graph.get_node_by_name(name)
    if node is None:
        return False
    try:
        return math.hypot(as_float(node.attrs.get("vx", 0.0)), as_float(node.attrs.get("vy", 0.0))) < PERSON_STILL_MPS
    except (TypeError, ValueError):
        return False


def _centre(points: list[tuple[float, float]]) -> tuple[float, float]:
    return (sum(p[0] for p in points) / len(points), sum(p[1] for p in points) / len(points))


def _positions(graph: GraphReader) -> dict[str, tuple[float, float]]:
    out = {}
    for node in graph.nodes_of_type(NodeType.PERSON):
        try:
            x, y, _ = graph.world_pose(node.id)
        except (KeyError, LookupError, ValueError):
            continue
        out[node.name] = (x, y)
    return out


def interacting_closure(graph: GraphReader, seeds: set[str]) -> set[str]:
    """The seeds plus everyone linked to them by person-person ``interacting`` edges (transitively)."""
    names = set(seeds)
    changed = True
    while changed:
        changed = False
        for edge in graph.edges_of_type(EdgeType.INTERACTING):
            src, dst = graph.get_node(edge.src), graph.get_node(edge.dst)
            if src is None or dst is None or src.type != NodeType.PERSON or dst.type != NodeType.PERSON:
                continue
            if (src.name in names) != (dst.name in names):
                names |= {src.name, dst.name}
                changed = True
    return names


def busy_spaces(graph: GraphReader, objects: list) -> list[shapely.Geometry]:
    """Interaction spaces of objects with a running activity: no goal pose inside them."""
    running = {a.object for a in activities(graph) if a.running}
    return [posed_polygon(o.interaction, o.x, o.y, o.theta) for o in objects if o.name in running]
