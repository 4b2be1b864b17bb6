"""The object recognition agent: writes the objects people use into the DSR.

Why objects carry their own shape parameters in the graph: the social navigation agent (maybe on
another machine) must rebuild interaction spaces from the DSR alone; the footprint and the
interaction space are properties of the recognised object model, so they travel with it.
"""

from __future__ import annotations

import math

from agents.runtime.base import Agent
from agents.runtime.recording import Recorder
from agents.world_model import object_attrs

CHECK_PERIOD_S = 5.0


class ObjectRecognitionAgent(Agent):
    kind = "object_recognition"

    def setup(self, graph, recorder: Recorder) -> None:  # noqa: ANN001
        self.graph = graph
        self.rec = recorder
        self._last_check = -math.inf

    def step(self) -> None:
        g = self.graph
        world, clock = g.get_node_by_name("world"), g.get_node_by_name("clock")
        if world is None or clock is None:
            return
        now_s = float(clock.attrs["now_s"])
        if now_s - self._last_check < CHECK_PERIOD_S:
            return
        self._last_check = now_s
        self.rec.set_time(now_s)  # its events belong on the sim_time timeline like everyone's
        for obj in self.scene.objects:
            self._publish(obj, world.id)

    def _publish(self, obj, world_id: int) -> None:  # noqa: ANN001 - scenes.model.SceneObject
        g = self.graph
        node = g.get_node_by_name(obj.name)
        attrs = object_attrs(obj)
        pose = {"x": obj.pose.x, "y": obj.pose.y, "theta": obj.pose.theta}
        if node is not None:
            edge = g.get_edge(world_id, node.id, "RT")
            same_attrs = all(node.attrs.get(k) == v for k, v in attrs.items())
            if edge is not None and same_attrs and all(abs(edge.attrs[k] - v) < 1e-6 for k, v in pose.items()):
                return
        with g.transaction():
            if node is None:
                node = g.insert_node(type="object", name=obj.name, attrs=attrs)
                self.rec.event(f"recognised {obj.kind} {obj.name!r}")
            else:
                g.update_node(node.id, attrs=attrs)
            g.insert_or_assign_edge(world_id, node.id, "RT", attrs=pose)
            room_name = self.scene.room_at(obj.pose.x, obj.pose.y)
            room = g.get_node_by_name(room_name) if room_name else None
            if room is not None:
                g.insert_or_assign_edge(node.id, room.id, "in", attrs={})
