"""An agent: writes a ``note`` node in the DSR each time the robot passes within ``near_m`` of a person.

Registered under ``chronav.agents`` in this package's pyproject.toml: the entry point names
``describe``, which tells chronav where the agent's code is (``process``: the module a launch runs
as ``python -m chronav_example.note_taker``; ``agent_class``: the class an in-process run builds),
where it goes in an in-process round (after the human observer, 30: it reads the people the
observer tracked this tick) and what it writes: the ``note`` node type and the ``about`` edge from
a note to its person, both its own.  chronav's vocabulary and write policy take them in at start;
anything else it tried to write (another agent's ``person``, an undeclared attribute) would be
refused, as for chronav's own agents (docs/extending.md, section 7).

Option (``-o near_m=1.5`` on its process's command line): ``near_m``, the distance that counts as
passing someone (metres between their centres, default 2: a robot that keeps a polite distance
still passes within it).
"""

from __future__ import annotations

import math
import sys
from typing import Any

from agents.lib.agent_plugins import AgentSpec, EdgeDecl, NodeDecl
from agents.runtime.base import Agent, run_agent
from agents.runtime.checked_graph import CheckedGraph
from agents.runtime.recording import Recorder
from agents.world.vocabulary import ClockView, NodeType

NOTE, ABOUT = "note", "about"
#: metres between the robot's and a person's centres that count as passing them
NEAR_M = 2.0
#: a person must get this much farther than ``near_m`` before a new pass counts (no note per tick
#: while the robot lingers at the edge)
HYSTERESIS_M = 0.5


def describe() -> AgentSpec:
    """Writes a note node each time the robot passes within 2 m of a person."""
    return AgentSpec(
        name="note_taker", process="chronav_example.note_taker",
        agent_class="chronav_example.note_taker:NoteTaker", round_order=35,
        nodes=(NodeDecl(NOTE, {"text": "str", "time_s": "float", "person": "str", "distance_m": "float",
                               "x": "float", "y": "float"}),),
        edges=(EdgeDecl(ABOUT, src=(NOTE,), dst=(NodeType.PERSON,)),))


class NoteTaker(Agent):
    """Notes who the robot passed, when, where and how close (sim time, world frame, metres)."""

    kind = "note_taker"

    def setup(self, graph: CheckedGraph, recorder: Recorder) -> None:
        self.graph = graph
        self.rec = recorder
        self.near_m = float(self.config.options.get("near_m", NEAR_M))
        self.passing: set[str] = set()     # people within reach now (noted once per pass)
        self.notes = 0

    def step(self) -> None:
        g = self.graph
        clock = ClockView.of(g)
        robots = g.nodes_of_type(NodeType.ROBOT)
        if clock is None or not robots:
            return
        try:
            rx, ry, _ = g.world_pose(robots[0].id)
        except (KeyError, LookupError, ValueError):
            return
        for person in g.nodes_of_type(NodeType.PERSON):
            try:
                px, py, _ = g.world_pose(person.id)
            except (KeyError, LookupError, ValueError):
                continue
            distance = math.hypot(px - rx, py - ry)
            if distance <= self.near_m and person.name not in self.passing:
                self.passing.add(person.name)
                self._note(person, distance, clock.now_s, rx, ry)
            elif distance > self.near_m + HYSTERESIS_M:
                self.passing.discard(person.name)

    def _note(self, person: Any, distance: float, now_s: float, x: float, y: float) -> None:
        self.notes += 1
        name = person.name
        text = f"passed {name} at {distance:.2f} m"
        note = self.graph.insert_node(NOTE, f"note/{self.notes}", {
            "text": text, "time_s": now_s, "person": name, "distance_m": distance, "x": x, "y": y})
        if note is not None:      # None: refused (the graph logged and counted why)
            self.graph.insert_or_assign_edge(note.id, person.id, ABOUT)
            self.rec.set_time(now_s)
            self.rec.event(f"note: {text}")


if __name__ == "__main__":
    sys.exit(run_agent(NoteTaker))
