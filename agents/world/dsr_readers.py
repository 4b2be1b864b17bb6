"""The world read back from the DSR: social-map inputs and the symbolic graph.

Why here: the navigation agent and the executive read the DSR; the offline commands read a DSR
built by ``agents/world/offline.py``.  Both call these functions, so they see the same people,
objects, activities and doors.  Malformed elements (a peer on another version, a half-written
node) are skipped rather than crashing the reader.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

from agents.lib.agenda.model import ActivityWindow, AgendaError
from agents.lib.socialmap.types import Person, SocialMapInputError, SocialObject
from agents.world.vocabulary import CLOCK, ActivityState, EdgeType, NodeType
from dsr.attr_values import as_float, as_strs
from dsr.protocols import GraphReader
from scenes.geometry import SHAPE_FIELDS, GeometryError, Shape, shape_from_spec, shape_keys

if TYPE_CHECKING:  # networkx (0.1 s) loads with DSRGraph.to_networkx, only when a symbolic view is asked for
    import networkx as nx


def shape_from_attrs(prefix: str, attrs: dict[str, Any], where: str) -> Shape:
    kind = attrs.get(f"{prefix}_shape")
    dims = attrs.get(f"{prefix}_dims")
    if kind not in SHAPE_FIELDS or not isinstance(dims, list) or len(dims) != len(shape_keys(kind)):
        raise GeometryError(f"{where}: attributes {prefix}_shape/{prefix}_dims are missing or malformed")
    return shape_from_spec({"shape": kind, **dict(zip(shape_keys(kind), dims, strict=True))}, where)


def dsr_objects(graph: GraphReader) -> list[SocialObject]:
    """Objects as the DSR holds them."""
    out: list[SocialObject] = []
    for node in graph.nodes_of_type(NodeType.OBJECT):
        try:
            x, y, theta = graph.world_pose(node.id)
            out.append(SocialObject(name=node.name, kind=str(node.attrs.get("kind", "object")), x=x, y=y,
                                    theta=theta, footprint=shape_from_attrs("footprint", node.attrs, node.name),
                                    interaction=shape_from_attrs("interaction", node.attrs, node.name),
                                    forbidden_while_active=bool(node.attrs.get("forbidden_while_active", False))))
        except (GeometryError, KeyError, LookupError):
            continue
    return out


DUE_BEFORE_S = 360.0   # an activity's participants are on their way this long before it starts


def dsr_people(graph: GraphReader) -> list[Person]:
    """People with their poses and the people they interact with (``interacting`` edges)."""
    out: list[Person] = []
    interacting: dict[int, list[str]] = {}
    for edge in graph.edges_of_type(EdgeType.INTERACTING):
        other = graph.get_node(edge.dst)
        if other is not None and other.type == NodeType.PERSON:
            interacting.setdefault(edge.src, []).append(other.name)
    heading_to = destinations(graph)
    doors = DoorGraph.of(graph) if heading_to else None
    for node in graph.nodes_of_type(NodeType.PERSON):
        try:
            x, y, theta = graph.world_pose(node.id)
            goal = heading_to.get(node.id)
            out.append(Person(name=node.name, x=x, y=y, theta=theta, role=str(node.attrs.get("role", "resident")),
                              interacting_with=tuple(sorted(interacting.get(node.id, ()))),
                              vx=as_float(node.attrs.get("vx", 0.0)), vy=as_float(node.attrs.get("vy", 0.0)),
                              destination=goal,
                              via=doors.via((x, y), goal) if doors is not None and goal is not None else ()))
        except (SocialMapInputError, KeyError, LookupError, ValueError, TypeError):
            continue
    return out


def destinations(graph: GraphReader) -> dict[int, tuple[float, float]]:
    """Where the agenda says people are going: a participant of a running activity, or of one due
    within ``DUE_BEFORE_S`` (the simulated participants leave to arrive 2.5 min early, always
    within the 5 min before it), is walking to its object (the prediction of a walker's path
    follows it, motion.py).  The earliest such activity wins."""
    out: dict[int, tuple[float, float, float]] = {}
    clock = graph.get_node_by_name(CLOCK)
    now_s = clock.attrs.get("now_s") if clock is not None else None
    for edge in graph.edges_of_type(EdgeType.PARTICIPANT):
        activity = graph.get_node(edge.dst)
        if activity is None or activity.attrs.get("state") not in (ActivityState.UPCOMING, ActivityState.RUNNING):
            continue
        if isinstance(now_s, (int, float)) and as_float(activity.attrs.get("start_s", 0.0)) - now_s > DUE_BEFORE_S:
            continue   # not due yet: the participant is not on the way (motion.py)
        obj = graph.get_node_by_name(str(activity.attrs.get("object", "")))
        if obj is None:
            continue
        try:
            x, y, _ = graph.world_pose(obj.id)
            start = as_float(activity.attrs.get("start_s", 0.0))
        except (KeyError, LookupError, ValueError, TypeError):
            continue
        if edge.src not in out or start < out[edge.src][2]:
            out[edge.src] = (x, y, start)
    return {person: (x, y) for person, (x, y, _) in out.items()}


class DoorGraph:
    """The building's rooms and open doors as the DSR holds them, to route a person to a place:
    the doors on the shortest way (door to door in straight lines through the rooms between), so
    a prediction follows doors instead of running into a wall (motion.py).  The ways between doors
    are computed once per graph read (Floyd-Warshall over the few doors, in numpy: `chronav path`
    loads neither networkx nor scipy.sparse for it); a person's query only joins her start and goal
    to the doors of their rooms."""

    def __init__(self, rooms: dict[str, Any], doors: dict[str, tuple[float, float, tuple[str, ...]]]) -> None:
        import numpy as np

        self.rooms = rooms          # name -> shapely polygon
        self.doors = doors          # name -> (x, y, the two rooms)
        self._names = list(doors)
        self._index = {name: i for i, name in enumerate(self._names)}
        n = len(doors)
        lengths = np.full((n, n), math.inf)
        np.fill_diagonal(lengths, 0.0)
        for i, (x, y, between) in enumerate(doors.values()):
            for j, (ox, oy, other_between) in enumerate(doors.values()):
                if i != j and set(between) & set(other_between):
                    lengths[i, j] = math.dist((x, y), (ox, oy))
        following = np.tile(np.arange(n), (n, 1))   # following[i, j]: the next door from i toward j
        for k in range(n):
            through = lengths[:, k, None] + lengths[None, k, :]
            shorter = through < lengths
            lengths = np.where(shorter, through, lengths)
            following = np.where(shorter, following[:, k, None], following)
        self._lengths, self._following = lengths, following

    def length(self, a: str, b: str) -> float:
        """The shortest way from door ``a`` to door ``b`` through the rooms (inf: none)."""
        return float(self._lengths[self._index[a], self._index[b]])

    def way(self, a: str, b: str) -> list[str]:
        """The doors from ``a`` to ``b`` on the shortest way, both included."""
        i, j = self._index[a], self._index[b]
        doors = [self._names[i]]
        while i != j:
            i = int(self._following[i, j])
            doors.append(self._names[i])
        return doors

    @classmethod
    def of(cls, graph: GraphReader) -> DoorGraph:
        import shapely

        rooms = {}
        for node in graph.nodes_of_type(NodeType.ROOM):
            xs, ys = node.attrs.get("polygon_x"), node.attrs.get("polygon_y")
            if isinstance(xs, list) and isinstance(ys, list) and len(xs) == len(ys) and len(xs) >= 3:
                rooms[node.name] = shapely.Polygon(list(zip(xs, ys, strict=True)))
        doors = {}
        for node in graph.nodes_of_type(NodeType.DOOR):
            a = node.attrs
            if a.get("open") is False:
                continue
            try:
                doors[node.name] = (as_float(a["x"]), as_float(a["y"]), tuple(as_strs(a["rooms"])))
            except (KeyError, TypeError, ValueError):
                continue
        return cls(rooms, doors)

    def room_at(self, x: float, y: float) -> str | None:
        import shapely

        point = shapely.Point(x, y)
        return next((name for name, poly in self.rooms.items() if poly.covers(point)), None)

    def via(self, start: tuple[float, float], goal: tuple[float, float]) -> tuple[tuple[float, float], ...]:
        """Door positions from ``start`` to ``goal``, in order; () in the same room, or when no
        way is known (the prediction then goes straight, and stops at a wall)."""
        here, there = self.room_at(*start), self.room_at(*goal)
        if here is None or there is None or here == there:
            return ()
        best: tuple[float, tuple[str, str]] | None = None
        for a, (ax, ay, a_rooms) in self.doors.items():
            if here not in a_rooms:
                continue
            for b, (bx, by, b_rooms) in self.doors.items():
                if there not in b_rooms or math.isinf(self.length(a, b)):
                    continue
                cost = math.dist(start, (ax, ay)) + self.length(a, b) + math.dist((bx, by), goal)
                if best is None or cost < best[0]:
                    best = (cost, (a, b))
        return () if best is None else tuple(self.doors[name][:2] for name in self.way(*best[1]))


def dsr_activity_windows(graph: GraphReader) -> list[ActivityWindow]:
    out: list[ActivityWindow] = []
    for node in graph.nodes_of_type(NodeType.ACTIVITY):
        attrs = node.attrs
        try:
            out.append(ActivityWindow(object=str(attrs["object"]), start_s=as_float(attrs["start_s"]),
                                      end_s=as_float(attrs["end_s"]), cancelled=attrs.get("state") == ActivityState.CANCELLED))
        except (KeyError, ValueError, TypeError, AgendaError):
            continue
    return out


def closed_doors(graph: GraphReader) -> list[str]:
    """Names of the doors the DSR says are closed."""
    return sorted(node.name for node in graph.nodes_of_type(NodeType.DOOR) if node.attrs.get("open") is False)


SYMBOLIC_TYPES = frozenset({NodeType.ROOM, NodeType.DOOR, NodeType.ROBOT, NodeType.PERSON, NodeType.OBJECT,
                            NodeType.ACTIVITY})


def symbolic_view(graph: GraphReader) -> nx.MultiDiGraph:
    """The part of the DSR the grammar reasons about (no clock, missions, intentions, requests):
    nodes keyed by id with ``type``, ``name`` and their attributes; edges keyed by their type."""
    full = graph.to_networkx()
    keep = [n for n, data in full.nodes(data=True) if data.get("type") in SYMBOLIC_TYPES]
    return full.subgraph(keep).copy()


def running_activities(graph: GraphReader) -> list[tuple[str, tuple[float, float], tuple[str, ...]]]:
    """(object, object position, participants) of every activity the DSR says is running."""
    out = []
    for node in graph.nodes_of_type(NodeType.ACTIVITY):
        if node.attrs.get("state") != ActivityState.RUNNING:
            continue
        obj = graph.get_node_by_name(str(node.attrs.get("object", "")))
        if obj is None:
            continue
        try:
            x, y, _ = graph.world_pose(obj.id)
        except (KeyError, LookupError, ValueError):
            continue
        out.append((obj.name, (x, y), tuple(as_strs(node.attrs.get("participants", [])))))
    return out
