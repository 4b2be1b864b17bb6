"""The human observer agent: perceives people, tracks them, writes them into the DSR.

Why noise and a tracker in a simulator: the social map must be robust to jittery detections,
and an observer that republishes every sensor jitter would flood the graph and make the
navigation replan for nothing.  Detections carry identity (as a re-identification camera
network does); the tracker smooths them and publishes a person only when it has moved.
"""

from __future__ import annotations

import math
import zlib

import numpy as np

from agents.runtime.base import Agent
from agents.runtime.drawing.bodies import log_people
from agents.world.dsr_readers import running_activities
from agents.world.dsr_writers import write_interactions, write_person
from agents.world.freshness import mark_observed
from agents.world.interactions import interaction_pairs, scene_conversations
from agents.world.motion import PersonState, people_at
from agents.world.vocabulary import WORLD
from agents.world.vocabulary import now_s as now_of
from scenes.geometry import angle_difference
from agents.runtime.recording import Recorder

PUBLISH_MOVE_M = 0.03
PUBLISH_TURN_RAD = 0.05


class HumanObserverAgent(Agent):
    kind = "human_observer"

    def setup(self, graph, recorder: Recorder) -> None:  # noqa: ANN001
        self.graph = graph
        self.rec = recorder
        self.noise_xy = float(self.config.option("noise_xy", "0.02"))
        self.noise_theta = float(self.config.option("noise_theta", "0.03"))
        self.smoothing = float(self.config.option("smoothing", "0.5"))
        self.seed = int(self.config.option("seed", "7"))
        self.tracks: dict[str, tuple[float, float, float]] = {}
        self.published: dict[str, tuple[float, float, float]] = {}
        self._last_t: float | None = None

    def step(self) -> None:
        now_s = now_of(self.graph)
        if now_s is None or self.graph.get_node_by_name(WORLD) is None or now_s == self._last_t:
            return
        self._last_t = now_s
        self.rec.set_time(now_s)
        for truth in people_at(self.scene, now_s):
            rng = self._noise(truth, now_s)
            det = (truth.x + rng.normal(0, self.noise_xy), truth.y + rng.normal(0, self.noise_xy),
                   truth.theta + rng.normal(0, self.noise_theta))
            prev = self.tracks.get(truth.name)
            if prev is None or truth.moving or math.hypot(det[0] - prev[0], det[1] - prev[1]) > 0.5:
                track = det  # new, walking or re-acquired: no smoothing lag
            else:
                a = self.smoothing
                track = (prev[0] + a * (det[0] - prev[0]), prev[1] + a * (det[1] - prev[1]),
                         prev[2] + a * angle_difference(det[2], prev[2]))
            self.tracks[truth.name] = track
            self._publish(truth.name, truth.role, track, now_s)
        positions = {name: (x, y) for name, (x, y, _) in self.tracks.items()}
        write_interactions(self.graph, interaction_pairs(positions, running_activities(self.graph),
                                                         scene_conversations(self.scene)))
        mark_observed(self.graph, self.config.name, now_s)
        log_people(self.rec, self.tracks)

    def _noise(self, truth: PersonState, now_s: float) -> np.random.Generator:
        """The sensor noise of one detection, drawn from (seed, person, what is seen), not from one
        stream: this loop is not in lockstep with the clock, so how many clock values it sees differs
        from run to run, and a stream would give another world each time (chronav evaluate's seeds).
        A still person keeps one error while still (keyed by their pose: a biased detector); a
        walking one gets fresh noise every 0.1 s of sim time."""
        key = f"t{round(now_s * 10)}" if truth.moving else f"p{truth.x:.3f},{truth.y:.3f},{truth.theta:.3f}"
        return np.random.default_rng([self.seed, zlib.crc32(f"{truth.name}|{key}".encode())])

    def _publish(self, name: str, role: str, pose: tuple[float, float, float], now_s: float) -> None:
        """Write a person when new, or moved or turned enough: sensor jitter is not news."""
        old = self.published.get(name)
        if self.graph.get_node_by_name(name) is not None and old is not None \
                and math.hypot(pose[0] - old[0], pose[1] - old[1]) < PUBLISH_MOVE_M \
                and abs(angle_difference(pose[2], old[2])) < PUBLISH_TURN_RAD:
            return
        write_person(self.graph, name, role, pose, self.scene.room_at(pose[0], pose[1]), now_s)
        self.published[name] = pose
