"""Which sim time has each perceiving agent caught up with?

Why: when the simulator skips an idle stretch (10:45 -> 11:15 in one step), people and agenda
states in the DSR still describe 10:45 for a few milliseconds.  A planner starting a mission at
11:15 must wait for them, or it plans around people who have left.  Each perceiving agent stamps
``sensor/<agent>.observed_s`` after processing a clock value; consumers wait until all caught up.
"""

from __future__ import annotations


from agents.world.vocabulary import (AGENDA_AGENT, EXECUTIVE, OBSERVER, ActivityState, EdgeType, NodeType,
                                     SensorAttr, sensor_name)
from dsr.attr_values import as_float
from dsr.protocols import GraphReader, GraphWriter

PERCEIVERS: tuple[str, ...] = (OBSERVER, AGENDA_AGENT)
#: who stamps every tick in lockstep (-o perception_lockstep=1): the perceivers, then the executive,
#: which acts on what they saw; the navigation and the simulator's clock wait for all of them
LOCKSTEP: tuple[str, ...] = (*PERCEIVERS, EXECUTIVE)


def mark_observed(graph: GraphWriter, agent: str, now_s: float) -> None:
    name = sensor_name(agent)
    node = graph.get_node_by_name(name)
    if node is None:
        graph.insert_node(type=NodeType.SENSOR, name=name, attrs={SensorAttr.OBSERVED_S: now_s})
    elif node.attrs.get("observed_s") != now_s:
        graph.update_node(node.id, attrs={"observed_s": now_s})


def observed_s(graph: GraphReader, agent: str) -> float | None:
    """The sim time ``agent`` last stamped, or None before its first stamp."""
    node = graph.get_node_by_name(sensor_name(agent))
    if node is None:
        return None
    try:
        return as_float(node.attrs.get("observed_s"))
    except (TypeError, ValueError):
        return None


def observed_up_to(graph: GraphReader, now_s: float, agents: tuple[str, ...] = PERCEIVERS, slack_s: float = 1.0) -> bool:
    """True when every perceiver has processed a clock value within ``slack_s`` of ``now_s``."""
    for agent in agents:
        node = graph.get_node_by_name(sensor_name(agent))
        if node is None or as_float(node.attrs.get("observed_s", -1e9)) < now_s - slack_s:
            return False
    return True


def interactions_follow_activities(graph: GraphReader) -> bool:
    """False while a person -> object ``interacting`` link remains for an object no running activity
    has: the human observer has not yet seen that the activity ended (it recomputes its links on its
    next look).  A planner must not read such an object as in use."""
    running = {str(node.attrs.get("object")) for node in graph.nodes_of_type(NodeType.ACTIVITY)
               if node.attrs.get("state") == ActivityState.RUNNING}
    for edge in graph.edges_of_type(EdgeType.INTERACTING):
        target = graph.get_node(edge.dst)
        if target is not None and target.type == NodeType.OBJECT and target.name not in running:
            return False
    return True

