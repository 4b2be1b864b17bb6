"""The world written into the DSR: the functions the agents call to publish what they own.

Why shared: each agent publishes its part of the world live (the simulator the building and the
clock, the recogniser the objects, the observer the people, the agenda the activities and R(t)),
and the offline commands build the same graph at a sim time by calling the same functions
(``agents/world/offline.py``).  Every function here is idempotent: it writes only what differs
from the graph, so an agent may call it every loop and a restarted agent may call it again.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from typing import Any

from agents.lib.agenda import Activity, AgendaDay
from agents.lib.agenda.chronemics import ChronemicsParams, r_band, r_of_t
from agents.world.vocabulary import (AGENDA, CLOCK, GROUND_TRUTH_PEOPLE, WORLD, ClockMode, EdgeType, NodeType,
                                     activity_name)
from dsr.model import Node
from dsr.protocols import GraphWriter
from scenes.geometry import Shape, shape_keys
from scenes.model import RobotSpec, Scene, SceneObject

R_DECIMALS = 3   # R(t) as published: a finer change is not news, and live and offline round alike
IDENTITY = {"x": 0.0, "y": 0.0, "theta": 0.0}


def shape_attrs(prefix: str, shape: Shape) -> dict[str, Any]:
    """``{prefix}_shape`` (str) and ``{prefix}_dims`` (floats, in the order of ``shape_keys``)."""
    return {f"{prefix}_shape": shape.shape, f"{prefix}_dims": [float(getattr(shape, k)) for k in shape_keys(shape.shape)]}


def _world(graph: GraphWriter) -> Node:
    return graph.get_node_by_name(WORLD) or graph.insert_node(type=NodeType.WORLD, name=WORLD, attrs={})


def _set_in_room(graph: GraphWriter, node_id: int, room_name: str | None) -> None:
    """Exactly one ``in`` edge from the node, to ``room_name`` (none when it is in no room).
    (The room by id only: a snapshot of it would copy its polygon at every person's every write.)"""
    room_id = graph.node_id_of(room_name) if room_name else None
    there = False
    for edge in graph.edges_from(node_id, EdgeType.IN):
        if edge.dst == room_id:
            there = True
        else:
            graph.delete_edge(node_id, edge.dst, EdgeType.IN)
    if room_id is not None and not there:
        graph.insert_or_assign_edge(node_id, room_id, EdgeType.IN, attrs={})


def _set_pose(graph: GraphWriter, parent_id: int, node_id: int, pose: Mapping[str, float]) -> None:
    edge = graph.get_edge(parent_id, node_id, EdgeType.RT)
    if edge is None or any(edge.attrs.get(k) != v for k, v in pose.items()):
        graph.insert_or_assign_edge(parent_id, node_id, EdgeType.RT, attrs=dict(pose))


# ----------------------------------------------------------------------------- simulator: building, clock, robot
def write_building(graph: GraphWriter, scene: Scene, doors_open: Mapping[str, bool]) -> None:
    """World root, rooms (polygons), doors (with their open state) and the ``connected`` edges."""
    with graph.transaction():
        world = _world(graph)
        for room in scene.rooms:
            if graph.get_node_by_name(room.name) is None:
                xs, ys = zip(*room.polygon, strict=True)
                node = graph.insert_node(type=NodeType.ROOM, name=room.name,
                                         attrs={"polygon_x": list(map(float, xs)), "polygon_y": list(map(float, ys))})
                graph.insert_or_assign_edge(world.id, node.id, EdgeType.RT, attrs=dict(IDENTITY))
        for door in scene.doors:
            if graph.get_node_by_name(door.name) is None:
                # The `connected` edges name this node in their `door` attribute (grammar changeRoom).
                graph.insert_node(type=NodeType.DOOR, name=door.name,
                                  attrs={"x": door.position[0], "y": door.position[1], "width": door.width,
                                         "rooms": list(door.between), "open": doors_open.get(door.name, True)})
            a, b = (graph.require_node(name) for name in door.between)
            # One `connected` edge per room pair (edges are keyed by type): it lists all their doors.
            doors = [d.name for d in scene.doors if set(d.between) == set(door.between)]
            for src, dst in ((a, b), (b, a)):
                if graph.get_edge(src.id, dst.id, EdgeType.CONNECTED) is None:
                    graph.insert_or_assign_edge(src.id, dst.id, EdgeType.CONNECTED, attrs={"door": doors[0], "doors": doors})
        set_doors(graph, doors_open)


def set_doors(graph: GraphWriter, doors_open: Mapping[str, bool]) -> list[tuple[str, bool]]:
    """Bring each door's ``open`` attribute to ``doors_open``; the doors that changed."""
    changed = []
    for name, is_open in sorted(doors_open.items()):
        node = graph.get_node_by_name(name)
        if node is not None and node.attrs.get("open") != is_open:
            graph.update_node(node.id, attrs={"open": is_open})
            changed.append((name, is_open))
    return changed


def write_clock(graph: GraphWriter, scene: Scene, now_s: float, rate: float) -> Node:
    node = graph.get_node_by_name(CLOCK)
    if node is None:
        node = graph.insert_node(type=NodeType.CLOCK, name=CLOCK,
                                 attrs={"now_s": now_s, "start_s": scene.clock.start_s, "end_s": scene.clock.end_s,
                                        "rate": rate, "mode": ClockMode.IDLE, "finished": False})
    elif node.attrs.get("now_s") != now_s:
        graph.update_node(node.id, attrs={"now_s": now_s})
    return node


def write_robot(graph: GraphWriter, spec: RobotSpec, pose: tuple[float, float, float], room: str | None,
                laser_angles: list[float]) -> Any:
    """The robot node, its pose (RT world -> robot) and its room."""
    with graph.transaction():
        world = _world(graph)
        node = graph.get_node_by_name(spec.name)
        if node is None:
            node = graph.insert_node(type=NodeType.ROBOT, name=spec.name,
                                     attrs={"radius": spec.radius, "kinematics": spec.kinematics,
                                            "max_speed": spec.max_speed, "nav_active": False,
                                            "laser_angles": laser_angles})
        _set_pose(graph, world.id, node.id, {"x": pose[0], "y": pose[1], "theta": pose[2]})
        _set_in_room(graph, node.id, room)
    return node


def write_ground_truth(graph: GraphWriter, people: Sequence[Any], now_s: float) -> None:
    """The simulated world's people as they truly are (``ground_truth/people``): what the simulated
    sensors - the human observer - perceive, with their own noise.  Written with the pose and the
    clock in one delta; never read by planners, which see people only through the observer."""
    attrs = {"names": [p.name for p in people], "roles": [p.role for p in people],
             "x": [float(p.x) for p in people], "y": [float(p.y) for p in people],
             "theta": [float(p.theta) for p in people], "vx": [float(p.vx) for p in people],
             "vy": [float(p.vy) for p in people], "groups": [p.group for p in people]}
    node = graph.get_node_by_name(GROUND_TRUTH_PEOPLE)
    if node is None:
        graph.insert_node(type=NodeType.GROUND_TRUTH, name=GROUND_TRUTH_PEOPLE, attrs={**attrs, "stamp": now_s})
        return
    changed = {k: v for k, v in attrs.items() if node.attrs.get(k) != v}
    if changed or node.attrs.get("stamp") != now_s:
        graph.update_node(node.id, attrs={**changed, "stamp": now_s})


# ----------------------------------------------------------------------------- object recognition
def object_attrs(obj: SceneObject) -> dict[str, Any]:
    """DSR attributes of a recognised scene object (its pose goes on its RT edge)."""
    return {"kind": obj.kind, "forbidden_while_active": obj.forbidden_while_active,
            **shape_attrs("footprint", obj.footprint), **shape_attrs("interaction", obj.interaction)}


def write_object(graph: GraphWriter, obj: SceneObject, room: str | None) -> bool:
    """One object with its shapes, pose and room; True when it was new."""
    attrs = object_attrs(obj)
    pose = {"x": obj.pose.x, "y": obj.pose.y, "theta": obj.pose.theta}
    with graph.transaction():
        world = _world(graph)
        node = graph.get_node_by_name(obj.name)
        new = node is None
        if node is None:
            node = graph.insert_node(type=NodeType.OBJECT, name=obj.name, attrs=attrs)
        elif any(node.attrs.get(k) != v for k, v in attrs.items()):
            graph.update_node(node.id, attrs=attrs)
        _set_pose(graph, world.id, node.id, pose)
        _set_in_room(graph, node.id, room)
    return new


# ----------------------------------------------------------------------------- human observer
def write_person(graph: GraphWriter, name: str, role: str, pose: tuple[float, float, float], room: str | None,
                 seen_s: float, velocity: tuple[float, float] = (0.0, 0.0)) -> None:
    """A person as perceived: pose (RT world -> person), velocity (m/s, world frame), room, and
    when they were seen."""
    with graph.transaction():      # (ids, not snapshots: the observer writes 40 people a tick)
        world_id = graph.node_id_of(WORLD)
        if world_id is None:
            world_id = _world(graph).id
        node_id = graph.node_id_of(name)
        if node_id is None:
            node_id = graph.insert_node(type=NodeType.PERSON, name=name, attrs={"role": role}).id
        _set_pose(graph, world_id, node_id, {"x": pose[0], "y": pose[1], "theta": pose[2]})
        graph.update_node(node_id, attrs={"seen_s": seen_s, "vx": float(velocity[0]), "vy": float(velocity[1])})
        _set_in_room(graph, node_id, room)


def remove_person(graph: GraphWriter, name: str) -> bool:
    """A person the observer no longer perceives (they left the scene: a replayed recording says
    so) leaves the graph, their edges with them; True when there was one."""
    node = graph.get_node_by_name(name)
    if node is None or node.type != NodeType.PERSON:
        return False
    graph.delete_node(node.id)
    return True


def write_interactions(graph: GraphWriter, pairs: Iterable[tuple[str, str]]) -> bool:
    """Exactly these ``interacting`` edges (person -> person | object), by name; True if any changed."""
    wanted: set[tuple[int, int]] = set()
    for src_name, dst_name in pairs:
        src, dst = graph.get_node_by_name(src_name), graph.get_node_by_name(dst_name)
        if src is not None and dst is not None:
            wanted.add((src.id, dst.id))
    current = {(e.src, e.dst) for e in graph.edges_of_type(EdgeType.INTERACTING)}
    if wanted == current:
        return False
    with graph.transaction():
        for src_id, dst_id in current - wanted:
            graph.delete_edge(src_id, dst_id, EdgeType.INTERACTING)
        for src_id, dst_id in wanted - current:
            graph.insert_or_assign_edge(src_id, dst_id, EdgeType.INTERACTING, attrs={})
    return True


# ----------------------------------------------------------------------------- agenda
def activity_attrs(activity: Activity) -> dict[str, Any]:
    """What the DSR holds of an activity whose state is already brought up to the sim time."""
    return {"activity_id": activity.id, "name": activity.name, "object": activity.object,
            "room": activity.room or "", "start_s": activity.start_s, "end_s": activity.end_s,
            "participants": list(activity.participants), "state": activity.state.value, "source": activity.source}


def write_activities(graph: GraphWriter, day_now: AgendaDay) -> bool:
    """``activity/<id>`` nodes for the day (states as given), their ``has`` and ``participant``
    edges; activities no longer in the day are deleted.  False while an edge could not be written
    yet (its object or person is not in the graph): call again later."""
    complete = True
    wanted = {a.id: activity_attrs(a) for a in day_now.activities}
    with graph.transaction():
        for activity_id, attrs in wanted.items():
            node = graph.get_node_by_name(activity_name(activity_id))
            if node is None:
                node = graph.insert_node(type=NodeType.ACTIVITY, name=activity_name(activity_id), attrs=attrs)
            elif any(node.attrs.get(k) != v for k, v in attrs.items()):
                graph.update_node(node.id, attrs=attrs)
            obj = graph.get_node_by_name(str(attrs["object"]))
            if obj is None:
                complete = False
            elif graph.get_edge(node.id, obj.id, EdgeType.HAS) is None:
                graph.insert_or_assign_edge(node.id, obj.id, EdgeType.HAS, attrs={})
            for person_name in attrs["participants"]:
                person = graph.get_node_by_name(str(person_name))
                if person is None or person.type != NodeType.PERSON:
                    complete = False
                elif graph.get_edge(person.id, node.id, EdgeType.PARTICIPANT) is None:
                    graph.insert_or_assign_edge(person.id, node.id, EdgeType.PARTICIPANT, attrs={})
        for node in graph.nodes_of_type(NodeType.ACTIVITY):
            if str(node.attrs.get("activity_id")) not in wanted:
                graph.delete_node(node.id)
    return complete


def object_r(day: AgendaDay, object_name: str, now_s: float, params: ChronemicsParams) -> tuple[float, int, bool]:
    """(R, colour band, running) of one object at ``now_s``; R rounded to ``R_DECIMALS`` so that
    the agenda agent (which writes only changes) and the offline graph (written once) hold the
    same value at any time."""
    own = [w for w in day.windows() if w.object == object_name]
    r = round(r_of_t(now_s, own, params), R_DECIMALS)
    return r, r_band(r, params), any(w.running_at(now_s) for w in own)


def write_object_r(graph: GraphWriter, day: AgendaDay, now_s: float, params: ChronemicsParams) -> dict[str, float]:
    """Each object's R(t), band and activity flag (written when they changed); R per object."""
    values: dict[str, float] = {}
    with graph.transaction():
        for node in graph.nodes_of_type(NodeType.OBJECT):
            r, band, running = object_r(day, node.name, now_s, params)
            values[node.name] = r
            if node.attrs.get("R") != r or node.attrs.get("active") != running \
                    or node.attrs.get("R_band") != band:
                graph.update_node(node.id, attrs={"R": r, "R_band": band, "active": running})
    return values


def agenda_log(graph: GraphWriter) -> Node:
    """The ``agenda`` node: the replayable log of accepted changes and applied scripted ones."""
    node = graph.get_node_by_name(AGENDA)
    if node is None:
        node = graph.insert_node(type=NodeType.AGENDA, name=AGENDA, attrs={"applied": [], "changes": []})
    return node
