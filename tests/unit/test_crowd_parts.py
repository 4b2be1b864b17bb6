"""The pieces the crowd composes (agents/lib/crowd: motion, schedule, routines, escorts), each
through its public API on a two-room building built here (no scene, no agenda file).

Why beside test_crowd.py: that file checks a whole day's behaviour; these pin what each piece
promises, so a change inside one of them shows which promise it broke.
"""

from __future__ import annotations

import math

import pytest
import shapely

from agents.lib.crowd.escorts import BESIDE_M, Escorts
from agents.lib.crowd.model import Agenda, Appointment, Building, RobotBody, Thing, Walker
from agents.lib.crowd.motion import ROBOT_CLEARANCE_M, Motion
from agents.lib.crowd.person import Person, Task
from agents.lib.crowd.routines import PASSAGE_WIDTH_M, SPOT_DOOR_M, Routines
from agents.lib.crowd.schedule import ARRIVE_EARLY_S, ESCORT_WAIT_S, Schedule

STEP_S = 0.25
TABLE = Thing("table", 3.0, 3.0, 0.0, shapely.box(2.2, 2.6, 3.8, 3.4))
# west and east rooms (6 m x 6 m) joined by a 1.2 m door at (6, 3); a 2 m-wide hall north of them
BUILDING = Building(
    rooms={"west": shapely.box(0, 0, 6, 6), "east": shapely.box(6, 0, 12, 6), "hall": shapely.box(0, 6, 12, 8)},
    walls=[[(0, 0), (12, 0), (12, 8), (0, 8), (0, 0)], [(6, 0), (6, 2.4)], [(6, 3.6), (6, 6)],
           [(0, 6), (10, 6)]],
    things={"table": TABLE},
    door_leaves={"door": ((6.0, 2.4), (6.0, 3.6))},
    doors={"door": (6.0, 3.0)})
WALKERS = [Walker("ann", "resident", "wander", (1.0, 1.0, 0.0)),
           Walker("bob", "resident", "wander", (10.0, 5.0, 0.0), escort=True),
           Walker("sue", "staff", "staff", (10.0, 1.0, 0.0), speed_mps=1.3, dwell_s=(30.0, 150.0))]
TALK = Appointment("talk", "table", 1000.0, 2000.0, ("ann", "bob"))


def parts(seed: int = 1) -> tuple[dict[str, Person], Motion, Schedule, Routines, Escorts]:
    """The pieces wired as crowd.Crowd wires them."""
    people = {w.name: Person(w, i, Task("stand", "dwell", w.pose)) for i, w in enumerate(WALKERS)}
    motion = Motion(BUILDING, WALKERS, people, step_s=STEP_S, robot_radius_m=0.3, start_s=0.0)
    schedule = Schedule(BUILDING, people, motion)
    routines = Routines(seed, people, motion, schedule)
    escorts = Escorts(BUILDING, people, motion, schedule, routines)
    motion.pick_up, motion.rejoin = escorts.pick_up, routines.rejoin
    return people, motion, schedule, routines, escorts


def walk_until_standing(motion: Motion, person: Person, t: float, steps: int = 400) -> float:
    """Step ``person`` alone until they stand; the time they stood."""
    for _ in range(steps):
        motion.walking(person, t)
        if person.task.kind == "stand":
            return t
        motion.step(t, t + STEP_S, [person], [], [], [], [], None)
        t += STEP_S
    raise AssertionError(f"{person.spec.name} still walks at {t} s")


def test_motion_walks_through_the_door_and_stands_at_the_target() -> None:
    people, motion, *_ = parts()
    ann = people["ann"]
    motion.walk(ann, 0.0, (9.0, 4.0, math.pi / 2), "dwell")
    crossing = shapely.LineString([(1.0, 1.0), *ann.task.route]).intersection(shapely.LineString([(6, 0), (6, 6)]))
    assert 2.4 + 0.25 < crossing.y < 3.6 - 0.25, "routed through the door gap, a body clear of the jambs"
    walk_until_standing(motion, ann, 0.0)
    assert tuple(motion.pos[ann.index]) == pytest.approx((9.0, 4.0), abs=0.05)
    assert ann.task.target[2] == pytest.approx(math.pi / 2)


def test_motion_a_closed_door_drops_the_route_and_the_room_is_out_of_reach() -> None:
    people, motion, *_ = parts()
    ann = people["ann"]
    motion.walk(ann, 0.0, (9.0, 4.0, 0.0), "dwell")
    motion.doors(frozenset({"door"}))
    assert ann.task.route == [], "replanned on this step"
    motion.route(ann)
    assert ann.task.route == [(9.0, 4.0)], "no route through a shut door: straight at the goal, settling when stuck"


