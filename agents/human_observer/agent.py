"""The human observer agent: perceives people, tracks them, writes them into the DSR.

Why noise and a tracker in a simulator: the social map must be robust to jittery detections and
needs each walking person's velocity, which a real detector does not give; an observer that
republished every sensor jitter would also flood the graph and make the navigation replan for
nothing.  The simulator publishes the people as they truly are (``ground_truth/people``, one delta
with the clock); this agent detects them with position and heading noise, tracks them
(agents/lib/perception/tracking.py, ``observer_tracker``: identities kept by the tracks, velocities
from a line fitted to each track's latest detections), and publishes a person when they moved,
turned or changed speed enough.  With zero noise it is a perfect sensor: it reports the truth,
velocity included, which is what the offline commands assume (agents/world/offline.py).
"""

from __future__ import annotations

import math
import zlib
from pathlib import Path

import numpy as np
import shapely

from agents.lib.perception import prediction_log, walker_model
from agents.lib.perception.tracking import LOST_S, OBSERVER_NOISE_M, Detection, observer_tracker
from agents.runtime.base import Agent
from agents.runtime.checked_graph import CheckedGraph
from agents.runtime.drawing.bodies import log_people
from agents.runtime.recording import FramePacer, Recorder
from agents.lib.socialmap.motion import MotionParams, predict_many
from agents.world.dsr_readers import dsr_people, running_activities
from agents.world.dsr_writers import remove_person, write_interactions, write_person
from agents.world.freshness import mark_observed, observed_up_to
from agents.world.interactions import interaction_pairs, observed_conversations, scene_conversations
from agents.world.vocabulary import CLOCK, GROUND_TRUTH_PEOPLE, WORLD, ClockMode
from scenes.geometry import angle_difference

TRAIL_S = 20.0               # the recording shows each person's last 20 s of track (a crowd stays legible)
TRAIL_SPACING_S = 0.5
DRAW_EVERY_S = 0.5
PUBLISH_MOVE_M = 0.03
PUBLISH_TURN_RAD = 0.05
PUBLISH_SPEED_MPS = 0.1
PUBLISH_BATCH = 200         # people per delta (a delta stays far below max_delta_bytes: ~1 kB a person)
TRUTH_STILL_MPS = 1e-6       # a person whose true velocity is zero is standing still


