"""Log the DSR itself to Rerun as a graph view: what a reader needs, laid out by room.

What is shown: rooms, objects, activities, people, the robot and missions, with their symbolic
edges (``connected``, ``interacting``, an activity's object and participants, a mission's target).  What is folded: the
RT tree (poses are the map view's job), ``in`` edges (the layout's columns say it), activities
neither running nor upcoming, the clock, sensors, ground truth, intentions and other
bookkeeping nodes: on center_day they were ~30 more nodes in an unreadable column.

Layout (why not the building's geometry): people crowd a room, and nodes placed where they stand
overlap.  Each room is a column, ordered west to east as in the building; under a room come its
objects, their running or upcoming activities and then its people (two to a row in a crowded room); the robot sits
in its room's column, the missions in a last column.  Positions are fixed, so the view does
not jump when the graph changes.

Why throttled and change-driven: the graph changes on every robot pose; a graph view needs the
*structure*, so it is logged only when the shown structure changes, at most once per
``min_period_s`` of sim time.
"""

from __future__ import annotations

from typing import Any

from agents.runtime.drawing.labels import short_id
from agents.world.vocabulary import ActivityState, EdgeType, NodeType
from dsr.attr_values import as_floats
from dsr.model import Node
from dsr.protocols import GraphReader

TYPE_COLOURS: dict[str, tuple[int, int, int]] = {
    NodeType.ROOM: (90, 160, 90), NodeType.PERSON: (240, 160, 40), NodeType.OBJECT: (160, 90, 200),
    NodeType.ROBOT: (0, 230, 90), NodeType.ACTIVITY: (230, 60, 60), NodeType.MISSION: (20, 180, 180),
}
SHOWN_TYPES = frozenset(TYPE_COLOURS)
# RT: poses are the map view's; in: a node's column is its room already (one edge per person was a web)
HIDDEN_EDGES = {EdgeType.RT, EdgeType.IN}
#: activities worth a node: what runs or is about to (the rest of the day is in R(t) and the agenda)
SHOWN_ACTIVITY_STATES = frozenset({ActivityState.UPCOMING, ActivityState.RUNNING})
# Compact: the view zooms to fit the whole graph, so a wide layout would shrink every label.
COLUMN_PX, ROW_PX, PERSON_COLUMN_PX, ACTIVITY_INDENT_PX = 140.0, 30.0, 60.0, 18.0
CROWDED_ROOM = 4   # more people than this in a room: they go two to a row


class GraphLogger:
    def __init__(self, recorder: Any, min_period_s: float = 5.0) -> None:
        self.rec = recorder
        self.min_period_s = min_period_s
        self._last_signature: tuple[Any, ...] | None = None
        self._last_time: float | None = None

    def maybe_log(self, graph: GraphReader, now_s: float | None, force: bool = False) -> None:
        if not self.rec.enabled or now_s is None:
            return
        shown = [n for n in _all_nodes(graph) if n.type in SHOWN_TYPES
                 and (n.type != NodeType.ACTIVITY or n.attrs.get("state") in SHOWN_ACTIVITY_STATES)]
        ids = {n.id for n in shown}
        nodes = sorted((n.id, n.type, n.name, str(n.attrs.get("state", ""))) for n in shown)
        edges = sorted((e.src, e.dst, e.type) for e in _all_edges(graph)
                       if e.type not in HIDDEN_EDGES and e.src in ids and e.dst in ids)
        signature = (tuple(nodes), tuple(edges))
        if not force and signature == self._last_signature:
            return
        if not force and self._last_time is not None and now_s - self._last_time < self.min_period_s:
            return
        import rerun as rr

        self._last_signature, self._last_time = signature, now_s
        labels = [label(n[1], n[2], n[3]) for n in nodes]
        colours = [TYPE_COLOURS[n[1]] for n in nodes]
        positions = layout(graph, [n[0] for n in nodes])
        self.rec.set_time(now_s)
        self.rec.log("dsr", rr.GraphNodes([str(n[0]) for n in nodes], labels=labels, colors=colours,
                                          positions=positions, radii=6.0),
                     rr.GraphEdges([(str(s), str(d)) for s, d, _ in edges], graph_type="directed"))


