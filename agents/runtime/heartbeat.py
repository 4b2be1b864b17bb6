"""The progress stamp every agent writes in the DSR, and how a supervisor reads it.

Why in the DSR and from the agent's main loop: a process can be alive (its pid exists, its
Zenoh threads still answer, its liveliness token stays) while its loop is stuck, e.g. in an
endless computation; only a stamp written by the loop itself shows that it still makes
progress.  ``heartbeat/<agent>`` carries ``beat`` (a counter), ``pid`` (which incarnation wrote
it: a restarted agent's first stamps must not be mistaken for its predecessor's) and
``wall_s``.  The launcher (tools/system/supervisor.py) restarts an agent whose stamp stops changing.
``problem`` says, in a user's words, what keeps a running agent from its job (the ROS 2 side does
not answer, the ROS robot sends no /odom): the launcher shows it on its progress line and in the
run's summary, where before only the agent's log had it.
"""

from __future__ import annotations

import os
import time

from agents.world.vocabulary import NodeType, heartbeat_name
from dsr.model import Attrs
from dsr.protocols import GraphReader, GraphWriter

#: wall seconds between two stamps: 6 agents -> 6 small deltas a second
HEARTBEAT_PERIOD_S = 1.0


class Heartbeat:
    """Stamps ``heartbeat/<agent>`` at most every ``period_s`` wall seconds."""

    def __init__(self, graph: GraphWriter, agent: str, period_s: float = HEARTBEAT_PERIOD_S) -> None:
        self.graph, self.agent, self.period_s = graph, agent, period_s
        self.beat = 0
        self._last = -float("inf")
        self._problem = ""

    def maybe_beat(self, problem: str = "") -> None:
        """Stamp (at most every ``period_s``), with the agent's ``problem`` when it changed."""
        now = time.monotonic()
        if now - self._last < self.period_s:
            return
        self._last = now
        self.beat += 1
        attrs: Attrs = {"beat": self.beat, "pid": os.getpid(), "wall_s": time.time()}
        if problem != self._problem:
            attrs["problem"] = self._problem = problem
        node = self.graph.get_node_by_name(heartbeat_name(self.agent))
        if node is None:
            self.graph.insert_node(type=NodeType.HEARTBEAT, name=heartbeat_name(self.agent), attrs=attrs)
        else:
            self.graph.update_node(node.id, attrs=attrs)


def read_stamp(graph: GraphReader, agent: str) -> tuple[int, int] | None:
    """(pid, beat) of the agent's last stamp, None before its first one."""
    node = graph.get_node_by_name(heartbeat_name(agent))
    if node is None:
        return None
    pid, beat = node.attrs.get("pid"), node.attrs.get("beat")
    if not isinstance(pid, int) or not isinstance(beat, int):
        return None
    return pid, beat


def read_problem(graph: GraphReader, agent: str) -> str:
    """What the agent last reported as keeping it from its job ("" when nothing, or no stamp yet)."""
    node = graph.get_node_by_name(heartbeat_name(agent))
    problem = None if node is None else node.attrs.get("problem")
    return problem if isinstance(problem, str) else ""
