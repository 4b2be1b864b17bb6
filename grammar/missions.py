"""Mission strings -> target patterns for the planner.

Why strings: missions arrive from scenes (YAML), from the CLI and as attributes of ``mission``
nodes in the DSR; one short, documented text form keeps them all the same:

==========================  ====================================================================
``room:NAME``               the robot is ``in`` room NAME
``object:NAME``             the robot is in the room of object NAME and ``near`` it
``person:NAME``             the robot is in the room of person NAME, ``near`` and ``facing`` them
``group:P1+P2[+P3...]``     the robot is in the group's room, ``facing`` every member
``wait:ACTIVITY``           activity ACTIVITY has ended (its ``state`` is finished or cancelled)
==========================  ====================================================================

The planner also needs to know what the mission is about (the agenda rules let the robot enter a
room with a group activity only when the mission targets it): ``with_mission_node`` adds a
``mission`` node with ``targets`` edges to the named nodes, as the executive writes it in the DSR.
"""

from __future__ import annotations

from dataclasses import dataclass

import networkx as nx

from grammar.errors import MissionError
from grammar.model import (
    AttrRef,
    Compare,
    Grammar,
    ListLit,
    Literal,
    Pattern,
    PatternLink,
    PatternNode,
    Target,
)
from grammar.planner import DEFAULT_MAX_EXPANSIONS, NoPlan, Planner, PlanResult

MISSION_KINDS = ("room", "object", "person", "group", "wait")
ENDED_STATES = ("finished", "cancelled")
_TYPE_OF_KIND = {"room": "room", "object": "object", "person": "person", "group": "person",
                 "wait": "activity"}


@dataclass(frozen=True)
class Mission:
    text: str
    kind: str
    names: tuple[str, ...]
    target: Target

    @property
    def node_type(self) -> str:
        """Type of the nodes the mission names."""
        return _TYPE_OF_KIND[self.kind]


def _robot(robot: str | None) -> PatternNode:
    if robot is None:
        return PatternNode("robot", "robot")
    return PatternNode(robot, "robot", constant=robot)


def parse_mission(text: str, robot: str | None = None) -> Mission:
    """``room:kitchen`` -> Mission with its target pattern; ``robot`` pins a robot by name."""
    if not isinstance(text, str) or ":" not in text:
        raise MissionError(f"mission {text!r} is not KIND:NAME; kinds: {', '.join(MISSION_KINDS)}")
    kind, _, rest = text.partition(":")
    kind, rest = kind.strip(), rest.strip()
    if kind not in MISSION_KINDS:
        raise MissionError(f"unknown mission kind {kind!r} in {text!r}; expected one of "
                           f"{', '.join(MISSION_KINDS)}")
    names = tuple(n.strip() for n in rest.split("+")) if kind == "group" else (rest,)
    if not all(names):
        raise MissionError(f"mission {text!r} has an empty name")
    if kind == "group" and len(names) < 2:
        raise MissionError(f"group mission {text!r} needs at least two people: group:P1+P2")
    if len(set(names)) != len(names):
        raise MissionError(f"mission {text!r} names someone twice")
    r = _robot(robot)
    rv = r.name
    if kind == "room":
        pattern = Pattern((r, PatternNode(names[0], "room", constant=names[0])),
                          (PatternLink(rv, names[0], "in"),))
    elif kind in ("object", "person"):
        thing = names[0]
        room = "_room" if thing != "_room" else "_room_"
        links = [PatternLink(thing, room, "in"), PatternLink(rv, room, "in"), PatternLink(rv, thing, "near")]
        if kind == "person":
            links.append(PatternLink(rv, thing, "facing"))
        pattern = Pattern((r, PatternNode(thing, kind, constant=thing), PatternNode(room, "room")), tuple(links))
    elif kind == "group":
        room = "_room"
        nodes = [r, PatternNode(room, "room")] + [PatternNode(n, "person", constant=n) for n in names]
        links = [PatternLink(rv, room, "in")]
        for n in names:
            links += [PatternLink(n, room, "in"), PatternLink(rv, n, "facing")]
        pattern = Pattern(tuple(nodes), tuple(links))
    else:  # wait
        ended = Compare("in", AttrRef(names[0], "state"), ListLit(tuple(Literal(s) for s in ENDED_STATES)))
        pattern = Pattern((PatternNode(names[0], "activity", constant=names[0], conditions=(ended,)),))
    return Mission(text, kind, names, Target(pattern, file=f"<mission {text}>"))


def check_mission(mission: Mission, graph: nx.MultiDiGraph) -> str | None:
    """Why the mission cannot be planned on ``graph`` (unknown names, wrong types), or ``None``."""
    by_name = {str(data.get("name", key)): data.get("type") for key, data in graph.nodes(data=True)}
    for name in mission.names:
        if name not in by_name:
            return f"no node named {name!r} in the world"
        if by_name[name] != mission.node_type:
            return f"{name!r} is a {by_name[name]}, not a {mission.node_type}"
    return None


def with_mission_node(graph: nx.MultiDiGraph, mission: Mission, name: str = "mission") -> nx.MultiDiGraph:
    """A copy of ``graph`` with a ``mission`` node that ``targets`` the mission's nodes."""
    out = graph.copy()
    key_of = {str(data.get("name", key)): key for key, data in graph.nodes(data=True)}
    node_key: object = name
    while node_key in out:
        node_key = f"{node_key}_"
    out.add_node(node_key, type="mission", name=str(node_key), goal=mission.text)
    for target in mission.names:
        if target in key_of:
            out.add_edge(node_key, key_of[target], key="targets", type="targets")
    return out


def plan_mission(grammar: Grammar, graph: nx.MultiDiGraph, mission: str | Mission, *,
                 robot: str | None = None, max_expansions: int = DEFAULT_MAX_EXPANSIONS,
                 add_mission_node: bool = True) -> PlanResult:
    """Plan a mission string on a symbolic graph (adds the mission node unless told not to)."""
    parsed = mission if isinstance(mission, Mission) else parse_mission(mission, robot=robot)
    problem = check_mission(parsed, graph)
    if problem is not None:
        return NoPlan(f"mission {parsed.text!r}: {problem}")
    world = with_mission_node(graph, parsed) if add_mission_node else graph
    return Planner(grammar, world).plan(parsed.target, max_expansions=max_expansions)
