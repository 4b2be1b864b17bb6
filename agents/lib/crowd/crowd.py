"""The simulated people of a care centre: who goes where when (the behaviour) and how they walk (ORCA).

One ``Crowd`` is one day.  It advances in fixed steps of ``STEP_S`` on a grid anchored at the
day's start, so the state at a time depends only on the scene, the seed, the agenda it was fed
and the robot's motion - never on how the caller slices time.  Positions between two steps are
interpolated (sensors read ``at(t)`` at any time).

Behaviour, each step, for every person who walks by themselves (name order, so it is
deterministic):

1. **The agenda first.** A participant of an activity leaves so as to arrive ``ARRIVE_EARLY_S``
   before its start (walking time estimated as ``DETOUR`` x the straight distance at their
   speed, plus ``START_SLACK_S``), goes to their place around the object (formations.py) and
   stands there, facing it, until the end.  A cancelled, moved or newly added activity changes
   this at once.  A resident marked ``escort`` waits up to ``ESCORT_WAIT_S`` for the staff member
   the agenda assigns to fetch them (the first free ``staff`` by name), who walks to them and
   then beside them to the activity.
2. **Otherwise the routine.** When a stay at one place ends, a person draws their next move from
   their own random stream (seed, name, decision number: a person's day does not change when
   someone else is added): chat with someone standing in one of their rooms (``CHAT_CHANCE``;
   pairs face each other, a third joins the circle), or go to a free place in their home room
   (``HOME_CHANCE``) or another of their rooms and stay a time drawn from their dwell range.
   Visitors keep company with the person they visit.

Walking follows a route through door gaps and around furniture (routes.py); ORCA (orca.py)
avoids the others and the robot (a moving body while it drives, an obstacle at rest; nobody
picks a place to stand next to the resting robot).  A walker that makes no progress for
``STUCK_S`` replans its route, and settles where it is when it is already close.

When nobody walks and nothing scripted moves (and the robot does not drive), nothing can change
until the next decision is due: the crowd jumps there directly instead of stepping.  That is what
makes a day cheap enough to fast-forward when the simulator skips an idle stretch, and to replay
from the start for the offline commands.
"""

from __future__ import annotations

import copy
import math
import zlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace

import numpy as np
import shapely
from shapely.geometry.polygon import orient

from agents.lib.crowd.formations import CHAT_RADIUS_M, chat_place, join_circle, ring_places, screen_places
from agents.lib.crowd.model import Agenda, Appointment, Building, PersonTruth, RobotBody, Walker
from agents.lib.crowd.orca import PARKED, Orca
from agents.lib.crowd.routes import NoRoute, Router
from scenes.angles import wrap_angle

STEP_S = 0.25              # people's decisions and ORCA steps: 4 Hz of sim time
ARRIVE_EARLY_S = 150.0      # aim to be at an activity this long before it starts (within 5 min)
START_SLACK_S = 20.0        # time to get up and turn at the start of a walk
DETOUR = 1.4                # route length over straight distance, for the departure estimate
ESCORT_WAIT_S = 150.0       # a resident waits this long for the staff who fetches them
CHAT_CHANCE = {"wander": 0.35, "staff": 0.1, "visitor": 0.0}
HOME_CHANCE = 0.5
STUCK_S = 8.0               # no progress for this long: replan, or settle when close
SETTLE_M = 0.8              # ... close means this near the goal
WAYPOINT_REACHED_M = 0.35
TURN_RATE_RADPS = 3.0
SPOT_TRIES = 40
SPOT_WALL_M = 0.5           # a chosen spot keeps this from walls
SPOT_FURNITURE_M = 0.6
SPOT_DOOR_M = 1.3           # ... and out of doorways
SPOT_PEOPLE_M = 1.0         # ... and from other people and where they are going
SPOT_CORNER_M = 0.9         # ... and off the corners routes turn at (where others will walk)
SIDESTEP_RAD = 0.9          # a walker blocked for half of STUCK_S steps this much to a side
ROBOT_MARGIN_M = 0.1        # people give the robot this much more than its body
ROBOT_CLEARANCE_M = 0.6     # nobody picks a place to stand nearer the resting robot's body than this
PASSAGE_WIDTH_M = 3.0       # a room narrower than this is a corridor: people pass, they do not stay
FIRST_DECISION = 2**31      # the random stream index of the start-of-day draw
SCRIPT_VELOCITY_DT_S = 0.05


@dataclass
class Task:
    """What one person is doing: standing somewhere (until a time) or walking to a pose."""

    kind: str                         # "stand" | "walk"
    purpose: str                      # dwell | chat | attend | fetch | escort | stay
    target: tuple[float, float, float]
    until_s: float = math.inf
    activity: str = ""
    other: str = ""                   # fetch/escort: the resident; chat: the group id
    route: list[tuple[float, float]] = field(default_factory=list)
    look_at: tuple[float, float] | None = None   # what they face when they settle short of the target
    best_m: float = math.inf
    progress_s: float = 0.0
    replans: int = 0


@dataclass
class Person:
    spec: Walker
    index: int
    task: Task
    decisions: int = 0
    next_check_s: float = -math.inf
    escorted_to: str = ""             # activity a staff member is walking them to


def _width(polygon: shapely.Polygon) -> float:
    """The short side of a room's minimum rotated rectangle: a corridor's width."""
    box = shapely.minimum_rotated_rectangle(polygon)
    corners = np.asarray(box.exterior.coords)[:3]
    return float(min(np.hypot(*(corners[1] - corners[0])), np.hypot(*(corners[2] - corners[1]))))


