"""The simulated people (agents/lib/crowd, agents/world/people.py): routes, the agenda, routines,
motion, determinism.  One day of tests/data/crowd_small.yaml is simulated once (module fixture) and
examined step by step."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import shapely

from agents.lib.crowd.crowd import ARRIVE_EARLY_S, Crowd
from agents.lib.crowd.model import RobotBody
from agents.lib.crowd.routes import NoRoute, Router
from agents.world.interactions import observed_conversations
from agents.world.crowd_scene import building_of, walker_of
from agents.world.people import WorldFeed, new_crowd, people_at, resting_robot
from agents.world.scene_world import load_world
from scenes.clock import parse_clock
from scenes.loader import load_scene

SCENE = Path(__file__).resolve().parents[1] / "data" / "crowd_small.yaml"
WALL_CLEARANCE_M = 0.2      # a body's centre never closer to a wall than this (radius 0.25 less ORCA's slack)


@pytest.fixture(scope="module")
def world():
    return load_world(SCENE)


@pytest.fixture(scope="module")
def day(world):
    """Every person every step from 09:00 to 10:20: {name: [(t, truth)]}."""
    crowd, feed = new_crowd(world), WorldFeed(world)
    t, end = world.scene.clock.start_s, parse_clock("10:20")
    samples: dict[str, list] = {}
    while t < end:
        t += crowd.step_s
        crowd.advance(t, feed)
        for p in crowd.at(t):
            samples.setdefault(p.name, []).append((t, p))
    return samples


def test_routes_pass_doors_in_the_middle_and_go_round_furniture(world) -> None:
    building = building_of(world.scene)
    walls = list(building.walls)
    footprints = [t.footprint for t in building.things.values()]
    union = shapely.union_all(list(building.rooms.values()))
    router = Router.build(union, walls, footprints)
    waypoints, length = router.route((3.0, 5.0), (15.0, 5.0))     # activity room -> lounge
    path = shapely.LineString([(3.0, 5.0), *waypoints])
    for door_x in (3.0, 15.0):
        crossing = path.intersection(shapely.LineString([(door_x - 0.6, 2.4), (door_x + 0.6, 2.4)]))
        assert not crossing.is_empty and abs(crossing.centroid.x - door_x) <= 0.15, "doors are passed in the middle"
    assert length == pytest.approx(path.length)
    # behind the table: the route goes round its footprint, keeping a body's clearance
    waypoints, _ = router.route((9.0, 4.3), (9.0, 7.7))
    around = shapely.LineString([(9.0, 4.3), *waypoints])
    assert around.distance(building.things["table"].footprint) >= 0.39
    closed = Router.build(union, walls + [building.door_leaves["door_lounge"]], footprints)
    with pytest.raises(NoRoute):
        closed.route((3.0, 5.0), (15.0, 5.0))


def test_participants_arrive_before_the_start_take_places_facing_the_object_and_leave_at_the_end(world, day) -> None:
    agenda = {a.id: a for a in world.agenda.activities}
    for activity_id, names in (("game", ("ana", "dora")), ("therapy", ("ben", "eva"))):
        a = agenda[activity_id]
        obj = next(o for o in world.scene.objects if o.name == a.object)
        for name in names:
            there = [(t, p) for t, p in day[name] if p.group == f"activity/{activity_id}"]
            assert there, f"{name} never stood at {activity_id}"
            arrived = there[0][0]
            assert a.start_s - 300.0 <= arrived <= a.start_s, f"{name} arrived {a.start_s - arrived:.0f} s before"
            assert there[-1][0] == pytest.approx(a.end_s, abs=0.3), f"{name} left {there[-1][0] - a.end_s:.0f} s off"
            _, p = there[len(there) // 2]
            bearing = math.atan2(obj.pose.y - p.y, obj.pose.x - p.x)
            assert abs((p.theta - bearing + math.pi) % (2 * math.pi) - math.pi) < math.radians(60), "faces the object"
            assert math.hypot(p.x - obj.pose.x, p.y - obj.pose.y) < 1.8, "within the interaction range"
    assert ARRIVE_EARLY_S < 300.0


def test_the_staff_fetches_the_escorted_resident(day) -> None:
    ben = dict(day["ben"])
    marta = dict(day["marta"])
    leaving = next(t for t, p in day["ben"] if p.goal == "therapy" and p.moving)
    pos = ben[leaving]
    assert math.hypot(marta[leaving].x - pos.x, marta[leaving].y - pos.y) < 1.5, "the nurse is beside him"
    walking = [t for t, p in day["ben"] if p.goal == "therapy" and p.moving]
    beside = [math.hypot(marta[t].x - ben[t].x, marta[t].y - ben[t].y) for t in walking]
    assert np.median(beside) < 1.6, "she walks with him"


def test_speeds_are_realistic_and_nobody_overlaps_or_enters_a_wall(world, day) -> None:
    walls = shapely.MultiLineString([w for w in world.scene.walls])
    names = sorted(day)
    for name in names:
        speeds = [math.hypot(p.vx, p.vy) for _, p in day[name]]
        moving = [v for v in speeds if v > 0.1]
        limit = 0.5 if name == "ben" else 1.4
        assert max(speeds) <= limit + 1e-3, f"{name} walks at {max(speeds):.2f} m/s"
        if name in ("ana", "dora", "carla", "marta", "eva", "luis"):
            assert moving and np.percentile(moving, 90) >= 0.5, f"{name} walks at realistic speeds"
        xy = np.array([[p.x, p.y] for _, p in day[name]])
        assert shapely.distance(walls, shapely.points(xy)).min() >= WALL_CLEARANCE_M, f"{name} touches a wall"
    positions = np.array([[[p.x, p.y] for _, p in day[name]] for name in names])   # (people, steps, 2)
    gaps = np.hypot(*(positions[:, None] - positions[None, :]).transpose(3, 0, 1, 2))
    gaps[np.arange(len(names)), np.arange(len(names))] = np.inf
    assert gaps.min() >= 0.45, "bodies (0.25 m) never overlap by more than ORCA's few centimetres"


def test_residents_wander_and_chat_in_pairs_facing_each_other(day) -> None:
    rooms_visited = {name: set() for name in ("ana", "carla", "dora")}
    scene = load_scene(SCENE).scene
    for name in rooms_visited:
        for _, p in day[name]:
            rooms_visited[name].add(scene.room_at(p.x, p.y))
    assert sum(len(r - {"corridor"}) >= 2 for r in rooms_visited.values()) >= 2, rooms_visited
    chats = {p.group for people in day.values() for _, p in people if p.group.startswith("chat/")}
    assert chats, "people chat"
    steps = len(day["ana"])
    seen = 0
    for k in range(0, steps, 20):
        members: dict[str, list] = {}
        for samples in day.values():
            _, p = samples[k]
            if p.group.startswith("chat/"):
                members.setdefault(p.group, []).append(p)
        for group in members.values():
            if len(group) >= 2:
                seen += 1
                observed = observed_conversations({p.name: (p.x, p.y, p.theta, 0.0) for p in group})
                assert observed, "the observer's rule sees the conversation"
    assert seen > 0


def test_one_seed_gives_one_day_whatever_the_slicing_and_offline_going_back(world) -> None:
    times = [parse_clock(t) for t in ("09:41:10", "09:27:30", "10:05:00")]
    offline = {t: people_at(world, t) for t in times}          # out of order: restarts from a snapshot
    live, feed, robot = new_crowd(world), WorldFeed(world), resting_robot(world)   # the robot never drives
    for t in sorted(times):
        while live.t_s < t - 0.1:
            live.advance(min(t, live.t_s + 0.1), feed, robot)   # the simulator's 0.1 s control steps
        live.advance(t, feed, robot)
        assert live.at(t) == offline[t]
    scene = world.scene
    crowd = Crowd(building_of(scene), [walker_of(scene, p) for p in scene.people], seed=99,
                  start_s=scene.clock.start_s)
    crowd.advance(times[0], WorldFeed(world))
    assert crowd.at(times[0]) != offline[times[0]], "another seed, another day"


def test_an_agenda_change_changes_where_people_go_at_once(world) -> None:
    crowd = new_crowd(world)
    at = parse_clock("09:50")
    crowd.advance(at, WorldFeed(world))
    assert {p.name: p.group for p in crowd.at(at)}["ana"] == "activity/game"
    cancelled = WorldFeed(world, ('{"op": "cancel", "id": "game"}',))
    crowd.advance(at + 1.0, cancelled)
    assert {p.name: p.goal for p in crowd.at(at + 1.0)}["ana"] == "", "she leaves the cancelled game at once"
    added = WorldFeed(world, ('{"op": "cancel", "id": "game"}',
                              '{"op": "add", "activity": {"id": "tea", "name": "Tea", "object": "sofa", '
                              '"start": "09:53", "end": "10:30", "participants": ["ana"]}}'))
    crowd.advance(at + 2.0, added)
    assert {p.name: p.goal for p in crowd.at(at + 2.0)}["ana"] == "tea"
    crowd.advance(parse_clock("09:53"), added)
    assert {p.name: p.group for p in crowd.at(parse_clock("09:53"))}["ana"] == "activity/tea"


def test_people_avoid_the_robot_only_while_it_drives(world) -> None:
    """A robot halted on the corridor's walking line (its route corners at y = 1.9): people walking
    by give it room while it drives, and walk their usual line through where it stands when it does
    not (at rest nobody reacts to it, which keeps the offline world equal to the live one)."""
    start, end = parse_clock("09:30"), parse_clock("09:42")
    robot = RobotBody(12.0, 1.9, 0.0, 0.0, 0.3)
    feed = WorldFeed(world)
    base = new_crowd(world)
    base.advance(start, feed)
    closest = {}
    for driving in (True, False):
        crowd = base.clone()
        nearest = math.inf
        t = start
        while t < end:
            t += crowd.step_s
            crowd.advance(t, feed, robot if driving else None)
            nearest = min(nearest, min(math.hypot(p.x - robot.x, p.y - robot.y) for p in crowd.at(t)))
        closest[driving] = nearest
    assert closest[False] < 0.45, "without a driving robot someone walks the line through its place"
    assert closest[True] >= 0.3 + 0.25 - 0.05, "while it drives, people keep clear of its body"


@pytest.mark.parametrize("reacts", [True, False])
def test_nobody_walks_into_or_stands_at_the_resting_robot(reacts: bool) -> None:
    """Regression (bench_day, center_day): the robot rested in the dining room after a mission and
    a resident chose a place 0.37 m from its centre; the next mission began in contact with her.
    At rest the robot is an obstacle people walk round and a place nobody picks to stand."""
    world = load_world("center_day")
    robot = RobotBody(16.48, 4.81, 0.0, 0.0, world.scene.robot.radius)
    crowd, feed = new_crowd(world), WorldFeed(world)
    start = parse_clock("09:46")
    crowd.advance(start, feed, None)     # the morning before it parked there: no robot for anyone
    gaps = []
    for t in np.arange(start + 5.0, parse_clock("11:15"), 5.0):
        crowd.advance(float(t), feed, robot if reacts else None)
        gaps += [math.hypot(p.x - robot.x, p.y - robot.y) - robot.radius for p in crowd.at(float(t))]
    if reacts:
        assert min(gaps) > 0.3, "people keep clear of the resting robot's body"
    else:
        assert min(gaps) < 0.3, "without the robot in their world someone stands where it rests"


def test_an_activity_place_the_robot_parks_on_is_drawn_again_clear_of_it(world) -> None:
    """Issue 27: the robot came to rest by the table after its mission, on the place the therapy's
    formation had given eva; she walked there anyway and stood 0.65 m from the robot's centre, inside
    its intimate distance, while the idle clock skipped on.  Now the formation is drawn again clear
    of the resting robot: the attendees stand at least Hall's 0.45 m from its body."""
    crowd, feed = new_crowd(world), WorldFeed(world)
    during = parse_clock("09:50")
    crowd.advance(during, feed)                           # the agenda read, places given, no robot
    eva = next(p for p in crowd.at(during) if p.name == "eva")
    assert eva.group == "activity/therapy"
    robot = RobotBody(eva.x + 0.6, eva.y, 0.0, 0.0, world.scene.robot.radius)   # parks beside her place
    crowd, feed = new_crowd(world), WorldFeed(world)
    crowd.advance(parse_clock("09:20"), feed)             # before the attendees leave for the table
    for t in np.arange(parse_clock("09:20") + 5.0, parse_clock("10:05"), 5.0):
        crowd.advance(float(t), feed, robot)
    attendees = [p for p in crowd.at(parse_clock("10:05") - 5.0) if p.group == "activity/therapy"]
    assert attendees, "the therapy still takes place"
    for p in attendees:
        gap = math.hypot(p.x - robot.x, p.y - robot.y) - robot.radius - 0.25
        assert gap >= 0.45 - 0.05, f"{p.name} stands {gap:.2f} m from the robot's body"