def label(node_type: str, name: str, state: str) -> str:
    """Short: a person's id without role, an activity or mission without its ``kind/`` prefix."""
    text = short_id(name) if node_type == NodeType.PERSON else name.rsplit("/", 1)[-1]
    return f"{text} [{state}]" if state and node_type in (NodeType.ACTIVITY, NodeType.MISSION) else text


def _room_of(graph: GraphReader, node: Node, rooms: dict[int, int]) -> int | None:
    """The column of the room ``node`` is ``in`` (its ``in`` edge), or None."""
    for edge in graph.edges_from(node.id, EdgeType.IN):
        if edge.dst in rooms:
            return rooms[edge.dst]
    return None


def layout(graph: GraphReader, node_ids: list[int]) -> list[tuple[float, float]]:
    """Column per room (west to east), objects then people under it; missions in a last column."""
    nodes = {i: node for i in node_ids if (node := graph.get_node(i)) is not None}   # gone since: placed apart
    room_nodes = [n for n in nodes.values() if n.type == NodeType.ROOM]

    def centre_x(node: Node) -> float:
        xs = as_floats(node.attrs.get("polygon_x") or [0.0])
        return sum(xs) / len(xs)

    room_nodes.sort(key=lambda n: (centre_x(n), n.name))
    rooms = {n.id: col for col, n in enumerate(room_nodes)}
    extra = len(room_nodes)        # column for nodes in no room, then missions
    rows: dict[int, float] = {col: 1.0 for col in range(extra + 2)}
    placed: dict[int, tuple[float, float]] = {n.id: (rooms[n.id] * COLUMN_PX, 0.0) for n in room_nodes}
    objects_by_name: dict[str, int] = {}
    for node in sorted(nodes.values(), key=lambda n: n.name):
        if node.type in (NodeType.OBJECT, NodeType.ROBOT):
            col = _room_of(graph, node, rooms)
            col = extra if col is None else col
            placed[node.id] = (col * COLUMN_PX, rows[col] * ROW_PX)
            rows[col] += 1.0
            objects_by_name[node.name] = node.id
    for node in sorted(nodes.values(), key=lambda n: (str(n.attrs.get("object", "")), n.name)):
        if node.type == NodeType.ACTIVITY:   # a row of its own below the objects, indented: labels are long
            obj = objects_by_name.get(str(node.attrs.get("object", "")))
            col = extra if obj is None else round(placed[obj][0] / COLUMN_PX)
            placed[node.id] = (col * COLUMN_PX + ACTIVITY_INDENT_PX, rows[col] * ROW_PX)
            rows[col] += 1.0
    people_rooms = [(n, _room_of(graph, n, rooms)) for n in sorted(nodes.values(), key=lambda n: n.name)
                    if n.type == NodeType.PERSON]
    people = [(n, extra if col is None else col) for n, col in people_rooms]
    per_room = {col: sum(1 for _, c in people if c == col) for _, col in people}
    counts: dict[int, int] = {}
    for node, col in people:   # a grid of two only where a room is crowded: labels need the width
        k = counts.get(col, 0)
        counts[col] = k + 1
        across = 2 if per_room[col] > CROWDED_ROOM else 1
        placed[node.id] = (col * COLUMN_PX + (k % across) * PERSON_COLUMN_PX, (rows[col] + 0.5 + k // across) * ROW_PX)
    missions_col = extra + (1 if any(x >= extra * COLUMN_PX for x, _ in placed.values()) else 0)
    for node in sorted(nodes.values(), key=lambda n: n.name):
        if node.type == NodeType.MISSION:
            col = missions_col
            placed[node.id] = (col * COLUMN_PX, rows[col] * ROW_PX)
            rows[col] += 1.0
    return [placed.get(i, ((extra + 1) * COLUMN_PX, 0.0)) for i in node_ids]


def _all_nodes(graph: GraphReader) -> list[Any]:
    return list(graph.nodes())


def _all_edges(graph: GraphReader) -> list[Any]:
    return list(graph.edges())