def test_motion_nobody_fits_in_furniture_walls_or_at_the_resting_robot() -> None:
    _, motion, *_ = parts()
    assert motion.fits(1.0, 4.0)
    assert not motion.fits(3.0, 3.0), "inside the table"
    assert not motion.fits(6.1, 1.0), "against the partition"
    assert motion.park(RobotBody(1.0, 4.0, 0.0, 0.0, 0.3)) and not motion.park(RobotBody(1.0, 4.0, 0.0, 0.0, 0.3))
    assert not motion.fits(1.0, 4.0 + 0.3 + 0.1 + ROBOT_CLEARANCE_M - 0.05)
    assert motion.fits(1.0, 4.0 + 0.3 + 0.1 + ROBOT_CLEARANCE_M + 0.05)
    assert motion.park(None) and motion.fits(1.0, 4.0)
    assert motion.room_of(9.0, 4.0) == "east" and motion.room_of(20.0, 4.0) is None


def test_schedule_places_participants_around_the_object_and_calls_them_in_time() -> None:
    people, motion, schedule, *_ = parts()
    schedule.read(Agenda(1, (TALK,)))
    places = [schedule.place(TALK, name) for name in TALK.participants]
    assert len(set(places)) == 2 and all(motion.fits(x, y) for x, y, _ in places)
    for x, y, theta in places:      # around the table, facing it
        assert 0.2 < TABLE.footprint.distance(shapely.Point(x, y)) < 1.2
        assert abs(math.remainder(theta - math.atan2(3.0 - y, 3.0 - x), math.tau)) < 0.5
    ann = people["ann"]
    leave = schedule.departure_s(ann, TALK)
    assert leave < TALK.start_s - ARRIVE_EARLY_S
    assert schedule.due(ann, leave - 1.0) is None and schedule.due(ann, leave) == TALK
    assert schedule.next_due_s(ann, 0.0) == leave
    assert schedule.due(ann, TALK.end_s) is None, "over"


def test_schedule_an_escorted_resident_waits_for_the_staff_who_fetches_them() -> None:
    people, _, schedule, *_ = parts()
    schedule.read(Agenda(1, (TALK,)))
    bob, sue = people["bob"], people["sue"]
    assert schedule.jobs == {("talk", "bob"): "sue"}
    leave = schedule.departure_s(bob, TALK)
    assert schedule.due(bob, leave) is None and schedule.due(bob, leave + ESCORT_WAIT_S) == TALK
    assert schedule.fetch_s(sue, "talk", "bob") < leave
    assert schedule.next_due_s(sue, 0.0) == schedule.fetch_s(sue, "talk", "bob")


def test_schedule_redraws_a_formation_the_robot_came_to_rest_on() -> None:
    people, motion, schedule, *_ = parts()
    schedule.read(Agenda(1, (TALK,)))
    x, y, _ = schedule.place(TALK, "ann")
    people["ann"].task.activity = "talk"
    assert motion.park(RobotBody(x, y, 0.0, 0.0, 0.3))
    schedule.clear_places_of_robot()
    for px, py, _ in schedule.places["talk"]:
        assert math.hypot(px - x, py - y) >= 0.3 + 0.1 + ROBOT_CLEARANCE_M
    assert people["ann"].task.activity == "" and people["ann"].next_check_s == -math.inf, "she decides again"


def test_routines_pick_free_spots_in_rooms_one_stays_in_from_the_person_s_own_stream() -> None:
    people, motion, schedule, routines, _ = parts(seed=1)
    assert routines.rooms(people["ann"]) == ["east", "west"], f"the hall is narrower than {PASSAGE_WIDTH_M} m"
    schedule.read(Agenda(1, (TALK,)))
    for seed in range(20):
        x, y = routines.spot(people["ann"], "west", seed)
        assert motion.room_of(x, y) == "west" and motion.fits(x, y)
        assert math.hypot(x - 6.0, y - 3.0) >= SPOT_DOOR_M
    targets = []
    for seed in (1, 1, 2):
        people, _, _, routines, _ = parts(seed)
        routines.routine(people["ann"], 0.0)
        assert people["ann"].task.kind == "walk" and people["ann"].decisions == 1
        targets.append(people["ann"].task.target)
    assert targets[0] == targets[1] != targets[2], "one seed, one day; another seed, another"


def test_escorts_fetch_pick_up_and_walk_beside_the_resident() -> None:
    people, motion, schedule, routines, escorts = parts()
    schedule.read(Agenda(1, (TALK,)))
    bob, sue = people["bob"], people["sue"]
    x, y, theta = escorts.beside(sue, bob)
    assert math.hypot(x - 10.0, y - 5.0) == pytest.approx(BESIDE_M) and motion.fits(x, y)
    assert abs(math.remainder(theta - math.atan2(5.0 - y, 10.0 - x), math.tau)) < 1e-9, "facing him"
    fetch = schedule.fetch_s(sue, "talk", "bob")
    assert not escorts.start_job(sue, fetch - 1.0)
    assert escorts.start_job(sue, fetch) and sue.task.purpose == "fetch" and sue.task.other == "bob|talk"
    t = walk_until_standing(motion, sue, fetch) if sue.task.kind == "walk" else fetch
    assert ("talk", "bob") in schedule.jobs_done
    assert bob.task.purpose == "attend" and bob.task.kind == "walk" and bob.escorted_to == "talk"
    assert bob.task.target == schedule.place(TALK, "bob")
    assert sue.task.purpose == "escort" and sue.task.other == "bob" and t < TALK.start_s
