"""The symbolic view of a scene: the typed graph the executive's grammar planner works on.

Why its own module: `chronav plan SCENE` must plan without starting any process, and the
executive agent plans on the live DSR.  Both must see the same vocabulary (docs/CONTRACTS.md),
so this builder emits exactly the node/edge types the agents write into the DSR.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

import networkx as nx

from scenes.model import Scene


def activity_state(start_s: float, end_s: float, now_s: float, upcoming_window_s: float = 45 * 60) -> str:
    """scheduled / upcoming / running / finished, the states the agenda agent writes."""
    if now_s >= end_s:
        return "finished"
    if now_s >= start_s:
        return "running"
    if start_s - now_s <= upcoming_window_s:
        return "upcoming"
    return "scheduled"


def symbolic_graph(scene: Scene, at_s: float | None = None, activities: Iterable[Any] = ()) -> nx.MultiDiGraph:
    """Rooms, doors, robot, people, objects and today's activities as a typed MultiDiGraph.

    Node keys are the scene names; every node has ``type`` and ``name``; edges are keyed by their
    type and also carry it as the ``type`` attribute.  ``at_s`` (seconds since midnight) sets
    each activity's ``state``; by default the scene clock's start.  ``activities`` are the day's
    ``agents.agenda.Activity`` items (``LoadedScene.agenda_day.activities``).
    """
    now_s = scene.clock.start_s if at_s is None else at_s
    graph = nx.MultiDiGraph()

    def add_edge(src: str, dst: str, edge_type: str, **attrs: object) -> None:
        graph.add_edge(src, dst, key=edge_type, type=edge_type, **attrs)

    graph.add_node("world", type="world", name="world")
    for room in scene.rooms:
        graph.add_node(room.name, type="room", name=room.name)
    for door in scene.doors:
        a, b = door.between
        graph.add_node(door.name, type="door", name=door.name, x=door.position[0], y=door.position[1])
        doors = [d.name for d in scene.doors if set(d.between) == set(door.between)]
        add_edge(a, b, "connected", door=doors[0], doors=doors)
        add_edge(b, a, "connected", door=doors[0], doors=doors)

    def place(name: str, node_type: str, x: float, y: float, **attrs: object) -> None:
        graph.add_node(name, type=node_type, name=name, x=x, y=y, **attrs)
        room = scene.room_at(x, y)
        if room is not None:
            add_edge(name, room, "in")

    robot = scene.robot
    place(robot.name, "robot", robot.pose.x, robot.pose.y, theta=robot.pose.theta)
    for obj in scene.objects:
        place(obj.name, "object", obj.pose.x, obj.pose.y, theta=obj.pose.theta, kind=obj.kind)
    for person in scene.people:
        place(person.name, "person", person.pose.x, person.pose.y, theta=person.pose.theta, role=person.role)
    for person in scene.people:
        for other in person.interacting_with:
            add_edge(person.name, other, "interacting")

    for activity in activities:
        name = f"activity/{activity.id}"
        state = "cancelled" if activity.cancelled else activity_state(activity.start_s, activity.end_s, now_s)
        graph.add_node(name, type="activity", name=name, activity_id=activity.id, object=activity.object,
                       start_s=activity.start_s, end_s=activity.end_s, state=state)
        add_edge(name, activity.object, "has")
        room = next((d for _, d, k in graph.out_edges(activity.object, keys=True) if k == "in"), None)
        if room is not None:
            add_edge(name, room, "in")
        for participant in activity.participants:
            if participant in graph:
                add_edge(str(participant), name, "participant")
    return graph
