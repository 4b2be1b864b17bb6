"""The human observer agent: perceives people, tracks them, writes them into the DSR.

Why noise and a tracker in a simulator: the social map must be robust to jittery detections,
and an observer that republishes every sensor jitter would flood the graph and make the
navigation replan for nothing.  Detections carry identity (as a re-identification camera
network does); the tracker smooths them and publishes a person only when it has moved.
"""

from __future__ import annotations

import math

import numpy as np

from agents.runtime.base import Agent
from agents.runtime.freshness import mark_observed
from agents.runtime.recording import Recorder
from scenes.motion import people_at

PUBLISH_MOVE_M = 0.03
PUBLISH_TURN_RAD = 0.05
INTERACTION_RANGE_M = 1.8


class HumanObserverAgent(Agent):
    kind = "human_observer"

    def setup(self, graph, recorder: Recorder) -> None:  # noqa: ANN001
        self.graph = graph
        self.rec = recorder
        self.noise_xy = float(self.config.option("noise_xy", "0.02"))
        self.noise_theta = float(self.config.option("noise_theta", "0.03"))
        self.smoothing = float(self.config.option("smoothing", "0.5"))
        self.rng = np.random.default_rng(int(self.config.option("seed", "7")))
        self.tracks: dict[str, tuple[float, float, float]] = {}
        self.published: dict[str, tuple[float, float, float]] = {}
        self._last_t: float | None = None

    def _now(self) -> float | None:
        clock = self.graph.get_node_by_name("clock")
        return None if clock is None else float(clock.attrs["now_s"])

    def step(self) -> None:
        now_s = self._now()
        world = self.graph.get_node_by_name("world")
        if now_s is None or world is None or now_s == self._last_t:
            return
        self._last_t = now_s
        self.rec.set_time(now_s)
        for truth in people_at(self.scene, now_s):
            det = (truth.x + self.rng.normal(0, self.noise_xy), truth.y + self.rng.normal(0, self.noise_xy),
                   truth.theta + self.rng.normal(0, self.noise_theta))
            prev = self.tracks.get(truth.name)
            if prev is None or truth.moving or math.hypot(det[0] - prev[0], det[1] - prev[1]) > 0.5:
                track = det  # new, walking or re-acquired: no smoothing lag
            else:
                a = self.smoothing
                dtheta = math.atan2(math.sin(det[2] - prev[2]), math.cos(det[2] - prev[2]))
                track = (prev[0] + a * (det[0] - prev[0]), prev[1] + a * (det[1] - prev[1]), prev[2] + a * dtheta)
            self.tracks[truth.name] = track
            self._publish(truth.name, truth.role, track, now_s)
        self._publish_interactions(now_s)
        mark_observed(self.graph, self.config.name, now_s)
        self._log()

    def _publish(self, name: str, role: str, pose: tuple[float, float, float], now_s: float) -> None:
        old = self.published.get(name)
        g = self.graph
        node = g.get_node_by_name(name)
        if node is not None and old is not None and math.hypot(pose[0] - old[0], pose[1] - old[1]) < PUBLISH_MOVE_M \
                and abs(math.atan2(math.sin(pose[2] - old[2]), math.cos(pose[2] - old[2]))) < PUBLISH_TURN_RAD:
            return
        world = g.get_node_by_name("world")
        with g.transaction():
            if node is None:
                node = g.insert_node(type="person", name=name, attrs={"role": role})
            g.insert_or_assign_edge(world.id, node.id, "RT", attrs={"x": pose[0], "y": pose[1], "theta": pose[2]})
            g.update_node(node.id, attrs={"seen_s": now_s})
            room_name = self.scene.room_at(pose[0], pose[1])
            room = g.get_node_by_name(room_name) if room_name else None
            for edge in g.edges_from(node.id, "in"):
                if room is None or edge.dst != room.id:
                    g.delete_edge(node.id, edge.dst, "in")
            if room is not None:
                g.insert_or_assign_edge(node.id, room.id, "in", attrs={})
        self.published[name] = pose

    def _publish_interactions(self, now_s: float) -> None:
        """Declared conversations from the scene, plus participants at their running activity's object."""
        g = self.graph
        wanted: set[tuple[int, int]] = set()
        for spec in self.scene.people:
            me = g.get_node_by_name(spec.name)
            if me is None:
                continue
            for other_name in spec.interacting_with:
                other = g.get_node_by_name(other_name)
                if other is not None:
                    wanted.add((me.id, other.id))
        for activity in g.nodes_of_type("activity"):
            if activity.attrs.get("state") != "running":
                continue
            obj = g.get_node_by_name(str(activity.attrs.get("object", "")))
            if obj is None:
                continue
            ox, oy, _ = g.world_pose(obj.id)
            for name in activity.attrs.get("participants", []):
                person = g.get_node_by_name(name)
                track = self.tracks.get(name)
                if person is not None and track is not None and math.hypot(track[0] - ox, track[1] - oy) < INTERACTION_RANGE_M:
                    wanted.add((person.id, obj.id))
        current = {(e.src, e.dst) for e in g.edges_of_type("interacting")}
        if wanted == current:
            return
        with g.transaction():
            for src, dst in current - wanted:
                if g.get_node(src) is not None and g.get_node(src).type == "person":
                    g.delete_edge(src, dst, "interacting")
            for src, dst in wanted - current:
                g.insert_or_assign_edge(src, dst, "interacting", attrs={})

    def _log(self) -> None:
        if not self.rec.enabled or not self.tracks:
            return
        import rerun as rr

        names = sorted(self.tracks)
        xy = [[self.tracks[n][0], self.tracks[n][1]] for n in names]
        self.rec.log("world/people/positions", rr.Points2D(xy, radii=0.25, colors=[[240, 160, 40]], labels=names))
        heads = [[[x, y], [x + 0.45 * math.cos(self.tracks[n][2]), y + 0.45 * math.sin(self.tracks[n][2])]]
                 for n, (x, y) in zip(names, xy, strict=True)]
        self.rec.log("world/people/headings", rr.LineStrips2D(heads, colors=[[240, 160, 40]], radii=0.03))
