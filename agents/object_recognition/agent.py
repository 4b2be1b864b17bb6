"""The object recognition agent: writes the objects people use into the DSR.

Why objects carry their own shape parameters in the graph: the social navigation agent (maybe on
another machine) must rebuild interaction spaces from the DSR alone; the footprint and the
interaction space are properties of the recognised object model, so they travel with it.
"""

from __future__ import annotations

import math

from agents.runtime.base import Agent
from agents.runtime.checked_graph import CheckedGraph
from agents.runtime.recording import Recorder
from agents.world.dsr_writers import write_object
from agents.world.vocabulary import WORLD, ClockView
from scenes.clock import format_clock

CHECK_PERIOD_S = 5.0


class ObjectRecognitionAgent(Agent):
    kind = "object_recognition"

    def setup(self, graph: CheckedGraph, recorder: Recorder) -> None:
        self.graph = graph
        self.rec = recorder
        self._last_check = -math.inf

    def step(self) -> None:
        g = self.graph
        clock = ClockView.of(g)
        if g.get_node_by_name(WORLD) is None or clock is None:
            return
        if clock.now_s - self._last_check < CHECK_PERIOD_S:
            return
        self._last_check = clock.now_s
        self.rec.set_time(clock.now_s)  # its events belong on the sim_time timeline like everyone's
        for obj in self.scene.objects:
            if write_object(g, obj, self.scene.room_at(obj.pose.x, obj.pose.y)):
                self.rec.event(f"{format_clock(clock.now_s)} recognised {obj.kind} {obj.name!r}")