def _rng(seed: int, name: str, k: int) -> np.random.Generator:
    return np.random.default_rng([seed, zlib.crc32(name.encode()), k])


class Crowd:
    """One simulated day of a scene's people (see the module doc)."""

    def __init__(self, building: Building, walkers: Sequence[Walker], *, seed: int, start_s: float,
                 robot_radius_m: float = 0.3, step_s: float = STEP_S) -> None:
        self.building = building
        self.seed = int(seed)
        self.start_s = float(start_s)
        self.step_s = step_s
        self.k = 0
        self.walkers = sorted(walkers, key=lambda w: w.name)
        self.people = {w.name: Person(w, i, Task("stand", "dwell" if w.dynamic else "stay", w.pose,
                                                 until_s=self._first_move_s(w)))
                       for i, w in enumerate(self.walkers)}
        n = len(self.walkers)
        self._dynamic = [self.people[w.name] for w in self.walkers if w.dynamic]          # name order
        self._scripted = [self.people[w.name] for w in self.walkers if not w.dynamic and w.moves and w.script]
        self.pos = np.array([w.pose[:2] for w in self.walkers], dtype=float).reshape(n, 2)
        self.theta = np.array([w.pose[2] for w in self.walkers], dtype=float)
        self.vel = np.zeros((n, 2))
        self.prev = (self.pos.copy(), self.theta.copy(), self.vel.copy())
        self._robot_index = n
        self._robot_parked: tuple[float, float] | None = PARKED   # where the resting robot stands (None: it drives)
        self._robot_radius = robot_radius_m + ROBOT_MARGIN_M
        self._closed: frozenset[str] = frozenset()
        self._routers: dict[frozenset[str], Router] = {}
        self._room_polys = {name: poly for name, poly in building.rooms.items()}
        for poly in self._room_polys.values():
            shapely.prepare(poly)
        self._building_poly = shapely.union_all(list(building.rooms.values()))
        footprints = [t.footprint for t in building.things.values()]
        self._footprints = shapely.union_all(footprints) if footprints else shapely.GeometryCollection()
        self._wall_lines = shapely.MultiLineString([list(w) for w in building.walls if len(w) >= 2])
        shapely.prepare(self._footprints)
        shapely.prepare(self._wall_lines)
        self._door_xy = np.array(list(building.doors.values()), dtype=float).reshape(-1, 2)
        self._stay_rooms = sorted(name for name, poly in self._room_polys.items() if _width(poly) >= PASSAGE_WIDTH_M)
        radii = [w.radius_m for w in self.walkers] + [self._robot_radius]
        positions = np.vstack([self.pos, [PARKED]])
        self.orca = Orca(step_s, self._obstacles(frozenset()), radii, positions)
        for person in self.people.values():
            if not person.spec.dynamic and person.spec.script is not None:
                x, y, th = person.spec.script(self.start_s)
                self.pos[person.index] = (x, y)
                self.theta[person.index] = th
        self._sync_positions(range(n))
        self.prev = (self.pos.copy(), self.theta.copy(), self.vel.copy())
        self._agenda_version: object = object()
        self._appointments: dict[str, Appointment] = {}
        self._by_person: dict[str, list[Appointment]] = {}
        self._places: dict[str, list[tuple[float, float, float]]] = {}
        self._place_points = np.zeros((0, 2))
        self._jobs: dict[tuple[str, str], str] = {}
        self._jobs_done: set[tuple[str, str]] = set()
        self._chats: dict[str, dict] = {}
        self._chat_counter = 0

    def _first_move_s(self, walker: Walker) -> float:
        """People do not all get up at the start of the day: the first stay lasts a part of a dwell."""
        if not walker.dynamic:
            return math.inf
        u = float(_rng(self.seed, walker.name, FIRST_DECISION).random())
        return self.start_s + u * walker.dwell_s[1]

    def clone(self) -> Crowd:
        """An independent copy in the same state (the offline world's snapshots); it continues
        exactly as this one would."""
        orca, routers = self.orca, self._routers
        self.orca, self._routers = None, {}  # type: ignore[assignment]
        try:
            twin = copy.deepcopy(self)
        finally:
            self.orca, self._routers = orca, routers
        twin.orca = orca.clone()
        twin._routers = routers         # immutable once built: shared
        return twin

    # ------------------------------------------------------------------------------------ time
    @property
    def t_s(self) -> float:
        """Time of the latest computed state."""
        return self.start_s + self.k * self.step_s

    def advance(self, t_s: float, world: Callable[[float], Agenda], robot: RobotBody | None = None) -> None:
        """Compute states up to the first step at or after ``t_s``.

        ``world(t)`` gives the appointments and closed doors in force at step time t (and when they
        next change); ``robot`` is where the robot is and how it moves (at rest: zero velocity, an
        obstacle; None: no robot, nobody reacts to it)."""
        while self.t_s < t_s - 1e-9:
            self._step(world, robot, t_s)

    def next_event_s(self, t_s: float) -> float:
        """The next routine event after ``t_s``: someone standing decides to move on (their stay or
        chat ends, an activity calls them) or a scripted walk starts; inf when none is known.
        Why: the simulator's idle skip stops there, so the DSR shows each event at its time."""
        times = [p.next_check_s for p in self._dynamic if p.task.kind == "stand" and p.next_check_s > t_s + 1e-9]
        times += [t0 for p in self._scripted for t0, _ in p.spec.moves if t0 > t_s + 1e-9]
        return min(times, default=math.inf)

    def _doors(self, closed_doors: frozenset[str]) -> None:
        if closed_doors != self._closed:
            self._closed = closed_doors
            self.orca.set_obstacles(self._obstacles(closed_doors))
            for person in self.people.values():
                if person.task.kind == "walk":
                    person.task.route = []          # replanned on this step

    def at(self, t_s: float) -> tuple[PersonTruth, ...]:
        """Everyone at ``t_s`` in [t - step, t] of the latest state, linearly interpolated."""
        t1 = self.t_s
        f = 1.0 if t1 - t_s <= 1e-9 else max(0.0, 1.0 - (t1 - t_s) / self.step_s)
        p0, th0, _ = self.prev
        out = []
        for w, person in zip(self.walkers, (self.people[w.name] for w in self.walkers), strict=True):
            i = person.index
            if not w.dynamic:
                out.append(self._scripted_truth(w, t_s))
                continue
            x = float(p0[i, 0] + f * (self.pos[i, 0] - p0[i, 0]))
            y = float(p0[i, 1] + f * (self.pos[i, 1] - p0[i, 1]))
            dth = wrap_angle(self.theta[i] - th0[i])
            theta = wrap_angle(th0[i] + f * dth)
            out.append(PersonTruth(w.name, w.role, x, y, float(theta), float(self.vel[i, 0]), float(self.vel[i, 1]),
                                   self._group_of(person), person.task.activity or person.escorted_to))
        return tuple(out)

    def _scripted_truth(self, w: Walker, t_s: float) -> PersonTruth:
        """A ``stay`` person is exactly where their script puts them (no step grid, no interpolation)."""
        if w.script is None:
            return PersonTruth(w.name, w.role, *w.pose)
        x, y, theta = w.script(t_s)
        vx = vy = 0.0
        if any(t0 <= t_s < t1 for t0, t1 in w.moves):
            x1, y1, _ = w.script(t_s + SCRIPT_VELOCITY_DT_S)
            vx, vy = (x1 - x) / SCRIPT_VELOCITY_DT_S, (y1 - y) / SCRIPT_VELOCITY_DT_S
        return PersonTruth(w.name, w.role, x, y, theta, vx, vy)

    # ------------------------------------------------------------------------------------ geometry
    def _obstacles(self, closed: frozenset[str]) -> list[list[tuple[float, float]]]:
        obstacles = [[tuple(a), tuple(b)] for w in self.building.walls for a, b in zip(w, w[1:], strict=False)
                     if tuple(a) != tuple(b)]
        for thing in self.building.things.values():
            ring = orient(thing.footprint, 1.0).exterior.coords[:-1]   # RVO2 wants counter-clockwise
            obstacles.append([tuple(c) for c in ring])
        for name in sorted(closed):
            leaf = self.building.door_leaves.get(name)
            if leaf is not None:
                obstacles.append([tuple(leaf[0]), tuple(leaf[1])])
        return obstacles

    @property
    def router(self) -> Router:
        if self._closed not in self._routers:
            walls = [*self.building.walls, *(list(self.building.door_leaves[d]) for d in sorted(self._closed)
                                             if d in self.building.door_leaves)]
            self._routers[self._closed] = Router.build(self._building_poly, walls,
                                                       [t.footprint for t in self.building.things.values()])
        return self._routers[self._closed]

    def room_of(self, x: float, y: float) -> str | None:
        for name, poly in self._room_polys.items():
            if shapely.intersects_xy(poly, x, y):
                return name
        return None

    def _out_of_the_way(self, x: float, y: float) -> bool:
        """A body fits at (x, y) and does not stand where routes turn (a chat or a rest place)."""
        if not self._fits(x, y):
            return False
        corners = self.router.graphs[0].corners
        return not len(corners) or float(np.min(np.hypot(*(corners - (x, y)).T))) >= SPOT_CORNER_M

    def _clear_of_robot(self, x: float, y: float) -> bool:
        """(x, y) is at least ``ROBOT_CLEARANCE_M`` from the resting robot's body (or it drives)."""
        rest = self._robot_parked
        return rest is None or math.hypot(x - rest[0], y - rest[1]) >= self._robot_radius + ROBOT_CLEARANCE_M

    def _fits(self, x: float, y: float) -> bool:
        """A body can stand at (x, y): in the building, clear of walls, furniture and the resting robot."""
        rest = self._robot_parked
        if rest is not None and math.hypot(x - rest[0], y - rest[1]) < self._robot_radius + ROBOT_CLEARANCE_M:
            return False
        return bool(shapely.contains_xy(self._building_poly, x, y)
                    and self._wall_lines.distance(shapely.Point(x, y)) >= 0.3
                    and self._footprints.distance(shapely.Point(x, y)) >= 0.3)

    def _park(self, robot: RobotBody | None) -> None:
        """The robot at rest is furniture to the people: an obstacle ORCA walkers go round (max speed
        0), and no one chooses to stand where it is.  ``None``: no robot in this world."""
        rest = PARKED if robot is None else (robot.x, robot.y)
        if rest != self._robot_parked:
            self.orca.place(self._robot_index, *rest)
            self.orca.set_max_speed(self._robot_index, 0.0)
            self.orca.prefer(self._robot_index, 0.0, 0.0)
            self._robot_parked = rest
            self._clear_places_of_robot()

    def _clear_places_of_robot(self) -> None:
        """The robot came to rest where an activity's formation has a place (it parked by the table
        it was sent to): that formation is drawn again clear of it, and whoever attends walks to their
        new place, so nobody stands inside the robot's intimate distance (Hall's 0.45 m between the
        bodies: ``ROBOT_CLEARANCE_M``), however long the clock then skips."""
        rest = self._robot_parked
        if rest is None or rest == PARKED or not getattr(self, "_places", None):
            return
        limit = self._robot_radius + ROBOT_CLEARANCE_M
        for aid, places in list(self._places.items()):
            if all(math.hypot(x - rest[0], y - rest[1]) >= limit for x, y, _ in places):
                continue
            a = self._appointments[aid]
            self._places[aid] = new = self._formation(a)
            for old, place, name in zip(places, new, a.participants, strict=False):
                person = self.people.get(name)
                if person is not None and math.hypot(old[0] - place[0], old[1] - place[1]) > 1e-6:
                    if person.task.activity == aid:
                        person.task.activity = ""          # _decide sends them to their new place
                    person.next_check_s = -math.inf
        points = [p[:2] for places in self._places.values() for p in places]
        self._place_points = np.asarray(points, dtype=float).reshape(-1, 2)

    # ------------------------------------------------------------------------------------ agenda
    def _read_agenda(self, agenda: Agenda) -> None:
        if agenda.version == self._agenda_version:
            return
        self._agenda_version = agenda.version
        self._appointments = {a.id: a for a in agenda.appointments if a.object in self.building.things}
        self._by_person = {}
        for a in sorted(self._appointments.values(), key=lambda a: (a.start_s, a.id)):
            for name in a.participants:
                if name in self.people and self.people[name].spec.dynamic:
                    self._by_person.setdefault(name, []).append(a)
        self._places = {a.id: self._formation(a) for a in self._appointments.values()}
        points = [p[:2] for places in self._places.values() for p in places]
        self._place_points = np.asarray(points, dtype=float).reshape(-1, 2)
        self._jobs = self._escort_jobs()
        for person in self.people.values():
            person.next_check_s = -math.inf

    def _formation(self, a: Appointment) -> list[tuple[float, float, float]]:
        thing = self.building.things[a.object]
        count = len(a.participants)
        if thing.screen:
            places = screen_places(thing.x, thing.y, thing.theta, count, self._fits)
        else:
            places = ring_places(thing.footprint, count, self._fits)
        while len(places) < count:   # more participants than places: a second ring, farther out
            extra = ring_places(thing.footprint.buffer(0.7), count - len(places), self._fits) or \
                [(thing.x + 1.5, thing.y, math.pi)]
            places.extend(extra[: count - len(places)])
        return places

    def _place(self, a: Appointment, name: str) -> tuple[float, float, float]:
        return self._places[a.id][a.participants.index(name)]

    def _escort_jobs(self) -> dict[tuple[str, str], str]:
        """Which staff member fetches which escorted resident to which activity: the first ``staff``
        by name who takes part in nothing around then and fetches nobody else within 15 min."""
        staff = [p.spec.name for p in self.people.values() if p.spec.routine == "staff"]
        jobs: dict[tuple[str, str], str] = {}
        busy: dict[str, list[float]] = {}
        for a in sorted(self._appointments.values(), key=lambda a: (a.start_s, a.id)):
            for name in a.participants:
                person = self.people.get(name)
                if person is None or not person.spec.escort or not person.spec.dynamic:
                    continue
                for s in sorted(staff):
                    in_activity = any(s in b.participants and b.start_s - 900 < a.start_s < b.end_s
                                      for b in self._appointments.values())
                    if in_activity or any(abs(t - a.start_s) < 900 for t in busy.get(s, [])):
                        continue
                    jobs[(a.id, name)] = s
                    busy.setdefault(s, []).append(a.start_s)
                    break
        return jobs

    def _travel_s(self, person: Person, x: float, y: float) -> float:
        i = person.index
        distance = math.hypot(x - self.pos[i, 0], y - self.pos[i, 1])
        return DETOUR * distance / person.spec.speed_mps + START_SLACK_S

    def _departure_s(self, person: Person, a: Appointment) -> float:
        x, y, _ = self._place(a, person.spec.name)
        return a.start_s - ARRIVE_EARLY_S - self._travel_s(person, x, y)

    def _due(self, person: Person, t: float) -> Appointment | None:
        """The activity this person should now be walking to or attending, if any."""
        name = person.spec.name
        for a in self._by_person.get(name, ()):
            if t >= a.end_s:
                continue
            if person.escorted_to == a.id or person.task.activity == a.id:
                return a    # on the way (the estimate shrinks as they walk) or there: until it ends
            leave = self._departure_s(person, a)
            if (a.id, name) in self._jobs and (a.id, name) not in self._jobs_done:
                leave += ESCORT_WAIT_S
            if t >= leave:
                return a
        return None

    def _next_due_s(self, person: Person, t: float) -> float:
        """When this (standing) person's next departure for an activity is due."""
        name = person.spec.name
        soonest = math.inf
        for a in self._by_person.get(name, ()):
            if t >= a.end_s:
                continue
            leave = self._departure_s(person, a)
            if (a.id, name) in self._jobs and (a.id, name) not in self._jobs_done:
                leave += ESCORT_WAIT_S
            soonest = min(soonest, leave if leave > t else a.end_s)
        if person.spec.routine == "staff":
            for (activity_id, resident), staff in self._jobs.items():
                if staff == name and (activity_id, resident) not in self._jobs_done:
                    soonest = min(soonest, self._fetch_s(person, activity_id, resident))
        return soonest

    def _fetch_s(self, staff: Person, activity_id: str, resident: str) -> float:
        a = self._appointments[activity_id]
        r = self.people[resident]
        rx, ry = self.pos[r.index]
        return self._departure_s(r, a) - self._travel_s(staff, rx, ry) - 30.0

    # ------------------------------------------------------------------------------------ step
    def _step(self, agenda_at: Callable[[float], Agenda], robot: RobotBody | None, until_s: float) -> None:
        t = self.t_s
        if robot is None or not robot.driving:
            self._park(robot)   # first: the places people choose on this step keep clear of it
        agenda = agenda_at(t)
        self._doors(agenda.closed_doors)
        self._read_agenda(agenda)
        for person in self._dynamic:
            if person.task.kind == "walk" or t >= person.next_check_s:
                self._decide(person, t)
        walking = [p for p in self._dynamic if p.task.kind == "walk"]
        scripted_moving = [p for p in self._scripted
                           if any(t0 - self.step_s < t < t1 + self.step_s for t0, t1 in p.spec.moves)]
        standing = [p for p in self._dynamic if p.task.kind == "stand"]
        want = np.array([p.task.target[2] for p in standing])
        have = self.theta[[p.index for p in standing]] if standing else np.zeros(0)
        off = np.abs(wrap_angle(want - have)) > 1e-6
        turning = [p for p, o in zip(standing, off, strict=True) if o] if off.any() else []
        if not walking and not scripted_moving and not turning and (robot is None or not robot.driving):
            self._quiet_jump(t, agenda, until_s)
            return
        self.prev = (self.pos.copy(), self.theta.copy(), self.vel.copy())
        for person in walking:
            self._prefer(person, t)
        for person in scripted_moving:
            x0, y0, _ = person.spec.script(t)
            x1, y1, _ = person.spec.script(t + self.step_s)
            vx, vy = (x1 - x0) / self.step_s, (y1 - y0) / self.step_s
            self.orca.place(person.index, x0, y0, vx, vy)
            self.orca.set_max_speed(person.index, max(2.0, math.hypot(vx, vy)))
            self.orca.prefer(person.index, vx, vy)
        if robot is not None and robot.driving:
            self.orca.place(self._robot_index, robot.x, robot.y, robot.vx, robot.vy)
            self.orca.set_max_speed(self._robot_index, max(2.0, math.hypot(robot.vx, robot.vy)))
            self.orca.prefer(self._robot_index, robot.vx, robot.vy)
            self._robot_parked = None
        self.orca.step()
        self.k += 1
        t1 = self.t_s
        for person in walking:
            i = person.index
            x, y = self.orca.position(i)
            vx, vy = self.orca.velocity(i)
            self.pos[i] = (x, y)
            self.vel[i] = (vx, vy)
            if vx * vx + vy * vy > 0.01:
                self.theta[i] = math.atan2(vy, vx)
        for person in scripted_moving:
            i = person.index
            x, y, th = person.spec.script(t1)
            x0, y0, _ = person.spec.script(t)
            self.orca.place(i, x, y, 0.0, 0.0)
            self.orca.set_max_speed(i, 0.0)
            self._sync_positions([i])
            self.theta[i] = th
            self.vel[i] = ((x - x0) / self.step_s, (y - y0) / self.step_s)
        for person in turning:
            i = person.index
            want = person.task.target[2]
            diff = wrap_angle(want - self.theta[i])
            limit = TURN_RATE_RADPS * self.step_s
            self.theta[i] = want if abs(diff) <= limit else self.theta[i] + math.copysign(limit, diff)
            self.vel[i] = (0.0, 0.0)
        if standing:
            self.vel[[p.index for p in standing]] = 0.0
        for person in self._scripted:
            if person not in scripted_moving:
                self.vel[person.index] = (0.0, 0.0)

    def _quiet_jump(self, t: float, agenda: Agenda, until_s: float) -> None:
        """Nobody moves: jump to the step where the next decision is due (or the caller's time)."""
        due = min([p.next_check_s for p in self._dynamic] + [agenda.next_change_s])
        for person in self._scripted:
            for t0, _ in person.spec.moves:
                if t0 > t:
                    due = min(due, t0)
        target = min(due, until_s)
        steps = max(1, math.ceil((target - self.start_s) / self.step_s - 1e-9) - self.k)
        self.vel[:] = 0.0
        self.prev = (self.pos.copy(), self.theta.copy(), self.vel.copy())
        self.k += steps

    def _sync_positions(self, indices: Sequence[int] | range) -> None:
        """Mirror RVO2's float32 positions (what the next step starts from) after placing agents."""
        for i in indices:
            self.orca.place(i, float(self.pos[i, 0]), float(self.pos[i, 1]))
            self.pos[i] = self.orca.position(i)

    # ------------------------------------------------------------------------------------ behaviour
    def _decide(self, person: Person, t: float) -> None:
        task = person.task
        due = self._due(person, t)
        if person.spec.routine == "staff" and task.purpose in ("fetch", "escort") and due is None:
            self._staff_job(person, t)
            return
        if due is not None:
            if task.activity != due.id:
                self._leave_chat(person)
                x, y, th = self._place(due, person.spec.name)
                thing = self.building.things[due.object]
                self._walk(person, t, (x, y, th), "attend", activity=due.id, look_at=(thing.x, thing.y))
            elif task.kind == "walk":
                self._walking(person, t)
            person.next_check_s = due.end_s if person.task.kind == "stand" else t
            return
        if task.purpose == "attend":
            person.escorted_to = ""
            self._routine(person, t)
            return
        if person.spec.routine == "staff" and self._start_job(person, t):
            return
        if task.kind == "walk":
            self._walking(person, t)
            if person.task.kind == "walk":
                return
        if t >= person.task.until_s:
            self._routine(person, t)
            return
        person.next_check_s = min(person.task.until_s, self._next_due_s(person, t))

    def _walk(self, person: Person, t: float, target: tuple[float, float, float], purpose: str,
              activity: str = "", other: str = "", until_s: float = math.inf,
              look_at: tuple[float, float] | None = None) -> None:
        person.task = Task("walk", purpose, target, until_s=until_s, activity=activity, other=other,
                           progress_s=t, look_at=look_at)
        self._route(person)
        self.orca.set_max_speed(person.index, person.spec.speed_mps)
        person.next_check_s = t

    def _route(self, person: Person) -> None:
        i = person.index
        start = (float(self.pos[i, 0]), float(self.pos[i, 1]))
        goal = person.task.target[:2]
        try:
            person.task.route, _ = self.router.route(start, goal)
        except NoRoute:
            person.task.route = [goal]    # ORCA will get as close as walls allow; settles when stuck

    def _walking(self, person: Person, t: float) -> None:
        """Arrived, stuck, or on the way."""
        task = person.task
        i = person.index
        x, y = self.pos[i]
        gx, gy, gth = task.target
        distance = math.hypot(gx - x, gy - y)
        if distance < 0.02:
            self._arrive(person, t, (gx, gy, gth))
            return
        if distance < task.best_m - 0.1:
            task.best_m, task.progress_s = distance, t
        elif t - task.progress_s > STUCK_S:
            task.progress_s = t
            task.replans += 1
            if task.purpose == "chat" and self._rejoin(person, t):
                return
            if (distance < SETTLE_M or (task.replans > 3 and task.purpose not in ("attend", "fetch"))) \
                    and self._clear_of_robot(float(x), float(y)):     # never settle in the robot's intimate distance
                facing = gth if task.look_at is None else math.atan2(task.look_at[1] - y, task.look_at[0] - x)
                self._arrive(person, t, (float(x), float(y), facing))
                return
            self._route(person)
        if not task.route:
            self._route(person)

    def _arrive(self, person: Person, t: float, pose: tuple[float, float, float]) -> None:
        i = person.index
        task = person.task
        self.orca.set_max_speed(i, 0.0)
        self.pos[i] = pose[:2]
        self._sync_positions([i])
        self.vel[i] = (0.0, 0.0)
        if task.purpose == "fetch":
            self._pick_up(person, t)
            return
        person.task = Task("stand", task.purpose, pose, until_s=task.until_s, activity=task.activity, other=task.other)
        if task.purpose == "attend":
            person.escorted_to = ""
        person.next_check_s = t

    def _prefer(self, person: Person, t: float) -> None:
        """Preferred velocity toward the next waypoint (slowing to land exactly on the goal)."""
        i = person.index
        task = person.task
        x, y = self.pos[i]
        if task.purpose == "escort":
            resident = self.people[task.other]
            rx, ry = self.pos[resident.index]
            rth = self.theta[resident.index]
            # beside them on their left, half a step behind
            task.route = [(rx - 0.8 * math.sin(rth) - 0.2 * math.cos(rth), ry + 0.8 * math.cos(rth) - 0.2 * math.sin(rth))]
        while len(task.route) > 1 and math.hypot(task.route[0][0] - x, task.route[0][1] - y) < WAYPOINT_REACHED_M:
            task.route.pop(0)
        if not task.route:
            self.orca.prefer(i, 0.0, 0.0)
            return
        wx, wy = task.route[0]
        dx, dy = wx - x, wy - y
        distance = math.hypot(dx, dy)
        if distance < 1e-9:
            self.orca.prefer(i, 0.0, 0.0)
            return
        if task.replans and t - task.progress_s > STUCK_S / 2 and task.purpose != "escort":
            # Blocked (someone stands on the way): step aside, left or right in turn, and let ORCA
            # find the way round; the route is replanned when STUCK_S passes without progress.
            turn = SIDESTEP_RAD if task.replans % 2 else -SIDESTEP_RAD
            c, s_ = math.cos(turn), math.sin(turn)
            dx, dy = c * dx - s_ * dy, s_ * dx + c * dy
        speed = person.spec.speed_mps
        if task.purpose == "escort":
            speed = min(speed, 1.2 * self.people[task.other].spec.speed_mps + 0.2 * distance)
        if len(task.route) == 1:
            speed = min(speed, distance / self.step_s)
        self.orca.prefer(i, dx / distance * speed, dy / distance * speed)

    def _routine(self, person: Person, t: float) -> None:
        """The next place to be, from the person's own random stream."""
        self._leave_chat(person)
        spec = person.spec
        rng = _rng(self.seed, spec.name, person.decisions)
        person.decisions += 1
        u = rng.random(8)
        dwell = spec.dwell_s[0] + (spec.dwell_s[1] - spec.dwell_s[0]) * u[5]
        if spec.routine == "visitor" and spec.visits in self.people:
            friend = self.people[spec.visits]
            if self._chat_with(person, friend, t, dwell):
                return
            room = self.room_of(*self.pos[friend.index]) or spec.home
            self._dwell(person, t, room, u, min(dwell, 60.0))
            return
        if u[0] < CHAT_CHANCE.get(spec.routine, 0.0):
            candidates = [p for name, p in sorted(self.people.items()) if p is not person and p.spec.dynamic
                          and p.task.kind == "stand" and p.task.purpose in ("dwell", "chat")
                          and self.room_of(*self.pos[p.index]) in self._rooms(person)]
            if candidates and self._chat_with(person, candidates[int(u[6] * len(candidates))], t, dwell):
                return
        rooms = self._rooms(person)
        room = spec.home if (spec.home in rooms and u[1] < HOME_CHANCE) else rooms[int(u[2] * len(rooms))]
        self._dwell(person, t, room, u, dwell)

    def _rooms(self, person: Person) -> list[str]:
        """Where the routine goes: the person's ``rooms``, or every room a group can stand in
        (corridors, narrower than ``PASSAGE_WIDTH_M``, are for passing through)."""
        if person.spec.rooms:
            return list(person.spec.rooms)
        return self._stay_rooms or sorted(self._room_polys)

    def _dwell(self, person: Person, t: float, room: str | None, u: np.ndarray, dwell: float) -> None:
        spot = self._spot(person, room, int(u[3] * 2**31))
        theta = -math.pi + 2 * math.pi * float(u[4])
        i = person.index
        travel = math.hypot(spot[0] - self.pos[i, 0], spot[1] - self.pos[i, 1]) * DETOUR / person.spec.speed_mps
        self._walk(person, t, (spot[0], spot[1], theta), "dwell", until_s=t + travel + dwell)

    def _spot(self, person: Person, room: str | None, seed: int) -> tuple[float, float]:
        """A free place in ``room``: off the walls, the furniture and the doorways, away from people
        and from where they are going, and off today's activity places."""
        poly = self._room_polys.get(room or "") or self._building_poly
        xmin, ymin, xmax, ymax = poly.bounds
        rng = np.random.default_rng(seed)
        others = [self.pos[p.index] for p in self.people.values() if p is not person] + \
                 [p.task.target[:2] for p in self.people.values() if p is not person]
        others_xy = np.asarray(others, dtype=float).reshape(-1, 2)
        for _ in range(SPOT_TRIES):
            x, y = float(rng.uniform(xmin, xmax)), float(rng.uniform(ymin, ymax))
            if not shapely.contains_xy(poly, x, y):
                continue
            point = shapely.Point(x, y)
            if self._wall_lines.distance(point) < SPOT_WALL_M or self._footprints.distance(point) < SPOT_FURNITURE_M:
                continue
            if len(self._door_xy) and np.min(np.hypot(*(self._door_xy - (x, y)).T)) < SPOT_DOOR_M:
                continue
            if len(others_xy) and np.min(np.hypot(*(others_xy - (x, y)).T)) < SPOT_PEOPLE_M:
                continue
            if len(self._place_points) and np.min(np.hypot(*(self._place_points - (x, y)).T)) < SPOT_PEOPLE_M:
                continue
            if not self._out_of_the_way(x, y):
                continue
            return x, y
        i = person.index
        return float(self.pos[i, 0]), float(self.pos[i, 1])   # nowhere free: stay where one is

    # ------------------------------------------------------------------------------------ chats
    def _chat_with(self, person: Person, partner: Person, t: float, dwell: float) -> bool:
        if partner.task.kind != "stand" or partner.task.purpose not in ("dwell", "chat"):
            return False
        i, j = person.index, partner.index
        group_id = partner.task.other if partner.task.purpose == "chat" else ""
        group = self._chats.get(group_id)
        if group is not None and len(group["members"]) >= 2:
            members = [tuple(self.pos[self.people[m].index]) for m in sorted(group["members"])]
            place = join_circle(group["centre"], members, self._out_of_the_way)
            if place is None:
                return False
            centre = group["centre"]
        else:
            found = chat_place(tuple(self.pos[j]), tuple(self.pos[i]), self._out_of_the_way)
            if found is None:
                return False
            place, partner_pose, centre = found
            self._chat_counter += 1
            group_id = f"chat{self._chat_counter}"
            group = {"centre": centre, "members": {partner.spec.name}}
            self._chats[group_id] = group
            partner.task = Task("stand", "chat", (float(self.pos[j, 0]), float(self.pos[j, 1]), partner_pose[2]),
                                until_s=partner.task.until_s, other=group_id)
        group["members"].add(person.spec.name)
        travel = math.hypot(place[0] - self.pos[i, 0], place[1] - self.pos[i, 1]) * DETOUR / person.spec.speed_mps
        until = t + travel + dwell
        self._walk(person, t, place, "chat", other=group_id, until_s=until, look_at=tuple(centre))
        partner.task.until_s = max(partner.task.until_s, until)
        partner.next_check_s = min(partner.next_check_s, t)
        return True

    def _rejoin(self, person: Person, t: float) -> bool:
        """Blocked on the way to a conversation: talk from where one is, if that is a conversation
        distance from the others (the circle's centre moves between them), else give it up."""
        group = self._chats.get(person.task.other)
        i = person.index
        here = self.pos[i]
        others = [self.pos[self.people[m].index] for m in sorted(group["members"]) if m != person.spec.name] \
            if group else []
        if not others or min(math.hypot(*(here - o)) for o in others) > 2 * CHAT_RADIUS_M + 0.8:
            return False
        nearest = min(others, key=lambda o: math.hypot(*(here - o)))
        gap = math.hypot(*(here - nearest))
        if gap < 2 * CHAT_RADIUS_M - 0.3:
            # Pressed against them: step back to a conversation distance on this side.
            away = (here - nearest) / max(gap, 1e-9)
            x, y = nearest + away * 2 * CHAT_RADIUS_M
            if not self._fits(float(x), float(y)):
                return False
            person.task.target = (float(x), float(y), math.atan2(-away[1], -away[0]))
            person.task.look_at = tuple(nearest + away * CHAT_RADIUS_M)
            person.task.route = [(float(x), float(y))]
            person.task.best_m = math.inf
            return True
        centre = tuple(np.mean([here, *others], axis=0))
        group["centre"] = centre
        for name in group["members"]:
            member = self.people[name]
            j = member.index
            facing = math.atan2(centre[1] - self.pos[j, 1], centre[0] - self.pos[j, 0])
            if member is person:
                self._arrive(person, t, (float(here[0]), float(here[1]), facing))
            elif member.task.kind == "stand":
                member.task.target = (member.task.target[0], member.task.target[1], facing)
        return True

    def _leave_chat(self, person: Person) -> None:
        group_id = person.task.other if person.task.purpose == "chat" else ""
        group = self._chats.get(group_id)
        if group is None:
            return
        group["members"].discard(person.spec.name)
        person.task = replace(person.task, purpose="dwell", other="")
        if len(group["members"]) <= 1:
            for name in group["members"]:
                other = self.people[name]
                if other.task.purpose == "chat":
                    other.task = replace(other.task, purpose="dwell", other="")
            del self._chats[group_id]

    def _settled(self, person: Person) -> bool:
        """Standing at their place and turned to face where they should."""
        task = person.task
        turn = wrap_angle(task.target[2] - self.theta[person.index])
        return task.kind == "stand" and abs(turn) < 0.3

    def _group_of(self, person: Person) -> str:
        """The formation a person stands in (the truth the metrics' group intrusions use)."""
        task = person.task
        if not self._settled(person):
            return ""
        if task.purpose == "attend":
            return f"activity/{task.activity}"
        if task.purpose == "chat" and task.other in self._chats and len(self._chats[task.other]["members"]) >= 2:
            settled = [m for m in self._chats[task.other]["members"] if self._settled(self.people[m])]
            return f"chat/{task.other}" if len(settled) >= 2 else ""
        return ""

    # ------------------------------------------------------------------------------------ staff
    def _start_job(self, staff: Person, t: float) -> bool:
        """Go and fetch a resident when it is time (the staff's next job by activity start)."""
        for (activity_id, resident), name in sorted(self._jobs.items(),
                                                    key=lambda kv: self._appointments[kv[0][0]].start_s):
            if name != staff.spec.name or (activity_id, resident) in self._jobs_done:
                continue
            a = self._appointments[activity_id]
            if t >= a.end_s or self.people[resident].task.activity == activity_id:
                self._jobs_done.add((activity_id, resident))
                continue
            if t >= self._fetch_s(staff, activity_id, resident):
                self._leave_chat(staff)
                self._walk(staff, t, self._beside(staff, self.people[resident]), "fetch", activity=activity_id,
                           other=resident)
                staff.task.activity = ""     # not a participant: only fetching
                staff.task.other = f"{resident}|{activity_id}"
                return True
        return False

    def _beside(self, staff: Person, resident: Person) -> tuple[float, float, float]:
        """Where the staff stops to pick a resident up: 0.8 m from them, on the staff's side."""
        rx, ry = self.pos[resident.index]
        sx, sy = self.pos[staff.index]
        a = math.atan2(sy - ry, sx - rx) if math.hypot(sx - rx, sy - ry) > 1e-6 else 0.0
        for turn in (0.0, 0.785, -0.785, 1.571, -1.571, 3.142):
            x, y = rx + 0.8 * math.cos(a + turn), ry + 0.8 * math.sin(a + turn)
            if self._fits(x, y):
                return (x, y, math.atan2(ry - y, rx - x))
        return (float(rx), float(ry), 0.0)

    def _staff_job(self, staff: Person, t: float) -> None:
        task = staff.task
        resident_name, _, activity_id = task.other.partition("|") if task.purpose == "fetch" else (task.other, "", "")
        resident = self.people.get(resident_name)
        if task.purpose == "fetch":
            a = self._appointments.get(activity_id)
            if resident is None or a is None or t >= a.end_s or resident.task.activity == activity_id:
                self._jobs_done.add((activity_id, resident_name))
                self._routine(staff, t)
                return
            target = self._beside(staff, resident)
            if math.hypot(target[0] - task.target[0], target[1] - task.target[1]) > 0.5:
                task.target = target
                self._route(staff)
            self._walking(staff, t)
            if staff.task.kind == "walk" and math.hypot(*(self.pos[staff.index] - self.pos[resident.index])) < 1.0:
                self._pick_up(staff, t)
            return
        # escort: walk beside them until they stand at their place
        if resident is None or resident.task.kind == "stand" or not resident.escorted_to:
            self._routine(staff, t)
            return
        staff.next_check_s = t

    def _pick_up(self, staff: Person, t: float) -> None:
        resident_name, _, activity_id = staff.task.other.partition("|")
        resident = self.people[resident_name]
        self._jobs_done.add((activity_id, resident_name))
        a = self._appointments.get(activity_id)
        if a is None or t >= a.end_s:
            self._routine(staff, t)
            return
        resident.escorted_to = activity_id
        self._leave_chat(resident)
        x, y, th = self._place(a, resident_name)
        thing = self.building.things[a.object]
        self._walk(resident, t, (x, y, th), "attend", activity=activity_id, look_at=(thing.x, thing.y))
        staff.task = Task("walk", "escort", (x, y, th), other=resident_name, progress_s=t)
        self.orca.set_max_speed(staff.index, staff.spec.speed_mps)
        staff.next_check_s = t
