"""What a person does when no activity calls them: stay somewhere a while, or talk with someone.

Why apart from the schedule and the motion: the routine is each person's own random stream (seed,
name, decision number), so a person's day does not change when someone else is added; the
conversations it starts (pairs facing each other, a third joining the circle, given up or held
from where one is when the way is blocked) are state of their own (``chats``).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import shapely

from agents.lib.crowd.formations import CHAT_RADIUS_M, chat_place, join_circle
from agents.lib.crowd.motion import Motion
from agents.lib.crowd.person import AWAY, LEAVE, Person, Task, person_rng
from agents.lib.crowd.schedule import DETOUR, Schedule
from scenes.angles import wrap_angle

CHAT_CHANCE = {"wander": 0.35, "staff": 0.1, "visitor": 0.0}
HOME_CHANCE = 0.5
VISIT_DWELL_MAX_S = 60.0    # a visitor whose friend cannot talk waits near them this long at most
SPOT_TRIES = 40
SPOT_WALL_M = 0.5           # a chosen spot keeps this from walls
SPOT_FURNITURE_M = 0.6
SPOT_DOOR_M = 1.3           # ... and out of doorways
SPOT_PEOPLE_M = 1.0         # ... and from other people and where they are going
PASSAGE_WIDTH_M = 3.0       # a room narrower than this is a corridor: people pass, they do not stay
SETTLED_RAD = 0.3           # facing within this of where they should: settled in a formation


def corridor_width(polygon: shapely.Polygon) -> float:
    """The short side of a room's minimum rotated rectangle: a corridor's width."""
    box = shapely.minimum_rotated_rectangle(polygon)
    corners = np.asarray(box.exterior.coords)[:3]
    return float(min(np.hypot(*(corners[1] - corners[0])), np.hypot(*(corners[2] - corners[1]))))


class Routines:
    """The routine decisions and the conversations (``chats``: group id -> centre and members)."""

    def __init__(self, seed: int, people: dict[str, Person], motion: Motion, schedule: Schedule) -> None:
        self.seed = seed
        self.people = people
        self.motion = motion
        self.schedule = schedule
        self.stay_rooms = sorted(name for name, poly in motion.room_polys.items()
                                 if corridor_width(poly) >= PASSAGE_WIDTH_M)
        self.chats: dict[str, dict] = {}
        self._chat_counter = 0

    def routine(self, person: Person, t: float) -> None:
        """The next place to be, from the person's own random stream."""
        self.leave_chat(person)
        spec = person.spec
        motion = self.motion
        rng = person_rng(self.seed, spec.name, person.decisions)
        person.decisions += 1
        u = rng.random(8)
        dwell = spec.dwell_s[0] + (spec.dwell_s[1] - spec.dwell_s[0]) * u[5]
        if spec.routine == "visitor" and spec.visits in self.people \
                and self.people[spec.visits].task.purpose not in (AWAY, LEAVE):   # not while they are out
            friend = self.people[spec.visits]
            if self._chat_with(person, friend, t, dwell):
                return
            room = motion.room_of(*motion.pos[friend.index]) or spec.home
            self._dwell(person, t, room, u, min(dwell, VISIT_DWELL_MAX_S))
            return
        if u[0] < CHAT_CHANCE.get(spec.routine, 0.0):
            candidates = [p for name, p in sorted(self.people.items()) if p is not person and p.spec.dynamic
                          and p.task.kind == "stand" and p.task.purpose in ("dwell", "chat")
                          and motion.room_of(*motion.pos[p.index]) in self.rooms(person)]
            if candidates and self._chat_with(person, candidates[int(u[6] * len(candidates))], t, dwell):
                return
        rooms = self.rooms(person)
        room = spec.home if (spec.home in rooms and u[1] < HOME_CHANCE) else rooms[int(u[2] * len(rooms))]
        self._dwell(person, t, room, u, dwell)

    def rooms(self, person: Person) -> list[str]:
        """Where the routine goes: the person's ``rooms``, or every room a group can stand in
        (corridors, narrower than ``PASSAGE_WIDTH_M``, are for passing through)."""
        if person.spec.rooms:
            return list(person.spec.rooms)
        return self.stay_rooms or sorted(self.motion.room_polys)

    def _dwell(self, person: Person, t: float, room: str | None, u: np.ndarray, dwell: float) -> None:
        spot = self.spot(person, room, int(u[3] * 2**31))
        theta = -math.pi + 2 * math.pi * float(u[4])
        pos = self.motion.pos
        i = person.index
        travel = math.hypot(spot[0] - pos[i, 0], spot[1] - pos[i, 1]) * DETOUR / person.spec.speed_mps
        self.motion.walk(person, t, (spot[0], spot[1], theta), "dwell", until_s=t + travel + dwell)

    def spot(self, person: Person, room: str | None, seed: int) -> tuple[float, float]:
        """A free place in ``room``: off the walls, the furniture and the doorways, away from people
        and from where they are going, and off today's activity places."""
        motion = self.motion
        poly = motion.room_polys.get(room or "") or motion.building_poly
        xmin, ymin, xmax, ymax = poly.bounds
        rng = np.random.default_rng(seed)
        others = [motion.pos[p.index] for p in self.people.values() if p is not person] + \
                 [p.task.target[:2] for p in self.people.values() if p is not person]
        others_xy = np.asarray(others, dtype=float).reshape(-1, 2)
        place_points = self.schedule.place_points
        for _ in range(SPOT_TRIES):
            x, y = float(rng.uniform(xmin, xmax)), float(rng.uniform(ymin, ymax))
            if not shapely.contains_xy(poly, x, y):
                continue
            point = shapely.Point(x, y)
            if motion.wall_lines.distance(point) < SPOT_WALL_M or motion.footprints.distance(point) < SPOT_FURNITURE_M:
                continue
            if len(motion.door_xy) and np.min(np.hypot(*(motion.door_xy - (x, y)).T)) < SPOT_DOOR_M:
                continue
            if len(others_xy) and np.min(np.hypot(*(others_xy - (x, y)).T)) < SPOT_PEOPLE_M:
                continue
            if len(place_points) and np.min(np.hypot(*(place_points - (x, y)).T)) < SPOT_PEOPLE_M:
                continue
            if not motion.out_of_the_way(x, y):
                continue
            return x, y
        i = person.index
        return float(motion.pos[i, 0]), float(motion.pos[i, 1])   # nowhere free: stay where one is

    # ------------------------------------------------------------------------------------ chats
    def _chat_with(self, person: Person, partner: Person, t: float, dwell: float) -> bool:
        if partner.task.kind != "stand" or partner.task.purpose not in ("dwell", "chat"):
            return False
        pos = self.motion.pos
        i, j = person.index, partner.index
        group_id = partner.task.other if partner.task.purpose == "chat" else ""
        group = self.chats.get(group_id)
        if group is not None and len(group["members"]) >= 2:
            members = [tuple(pos[self.people[m].index]) for m in sorted(group["members"])]
            place = join_circle(group["centre"], members, self.motion.out_of_the_way)
            if place is None:
                return False
            centre = group["centre"]
        else:
            found = chat_place(tuple(pos[j]), tuple(pos[i]), self.motion.out_of_the_way)
            if found is None:
                return False
            place, partner_pose, centre = found
            self._chat_counter += 1
            group_id = f"chat{self._chat_counter}"
            group = {"centre": centre, "members": {partner.spec.name}}
            self.chats[group_id] = group
            partner.task = Task("stand", "chat", (float(pos[j, 0]), float(pos[j, 1]), partner_pose[2]),
                                until_s=partner.task.until_s, other=group_id)
        group["members"].add(person.spec.name)
        travel = math.hypot(place[0] - pos[i, 0], place[1] - pos[i, 1]) * DETOUR / person.spec.speed_mps
        until = t + travel + dwell
        self.motion.walk(person, t, place, "chat", other=group_id, until_s=until, look_at=tuple(centre))
        partner.task.until_s = max(partner.task.until_s, until)
        partner.next_check_s = min(partner.next_check_s, t)
        return True

    def rejoin(self, person: Person, t: float) -> bool:
        """Blocked on the way to a conversation: talk from where one is, if that is a conversation
        distance from the others (the circle's centre moves between them), else give it up."""
        pos = self.motion.pos
        group = self.chats.get(person.task.other)
        i = person.index
        here = pos[i]
        others = [pos[self.people[m].index] for m in sorted(group["members"]) if m != person.spec.name] \
            if group else []
        if not others or min(math.hypot(*(here - o)) for o in others) > 2 * CHAT_RADIUS_M + 0.8:
            return False
        nearest = min(others, key=lambda o: math.hypot(*(here - o)))
        gap = math.hypot(*(here - nearest))
        if gap < 2 * CHAT_RADIUS_M - 0.3:
            # Pressed against them: step back to a conversation distance on this side.
            away = (here - nearest) / max(gap, 1e-9)
            x, y = nearest + away * 2 * CHAT_RADIUS_M
            if not self.motion.fits(float(x), float(y)):
                return False
            person.task.target = (float(x), float(y), math.atan2(-away[1], -away[0]))
            person.task.look_at = tuple(nearest + away * CHAT_RADIUS_M)
            person.task.route = [(float(x), float(y))]
            person.task.best_m = math.inf
            return True
        assert group is not None
        centre = tuple(np.mean([here, *others], axis=0))
        group["centre"] = centre
        for name in group["members"]:
            member = self.people[name]
            j = member.index
            facing = math.atan2(centre[1] - pos[j, 1], centre[0] - pos[j, 0])
            if member is person:
                self.motion.arrive(person, t, (float(here[0]), float(here[1]), facing))
            elif member.task.kind == "stand":
                member.task.target = (member.task.target[0], member.task.target[1], facing)
        return True

    def leave_chat(self, person: Person) -> None:
        """``person`` leaves their conversation; the last one left of it talks with nobody."""
        group_id = person.task.other if person.task.purpose == "chat" else ""
        group = self.chats.get(group_id)
        if group is None:
            return
        group["members"].discard(person.spec.name)
        person.task = replace(person.task, purpose="dwell", other="")
        if len(group["members"]) <= 1:
            for name in group["members"]:
                other = self.people[name]
                if other.task.purpose == "chat":
                    other.task = replace(other.task, purpose="dwell", other="")
            del self.chats[group_id]

    def settled(self, person: Person) -> bool:
        """Standing at their place and turned to face where they should."""
        task = person.task
        turn = wrap_angle(task.target[2] - self.motion.theta[person.index])
        return task.kind == "stand" and abs(turn) < SETTLED_RAD

    def group_of(self, person: Person) -> str:
        """The formation a person stands in (the truth the metrics' group intrusions use)."""
        task = person.task
        if not self.settled(person):
            return ""
        if task.purpose == "attend":
            return f"activity/{task.activity}"
        if task.purpose == "chat" and task.other in self.chats and len(self.chats[task.other]["members"]) >= 2:
            settled = [m for m in self.chats[task.other]["members"] if self.settled(self.people[m])]
            return f"chat/{task.other}" if len(settled) >= 2 else ""
        return ""