class HumanObserverAgent(Agent):
    kind = "human_observer"

    def setup(self, graph: CheckedGraph, recorder: Recorder) -> None:
        self.graph = graph
        self.rec = recorder
        self.noise_xy = float(self.config.option("noise_xy", str(OBSERVER_NOISE_M)))
        self.noise_theta = float(self.config.option("noise_theta", "0.03"))
        self.seed = int(self.config.option("seed", "7"))
        self.lockstep = self.config.option("perception_lockstep", "0") == "1"
        self.perfect = self.noise_xy == 0.0 and self.noise_theta == 0.0
        model_path = self.config.option("walker_model", "")   # chronav launch/evaluate --model FILE
        self.tracker = observer_tracker(self.noise_xy, walker_model.load(Path(model_path)) if model_path else None)
        if model_path:
            self.log.info("walker model %s (%s)", model_path,
                          "applies" if self.tracker.model is not None else
                          f"not used: trained for another detector noise than {self.noise_xy:g} m")
        self.roles: dict[str, str] = {}
        self.published: dict[str, tuple[float, float, float, float, float]] = {}
        self._last_t: float | None = None
        self.trails: dict[str, list[tuple[float, float, float]]] = {}
        self._frames = FramePacer(DRAW_EVERY_S)
        walls = [shapely.LineString(w) for w in self.scene.walls if len(w) >= 2]
        self._walls = shapely.union_all(walls) if walls else None
        self._motion = MotionParams()
        self._predicted_slot = -1
        self._predictions = self._open_predictions()

    def _open_predictions(self):
        """The live prediction log (agents/lib/perception/prediction_log.py) in the run's directory,
        appended (a restarted observer continues it)."""
        if self.config.run_dir is None:
            return None
        return (self.config.run_dir / prediction_log.PREDICTIONS_FILE).open("a", encoding="utf-8", buffering=1 << 16)

    def teardown(self) -> None:
        if self._predictions is not None:
            self._predictions.close()
            self._predictions = None

    def _log_predictions(self, now_s: float) -> None:
        """Every EVERY_S of sim time while the robot drives (when the simulator writes people.csv, the
        truth they are scored against), what the social map predicts for each walker, from what this
        agent published (read back as the navigation reads it: walls, agenda and all)."""
        slot = math.floor(now_s / prediction_log.EVERY_S + 1e-6)
        if self._predictions is None or slot == self._predicted_slot:
            return
        clock = self.graph.get_node_by_name(CLOCK)
        if clock is None or clock.attrs.get("mode") != ClockMode.DRIVING:
            return
        self._predicted_slot = slot
        people = dsr_people(self.graph)
        lines = [prediction_log.record(now_s, p.name, p.x, p.y, found.times.tolist(), found.points.tolist())
                 for p, found in zip(people, predict_many(people, self._motion, self._walls), strict=True)
                 if found is not None and len(found.times)]
        self._predictions.writelines(lines)

    def _truth(self) -> tuple[float, list[tuple[str, str, float, float, float, float, float]]] | None:
        node = self.graph.get_node_by_name(GROUND_TRUTH_PEOPLE)
        if node is None:
            return None
        a = node.attrs
        try:
            rows = list(zip(a["names"], a["roles"], a["x"], a["y"], a["theta"], a["vx"], a["vy"], strict=True))
            return float(a["stamp"]), rows
        except (KeyError, TypeError, ValueError):
            return None   # a half-written or foreign node: wait for the next one

    def step(self) -> None:
        truth = self._truth()
        if truth is None or self.graph.get_node_by_name(WORLD) is None:
            return
        now_s, rows = truth
        if now_s == self._last_t:
            return
        if self.lockstep and not observed_up_to(self.graph, now_s, ("agenda",), slack_s=0.0):
            return   # in lockstep: the conversations and participants below read the agenda of this tick
        self._last_t = now_s
        self.rec.set_time(now_s)
        estimates: dict[str, tuple[float, float, float, float, float]] = {}
        if self.perfect:
            for name, role, x, y, theta, vx, vy in rows:
                self.roles[name] = role
                estimates[name] = (x, y, theta, vx, vy)
        else:
            detections = []
            for name, role, x, y, theta, vx, vy in rows:
                self.roles[name] = role
                rng = self._noise(name, now_s, (x, y, theta) if math.hypot(vx, vy) < TRUTH_STILL_MPS else None)
                detections.append(Detection(name, x + rng.normal(0, self.noise_xy), y + rng.normal(0, self.noise_xy),
                                            theta + rng.normal(0, self.noise_theta)))
            tracks = self.tracker.update(now_s, detections)
            for name in [n for n, track in tracks.items() if now_s - track.updated_s > LOST_S]:
                del tracks[name]          # not detected for LOST_S: they left (a replayed record ended)
            for name in tracks:
                estimates[name] = self.tracker.estimate(name, now_s)
        # One delta per tick (per PUBLISH_BATCH people), not one per person: with a crowd of 40 the
        # per-delta work (commit, encode, merge on every replica) was most of the observer's time.
        with self.graph.transaction():
            for name in [n for n in self.published if n not in estimates]:
                remove_person(self.graph, name)     # left the scene: the social map forgets them too
                del self.published[name]
                self.trails.pop(name, None)
        items = list(estimates.items())
        rooms = self.scene.rooms_at([e[0] for e in estimates.values()], [e[1] for e in estimates.values()])
        for start in range(0, len(items), PUBLISH_BATCH):
            with self.graph.transaction():
                for (name, estimate), room in zip(items[start:start + PUBLISH_BATCH], rooms[start:start + PUBLISH_BATCH],
                                                  strict=True):
                    self._publish(name, self.roles.get(name, "resident"), estimate, now_s, room)
        positions = {name: (e[0], e[1]) for name, e in estimates.items()}
        seen = {name: (e[0], e[1], e[2], math.hypot(e[3], e[4])) for name, e in estimates.items()}
        write_interactions(self.graph, interaction_pairs(positions, running_activities(self.graph),
                                                         [*scene_conversations(self.scene),
                                                          *observed_conversations(seen)]))
        mark_observed(self.graph, self.config.name, now_s)
        self._log_predictions(now_s)
        self._draw(now_s, estimates)

    def _draw(self, now_s: float, estimates: dict[str, tuple[float, float, float, float, float]]) -> None:
        """Tracks, velocities and the social map's predictions of the walkers (from what this agent
        published, read back as the navigation reads it), every DRAW_EVERY_S of sim time."""
        if not self.rec.enabled or not self._frames.due(now_s):
            return
        for name, (x, y, *_rest) in estimates.items():
            trail = self.trails.setdefault(name, [])
            if not trail or now_s - trail[-1][0] >= TRAIL_SPACING_S or now_s < trail[-1][0]:
                trail.append((now_s, x, y))
            while trail and (trail[0][0] < now_s - TRAIL_S or trail[0][0] > now_s):
                trail.pop(0)
        predictions = [found for found in predict_many(dsr_people(self.graph), self._motion, self._walls)
                       if found is not None]
        log_people(self.rec, {name: e[:3] for name, e in estimates.items()},
                   {name: e[3:] for name, e in estimates.items()},
                   {name: [(x, y) for _, x, y in trail] for name, trail in self.trails.items()}, predictions)

    def _noise(self, name: str, now_s: float, still_pose: tuple[float, float, float] | None) -> np.random.Generator:
        """The sensor noise of one detection, drawn from (seed, person, what is seen), not from one
        stream: this loop is not in lockstep with the clock, so how many clock values it sees differs
        from run to run, and a stream would give another world each time (chronav evaluate's seeds).
        A still person keeps one error while still (keyed by their pose: a biased detector), so the
        track settles on one estimate however many frames were seen; a walking one gets fresh noise
        every 0.1 s of sim time."""
        key = f"t{round(now_s * 10)}" if still_pose is None else "p{:.3f},{:.3f},{:.3f}".format(*still_pose)
        return np.random.default_rng([self.seed, zlib.crc32(f"{name}|{key}".encode())])

    def _publish(self, name: str, role: str, estimate: tuple[float, float, float, float, float], now_s: float,
                 room: str | None) -> None:
        """Write a person (in ``room``, the scene's room at their estimate) when new, or moved, turned
        or changed speed enough: sensor jitter is not news."""
        x, y, theta, vx, vy = estimate
        old = self.published.get(name)
        if self.perfect and old == estimate and self.graph.node_id_of(name) is not None:
            return   # a perfect sensor reports every change, however small (what offline assumes)
        if not self.perfect and self.graph.node_id_of(name) is not None and old is not None \
                and math.hypot(x - old[0], y - old[1]) < PUBLISH_MOVE_M \
                and abs(angle_difference(theta, old[2])) < PUBLISH_TURN_RAD \
                and math.hypot(vx - old[3], vy - old[4]) < PUBLISH_SPEED_MPS:
            return
        write_person(self.graph, name, role, (x, y, theta), room, now_s, (vx, vy))
        self.published[name] = estimate
