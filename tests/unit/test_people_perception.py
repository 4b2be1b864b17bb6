"""Perceiving and predicting moving people: the tracker (identities, velocities), the observer agent
on the simulator's truth, the social map's stretch along the velocity and its predictions."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from agents.lib.perception.tracking import Detection, Tracker
from agents.lib.socialmap.grid import walls_geometry
from agents.lib.socialmap.motion import MotionParams, predict
from agents.lib.socialmap.social_map import build_social_map
from agents.lib.socialmap.types import Person, Wall
from agents.world.dsr_readers import dsr_people
from scenes.clock import parse_clock
from tools.offline_agents import OfflineAgents

SCENE = Path(__file__).resolve().parents[1] / "data" / "crowd_small.yaml"
BOUNDS = (0.0, 0.0, 12.0, 6.0)
WALLS = [Wall(((0.0, 0.0), (12.0, 0.0), (12.0, 6.0), (0.0, 6.0), (0.0, 0.0)))]


def test_tracks_keep_identities_when_two_people_cross_and_estimate_velocity() -> None:
    """Two people walk at 1 m/s toward each other along y = 0 and y = 0.4 and pass; detections at
    10 Hz with 5 cm noise are handed over in a shuffled order each time and both labelled with the
    *other* name once they have crossed (a confused detector): the tracks follow the motion and
    keep their names; the velocity estimates settle within 0.15 m/s of the truth."""
    rng = np.random.default_rng(1)
    tracker = Tracker(measurement_sigma=0.05)
    for k in range(60):
        t = k * 0.1
        a = (-3.0 + t, 0.0)
        b = (3.0 - t, 0.4)
        crossed = a[0] > b[0]
        detections = [Detection("bob" if crossed else "ann", a[0] + rng.normal(0, 0.05), a[1] + rng.normal(0, 0.05), 0.0),
                      Detection("ann" if crossed else "bob", b[0] + rng.normal(0, 0.05), b[1] + rng.normal(0, 0.05),
                                math.pi)]
        rng.shuffle(detections)
        tracks = tracker.update(t, detections)
    assert tracks["ann"].xy[0] > 1.5 and tracks["bob"].xy[0] < -1.5, "each track follows its own walker"
    assert tracker.velocity("ann", t) == pytest.approx((1.0, 0.0), abs=0.15)
    assert tracker.velocity("bob", t) == pytest.approx((-1.0, 0.0), abs=0.15)


def test_the_observer_tracks_the_simulators_people_with_noise_and_velocities(tmp_path: Path) -> None:
    """The simulator publishes the truth (ground_truth/people); the observer writes every person
    with a noisy pose and an estimated velocity close to the walkers' true one."""
    centre = OfflineAgents(SCENE, tmp_path, agents=("sim_robot", "human_observer"),
                           options={"human_observer": {"noise_xy": "0.03"}})
    graph, sim, observer = centre.graph, centre.sim, centre["human_observer"]
    t = parse_clock("09:26:00")
    errors, speeds = [], []
    while t < parse_clock("09:27:30"):
        t += 0.1
        sim.skip_to(t)
        observer.step()
        truth = {p.name: p for p in sim._people}
        for person in dsr_people(graph):
            real = truth[person.name]
            errors.append(math.hypot(person.x - real.x, person.y - real.y))
            if math.hypot(real.vx, real.vy) > 0.5 and t > parse_clock("09:26:05"):
                speeds.append(math.hypot(person.vx - real.vx, person.vy - real.vy))
    assert {p.name for p in dsr_people(graph)} == {p.name for p in sim.scene.people}
    assert 0.0 < np.median(errors) < 0.1, "noisy, but close"
    assert speeds, "someone walked"
    assert np.median(speeds) < 0.25, "velocities estimated from noisy positions"


def test_a_walkers_space_stretches_ahead_along_the_velocity() -> None:
    """Kirby: front sigma = max(2 v, rest) with v the speed; the sides do not grow.  A walker at
    1.2 m/s facing sideways is costed along where they walk: far ahead of them, not to their side."""
    still = Person("p", 4.0, 3.0, math.pi / 2)
    walker = Person("p", 4.0, 3.0, math.pi / 2, vx=1.2, vy=0.0)
    standing = build_social_map(BOUNDS, WALLS, [still], [], [], 0.0)
    walking = build_social_map(BOUNDS, WALLS, [walker], [], [], 0.0)
    front = walking.person_spaces[0].space
    assert front.front_m == pytest.approx(2.0 * 1.2)
    assert front.left_m == pytest.approx(standing.person_spaces[0].space.left_m)
    ahead = (6.0, 3.0)        # 2 m ahead of the walker
    assert standing.zone_at(*ahead) == "public" and walking.zone_at(*ahead) in ("personal", "social")
    assert walking.density_at(4.0, 4.0) < standing.density_at(4.0, 4.0), "their side counts less than their face"


def test_predictions_follow_the_velocity_or_the_activity_and_never_forbid() -> None:
    params = MotionParams()
    walker = Person("p", 2.0, 3.0, 0.0, vx=1.0, vy=0.0)
    found = predict(walker, params, None)
    assert found is not None
    assert found.points[:, 0] == pytest.approx(2.0 + found.times)
    assert np.all(np.diff(found.weights) < 0) and found.weights.max() < 0.8
    going = Person("p", 2.0, 3.0, 0.0, vx=0.6, vy=0.8, destination=(2.0, 5.5 + 1.8))   # 37 degrees off it
    toward = predict(going, params, None)
    assert np.all(toward.points[:, 0] == pytest.approx(2.0)) and toward.points[-1, 1] > 3.5, "toward the activity"
    near_wall = predict(Person("p", 11.0, 3.0, 0.0, vx=1.0, vy=0.0), params, None)
    assert near_wall is not None and near_wall.points[:, 0].max() > 12.0
    clipped = predict(Person("p", 11.0, 3.0, 0.0, vx=1.0, vy=0.0), params, walls_geometry(WALLS))
    assert clipped is None or clipped.points[:, 0].max() < 12.0, "no prediction through a wall"
    smap = build_social_map(BOUNDS, WALLS, [walker], [], [], 0.0)
    assert smap.predictions and smap.prediction_patches
    ahead = smap.predictions[0]
    far = ahead.points[int(np.flatnonzero(ahead.weights > smap.params.zones.social)[-1])]   # the farthest that counts
    r, c = smap.spec.cell_of(*far)
    assert 1.0 < smap.people_cost[r, c] < math.inf, "a predicted place costs, but is never forbidden"
    alone = build_social_map(BOUNDS, WALLS, [walker], [], [], 0.0)
    assert not any(np.isinf(p.values).any() for p in alone.prediction_patches), "predictions never forbid"
