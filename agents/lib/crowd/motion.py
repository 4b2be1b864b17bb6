"""How the simulated people move: their bodies, the building they walk in, and ORCA.

Why apart from the behaviour (crowd.py, routines.py, escorts.py, schedule.py): walking to a pose
(route through door gaps, preferred velocity, progress and getting stuck), turning on the spot,
the robot as a moving body or a resting obstacle and where a body can stand are the same whoever
decided where to go.  The behaviour hands a person a target (``walk``); ``Motion`` takes them
there.  Two events go back to the behaviour, through the hooks the composer sets: a staff member
reached the resident they fetch (``pick_up``), and a walker stuck on the way to a conversation
may talk from where they are (``rejoin``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import cast

import numpy as np
import shapely
from shapely.geometry.polygon import orient

from agents.lib.crowd.model import Building, RobotBody, Walker
from agents.lib.crowd.orca import PARKED, Orca
from agents.lib.crowd.person import Person, Task
from agents.lib.crowd.routes import NoRoute, Router
from scenes.angles import wrap_angle

STUCK_S = 8.0               # no progress for this long: replan, or settle when close
SETTLE_M = 0.8              # ... close means this near the goal
WAYPOINT_REACHED_M = 0.35
TURN_RATE_RADPS = 3.0
SPOT_CORNER_M = 0.9         # a place to stand keeps off the corners routes turn at (where others will walk)
SIDESTEP_RAD = 0.9          # a walker blocked for half of STUCK_S steps this much to a side
ROBOT_MARGIN_M = 0.1        # people give the robot this much more than its body
ROBOT_CLEARANCE_M = 0.6     # nobody picks a place to stand nearer the resting robot's body than this
BODY_CLEARANCE_M = 0.3      # a body stands at least this far from walls and furniture
OFFSTAGE_M = 1.0e6          # where the bodies of people not in the building wait (nobody's neighbour)

Pose = tuple[float, float, float]


def _no_pick_up(staff: Person, t: float) -> None:
    raise RuntimeError("Motion.pick_up not set: the composer (crowd.py) wires the escorts in")


def _no_rejoin(person: Person, t: float) -> bool:
    return False


class Motion:
    """Everyone's pose, velocity and ORCA body (index = the walker's place in name order; the robot
    last), the building's geometry, and walking to a target."""

    def __init__(self, building: Building, walkers: Sequence[Walker], people: dict[str, Person], *,
                 step_s: float, robot_radius_m: float, start_s: float) -> None:
        self.building = building
        self.people = people
        self.step_s = step_s
        n = len(walkers)
        self.pos = np.array([w.pose[:2] for w in walkers], dtype=float).reshape(n, 2)
        self.theta = np.array([w.pose[2] for w in walkers], dtype=float)
        self.vel = np.zeros((n, 2))
        self.prev = (self.pos.copy(), self.theta.copy(), self.vel.copy())
        self.robot_index = n
        self.robot_parked: tuple[float, float] | None = PARKED   # where the resting robot stands (None: it drives)
        self.robot_radius = robot_radius_m + ROBOT_MARGIN_M
        self.closed: frozenset[str] = frozenset()
        self.routers: dict[frozenset[str], Router] = {}   # immutable once built: clones share them
        self.room_polys = {name: poly for name, poly in building.rooms.items()}
        for poly in self.room_polys.values():
            shapely.prepare(poly)
        self.building_poly = shapely.union_all(list(building.rooms.values()))
        footprints = [t.footprint for t in building.things.values()]
        self.footprints = shapely.union_all(footprints) if footprints else shapely.GeometryCollection()
        self.wall_lines = shapely.MultiLineString([list(w) for w in building.walls if len(w) >= 2])
        shapely.prepare(self.footprints)
        shapely.prepare(self.wall_lines)
        self.door_xy = np.array(list(building.doors.values()), dtype=float).reshape(-1, 2)
        radii = [w.radius_m for w in walkers] + [self.robot_radius]
        positions = np.vstack([self.pos, [PARKED]])
        self.orca = Orca(step_s, self.obstacles(frozenset()), radii, positions)
        for person in people.values():
            if not person.spec.dynamic and person.spec.script is not None:
                x, y, th = person.spec.script(start_s)
                self.pos[person.index] = (x, y)
                self.theta[person.index] = th
        self.sync_positions(range(n))
        self.prev = (self.pos.copy(), self.theta.copy(), self.vel.copy())
        #: behaviour hooks, set by the composer
        self.pick_up: Callable[[Person, float], None] = _no_pick_up
        self.rejoin: Callable[[Person, float], bool] = _no_rejoin

    # ------------------------------------------------------------------------------------ geometry
    def obstacles(self, closed: frozenset[str]) -> list[list[tuple[float, float]]]:
        obstacles: list[list[tuple[float, float]]] = [
            [cast(tuple[float, float], tuple(a)), cast(tuple[float, float], tuple(b))]
            for w in self.building.walls for a, b in zip(w, w[1:], strict=False) if tuple(a) != tuple(b)]
        for thing in self.building.things.values():
            ring = orient(thing.footprint, 1.0).exterior.coords[:-1]   # RVO2 wants counter-clockwise
            obstacles.append([(c[0], c[1]) for c in ring])
        for name in sorted(closed):
            leaf = self.building.door_leaves.get(name)
            if leaf is not None:
                obstacles.append([(leaf[0][0], leaf[0][1]), (leaf[1][0], leaf[1][1])])
        return obstacles

    @property
    def router(self) -> Router:
        """Routes with the doors closed now (built once per set of closed doors, then shared)."""
        if self.closed not in self.routers:
            walls = [*self.building.walls, *(list(self.building.door_leaves[d]) for d in sorted(self.closed)
                                             if d in self.building.door_leaves)]
            self.routers[self.closed] = Router.build(self.building_poly, walls,
                                                      [t.footprint for t in self.building.things.values()])
        return self.routers[self.closed]

    def room_of(self, x: float, y: float) -> str | None:
        for name, poly in self.room_polys.items():
            if shapely.intersects_xy(poly, x, y):
                return name
        return None

    def out_of_the_way(self, x: float, y: float) -> bool:
        """A body fits at (x, y) and does not stand where routes turn (a chat or a rest place)."""
        if not self.fits(x, y):
            return False
        corners = self.router.graphs[0].corners
        return not len(corners) or float(np.min(np.hypot(*(corners - (x, y)).T))) >= SPOT_CORNER_M

    def clear_of_robot(self, x: float, y: float) -> bool:
        """(x, y) is at least ``ROBOT_CLEARANCE_M`` from the resting robot's body (or it drives)."""
        rest = self.robot_parked
        return rest is None or math.hypot(x - rest[0], y - rest[1]) >= self.robot_radius + ROBOT_CLEARANCE_M

    def fits(self, x: float, y: float) -> bool:
        """A body can stand at (x, y): in the building, clear of walls, furniture and the resting robot."""
        rest = self.robot_parked
        if rest is not None and math.hypot(x - rest[0], y - rest[1]) < self.robot_radius + ROBOT_CLEARANCE_M:
            return False
        return bool(shapely.contains_xy(self.building_poly, x, y)
                    and self.wall_lines.distance(shapely.Point(x, y)) >= BODY_CLEARANCE_M
                    and self.footprints.distance(shapely.Point(x, y)) >= BODY_CLEARANCE_M)

    # ------------------------------------------------------------------------------------ world
    def park(self, robot: RobotBody | None) -> bool:
        """The robot at rest is furniture to the people: an obstacle ORCA walkers go round (max speed
        0), and no one chooses to stand where it is.  ``None``: no robot in this world.  True when
        it came to rest somewhere new (the places people stand at are then drawn again)."""
        rest = PARKED if robot is None else (robot.x, robot.y)
        if rest == self.robot_parked:
            return False
        self.orca.place(self.robot_index, *rest)
        self.orca.set_max_speed(self.robot_index, 0.0)
        self.orca.prefer(self.robot_index, 0.0, 0.0)
        self.robot_parked = rest
        return True

    def doors(self, closed_doors: frozenset[str]) -> None:
        """Closed door leaves are walls from now on: everyone on the way replans on this step."""
        if closed_doors != self.closed:
            self.closed = closed_doors
            self.orca.set_obstacles(self.obstacles(closed_doors))
            for person in self.people.values():
                if person.task.kind == "walk":
                    person.task.route = []          # replanned on this step

    def sync_positions(self, indices: Sequence[int] | range) -> None:
        """Mirror RVO2's float32 positions (what the next step starts from) after placing agents."""
        for i in indices:
            self.orca.place(i, float(self.pos[i, 0]), float(self.pos[i, 1]))
            self.pos[i] = self.orca.position(i)

    # ------------------------------------------------------------------------------------ walking
    def offstage(self, i: int) -> None:
        """Body ``i`` out of the building: parked far from everything, still (nobody's neighbour)."""
        x, y = OFFSTAGE_M + 10.0 * i, OFFSTAGE_M
        self.orca.place(i, x, y)
        self.orca.set_max_speed(i, 0.0)
        self.orca.prefer(i, 0.0, 0.0)
        self.pos[i] = (x, y)
        self.vel[i] = (0.0, 0.0)

    def onstage(self, i: int, pose: Pose) -> None:
        """Body ``i`` comes in, standing at ``pose`` (its previous state too: no slide in from afar)."""
        x, y, theta = pose
        self.orca.place(i, x, y)
        self.orca.set_max_speed(i, 0.0)
        self.orca.prefer(i, 0.0, 0.0)
        self.pos[i] = (x, y)
        self.theta[i] = theta
        self.vel[i] = (0.0, 0.0)
        for array, value in zip(self.prev, ((x, y), theta, (0.0, 0.0)), strict=True):
            array[i] = value

    def walk(self, person: Person, t: float, target: Pose, purpose: str, activity: str = "", other: str = "",
             until_s: float = math.inf, look_at: tuple[float, float] | None = None) -> None:
        """``person`` sets off for ``target`` now (routed through door gaps and round furniture)."""
        person.task = Task("walk", purpose, target, until_s=until_s, activity=activity, other=other,
                           progress_s=t, look_at=look_at)
        self.route(person)
        self.orca.set_max_speed(person.index, person.spec.speed_mps)
        person.next_check_s = t

    def route(self, person: Person) -> None:
        i = person.index
        start = (float(self.pos[i, 0]), float(self.pos[i, 1]))
        goal = person.task.target[:2]
        try:
            person.task.route, _ = self.router.route(start, goal)
        except NoRoute:
            person.task.route = [goal]    # ORCA will get as close as walls allow; settles when stuck

    def walking(self, person: Person, t: float) -> None:
        """Arrived, stuck, or on the way."""
        task = person.task
        i = person.index
        x, y = self.pos[i]
        gx, gy, gth = task.target
        distance = math.hypot(gx - x, gy - y)
        if distance < 0.02:
            self.arrive(person, t, (gx, gy, gth))
            return
        if distance < task.best_m - 0.1:
            task.best_m, task.progress_s = distance, t
        elif t - task.progress_s > STUCK_S:
            task.progress_s = t
            task.replans += 1
            if task.purpose == "chat" and self.rejoin(person, t):
                return
            if (distance < SETTLE_M or (task.replans > 3 and task.purpose not in ("attend", "fetch"))) \
                    and self.clear_of_robot(float(x), float(y)):     # never settle in the robot's intimate distance
                facing = gth if task.look_at is None else math.atan2(task.look_at[1] - y, task.look_at[0] - x)
                self.arrive(person, t, (float(x), float(y), facing))
                return
            self.route(person)
        if not task.route:
            self.route(person)

    def arrive(self, person: Person, t: float, pose: Pose) -> None:
        """Stop at ``pose`` and stand there (a staff member who fetches picks the resident up)."""
        i = person.index
        task = person.task
        self.orca.set_max_speed(i, 0.0)
        self.pos[i] = pose[:2]
        self.sync_positions([i])
        self.vel[i] = (0.0, 0.0)
        if task.purpose == "fetch":
            self.pick_up(person, t)
            return
        person.task = Task("stand", task.purpose, pose, until_s=task.until_s, activity=task.activity, other=task.other)
        if task.purpose == "attend":
            person.escorted_to = ""
        person.next_check_s = t

    def prefer(self, person: Person, t: float) -> None:
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

    # ------------------------------------------------------------------------------------ one step
    def turning(self, standing: Sequence[Person]) -> list[Person]:
        """Who of ``standing`` still turns to face where they should."""
        want = np.array([p.task.target[2] for p in standing])
        have = self.theta[[p.index for p in standing]] if standing else np.zeros(0)
        off = np.abs(wrap_angle(want - have)) > 1e-6
        return [p for p, o in zip(standing, off, strict=True) if o] if off.any() else []

    def quiet(self) -> None:
        """Nobody moves over the coming stretch: everyone's velocity is zero."""
        self.vel[:] = 0.0
        self.prev = (self.pos.copy(), self.theta.copy(), self.vel.copy())

    def step(self, t: float, t1: float, walking: Sequence[Person], scripted_moving: Sequence[Person],
             turning: Sequence[Person], standing: Sequence[Person], scripted: Sequence[Person],
             robot: RobotBody | None) -> None:
        """One ORCA step from ``t`` to ``t1``: the walkers toward their waypoints, scripted people
        along their scripts, the driving robot as a moving body, standing people turning."""
        self.prev = (self.pos.copy(), self.theta.copy(), self.vel.copy())
        for person in walking:
            self.prefer(person, t)
        for person in scripted_moving:
            script = _script_of(person)
            x0, y0, _ = script(t)
            x1, y1, _ = script(t + self.step_s)
            vx, vy = (x1 - x0) / self.step_s, (y1 - y0) / self.step_s
            self.orca.place(person.index, x0, y0, vx, vy)
            self.orca.set_max_speed(person.index, max(2.0, math.hypot(vx, vy)))
            self.orca.prefer(person.index, vx, vy)
        if robot is not None and robot.driving:
            self.orca.place(self.robot_index, robot.x, robot.y, robot.vx, robot.vy)
            self.orca.set_max_speed(self.robot_index, max(2.0, math.hypot(robot.vx, robot.vy)))
            self.orca.prefer(self.robot_index, robot.vx, robot.vy)
            self.robot_parked = None
        self.orca.step()
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
            script = _script_of(person)
            x, y, th = script(t1)
            x0, y0, _ = script(t)
            self.orca.place(i, x, y, 0.0, 0.0)
            self.orca.set_max_speed(i, 0.0)
            self.sync_positions([i])
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
        for person in scripted:
            if person not in scripted_moving:
                self.vel[person.index] = (0.0, 0.0)

    def interpolated(self, i: int, f: float) -> tuple[float, float, float, float, float]:
        """Body ``i`` a fraction ``f`` of the way from the previous state to the latest: x, y, theta, vx, vy."""
        p0, th0, _ = self.prev
        x = float(p0[i, 0] + f * (self.pos[i, 0] - p0[i, 0]))
        y = float(p0[i, 1] + f * (self.pos[i, 1] - p0[i, 1]))
        dth = wrap_angle(self.theta[i] - th0[i])
        theta = wrap_angle(th0[i] + f * dth)
        return x, y, float(theta), float(self.vel[i, 0]), float(self.vel[i, 1])


def _script_of(person: Person) -> Callable[[float], Pose]:
    """The pose-at-t script of a scripted (``stay``) person, who always has one."""
    script = person.spec.script
    if script is None:
        raise ValueError(f"{person.spec.name} is scripted but has no script")
    return script
