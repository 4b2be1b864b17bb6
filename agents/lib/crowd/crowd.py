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

The concerns live beside this module, and ``Crowd`` composes them: ``schedule.py`` (the agenda
read: participants, places, departure times, who fetches whom), ``routines.py`` (each person's
random stream: stays and conversations), ``escorts.py`` (the staff's fetch jobs), ``motion.py``
(bodies, the building's geometry, routes, ORCA, the robot) and ``person.py`` (a person's task).
"""

from __future__ import annotations

import copy
import math
from collections.abc import Callable, Sequence

from agents.lib.crowd.escorts import Escorts
from agents.lib.crowd.model import Agenda, Building, PersonTruth, RobotBody, Walker
from agents.lib.crowd.motion import Motion
from agents.lib.crowd.person import AWAY, FIRST_DECISION, LEAVE, Person, Task, person_rng
from agents.lib.crowd.replay import Replayed
from agents.lib.crowd.routines import Routines
from agents.lib.crowd.schedule import ARRIVE_EARLY_S, Schedule

__all__ = ["ARRIVE_EARLY_S", "STEP_S", "Crowd"]

STEP_S = 0.25              # people's decisions and ORCA steps: 4 Hz of sim time
SCRIPT_VELOCITY_DT_S = 0.05


class Crowd:
    """One simulated day of a scene's people (see the module doc).

    Public surface: ``advance`` (compute up to a time), ``at`` (everyone at a time),
    ``next_event_s`` (the next routine event), ``clone`` and ``t_s``."""

    def __init__(self, building: Building, walkers: Sequence[Walker], *, seed: int, start_s: float,
                 robot_radius_m: float = 0.3, step_s: float = STEP_S) -> None:
        self.seed = int(seed)
        self.start_s = float(start_s)
        self.step_s = step_s
        self.k = 0
        self.walkers = sorted(walkers, key=lambda w: w.name)
        self.people = {w.name: Person(w, i, Task("stand", "dwell" if w.dynamic else "stay", w.pose,
                                                 until_s=self._first_move_s(w)))
                       for i, w in enumerate(self.walkers)}
        self._dynamic = [self.people[w.name] for w in self.walkers if w.dynamic]          # name order
        self._scripted = [self.people[w.name] for w in self.walkers if not w.dynamic and w.moves and w.script]
        self.motion = Motion(building, self.walkers, self.people, step_s=step_s, robot_radius_m=robot_radius_m,
                             start_s=self.start_s)
        self.schedule = Schedule(building, self.people, self.motion)
        self.routines = Routines(self.seed, self.people, self.motion, self.schedule)
        self.escorts = Escorts(building, self.people, self.motion, self.schedule, self.routines)
        self.motion.pick_up = self.escorts.pick_up
        self.motion.rejoin = self.routines.rejoin
        self.replayed = Replayed([self.people[w.name] for w in self.walkers if w.routine == "replay"], self.motion)
        self.replayed.stage(self.start_s)
        for person in self._dynamic:
            hours = person.spec.hours
            if hours is not None and not hours[0] <= self.start_s < hours[1]:
                self._away(person, hours[0] if self.start_s < hours[0] else math.inf)

    def _first_move_s(self, walker: Walker) -> float:
        """People do not all get up at the start of the day: the first stay lasts a part of a dwell."""
        if not walker.dynamic:
            return math.inf
        u = float(person_rng(self.seed, walker.name, FIRST_DECISION).random())
        return self.start_s + u * walker.dwell_s[1]

    def clone(self) -> Crowd:
        """An independent copy in the same state (the offline world's snapshots); it continues
        exactly as this one would."""
        motion = self.motion
        orca, routers = motion.orca, motion.routers
        motion.orca, motion.routers = None, {}  # type: ignore[assignment]  # ORCA cloned, routers shared
        try:
            twin = copy.deepcopy(self)
        finally:
            motion.orca, motion.routers = orca, routers
        twin.motion.orca = orca.clone()
        twin.motion.routers = routers         # immutable once built: shared
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
        chat ends, an activity calls them), a scripted walk starts or a recorded person enters; inf when
        none is known.
        Why: the simulator's idle skip stops there, so the DSR shows each event at its time."""
        times = [p.next_check_s for p in self._dynamic if p.task.kind == "stand" and p.next_check_s > t_s + 1e-9]
        times += [s for s in self._leave_times() if s > t_s + 1e-9]
        times += [t0 for p in self._scripted for t0, _ in p.spec.moves if t0 > t_s + 1e-9]
        times.append(self.replayed.next_entry_s(t_s))
        return min(times)

    def at(self, t_s: float) -> tuple[PersonTruth, ...]:
        """Everyone at ``t_s`` in [t - step, t] of the latest state, linearly interpolated."""
        t1 = self.t_s
        f = 1.0 if t1 - t_s <= 1e-9 else max(0.0, 1.0 - (t1 - t_s) / self.step_s)
        out = []
        for w in self.walkers:
            person = self.people[w.name]
            if w.routine == "replay":
                truth = self.replayed.truth(person, t_s, f)
                if truth is not None:       # None: not in the scene at this time (the record says)
                    out.append(truth)
                continue
            if not w.dynamic:
                out.append(self._scripted_truth(w, t_s))
                continue
            if person.task.purpose == AWAY:
                continue                    # not in the building (outside their hours)
            out.append(PersonTruth(w.name, w.role, *self.motion.interpolated(person.index, f),
                                   self.routines.group_of(person), person.task.activity or person.escorted_to))
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

    # ------------------------------------------------------------------------------------ step
    def _step(self, agenda_at: Callable[[float], Agenda], robot: RobotBody | None, until_s: float) -> None:
        t = self.t_s
        motion = self.motion
        if (robot is None or not robot.driving) and motion.park(robot):
            # first: the places people choose on this step keep clear of it
            self.schedule.clear_places_of_robot()
        agenda = agenda_at(t)
        motion.doors(agenda.closed_doors)
        self.schedule.read(agenda)
        for person in self._dynamic:
            if person.task.kind == "walk" or t >= person.next_check_s or self._time_to_leave(person, t):
                self._decide(person, t)
        walking = [p for p in self._dynamic if p.task.kind == "walk"]
        scripted_moving = [p for p in self._scripted
                           if any(t0 - self.step_s < t < t1 + self.step_s for t0, t1 in p.spec.moves)]
        standing = [p for p in self._dynamic if p.task.kind == "stand" and p.task.purpose != AWAY]
        turning = motion.turning(standing)
        t1 = self.start_s + (self.k + 1) * self.step_s
        if not walking and not scripted_moving and not turning and (robot is None or not robot.driving) \
                and not self.replayed.busy(t, t1):
            self._quiet_jump(t, agenda, until_s)
            return
        self.replayed.before_step(t)
        motion.step(t, t1, walking, scripted_moving, turning, standing, self._scripted, robot)
        self.replayed.after_step(t1)
        self.k += 1

    def _quiet_jump(self, t: float, agenda: Agenda, until_s: float) -> None:
        """Nobody moves: jump to the step where the next decision is due (or the caller's time)."""
        due = min([p.next_check_s for p in self._dynamic] + [agenda.next_change_s, self.replayed.next_entry_s(t)]
                  + [s for s in self._leave_times() if s > t])
        for person in self._scripted:
            for t0, _ in person.spec.moves:
                if t0 > t:
                    due = min(due, t0)
        target = min(due, until_s)
        steps = max(1, math.ceil((target - self.start_s) / self.step_s - 1e-9) - self.k)
        self.motion.quiet()
        self.k += steps

    # ------------------------------------------------------------------------------------ hours
    def _leave_times(self) -> list[float]:
        """When the people in the building with ``hours`` are due to set off for the way out."""
        return [p.spec.hours[1] for p in self._dynamic
                if p.spec.hours is not None and p.task.purpose not in (AWAY, LEAVE)]

    def _time_to_leave(self, person: Person, t: float) -> bool:
        hours = person.spec.hours
        return hours is not None and t >= hours[1] and person.task.purpose not in (AWAY, LEAVE)

    def _away(self, person: Person, back_s: float) -> None:
        """Out of the building until ``back_s`` (inf: gone for the day)."""
        self.motion.offstage(person.index)
        person.task = Task("stand", AWAY, person.spec.pose)
        person.escorted_to = ""
        person.next_check_s = back_s

    def _hours(self, person: Person, t: float) -> bool:
        """Arrive at the start of one's hours (at one's scene pose, the way in), walk back there at
        their end and leave; True when that was this step's decision."""
        assert person.spec.hours is not None
        arrive_s, leave_s = person.spec.hours
        task = person.task
        if task.purpose == AWAY:
            if not arrive_s <= t < leave_s:
                person.next_check_s = arrive_s if t < arrive_s else math.inf
                return True
            self.motion.onstage(person.index, person.spec.pose)
            person.task = Task("stand", "dwell", person.spec.pose, until_s=t)   # the routine decides at once
            return False
        if t < leave_s:
            return False
        if task.purpose != LEAVE:
            self.routines.leave_chat(person)
            person.escorted_to = ""
            self.motion.walk(person, t, person.spec.pose, LEAVE)
            return True
        if task.kind == "walk":
            self.motion.walking(person, t)
            if person.task.kind == "walk":
                return True
        self._away(person, math.inf)            # at the way out (or as near as they got): gone
        return True

    # ------------------------------------------------------------------------------------ behaviour
    def _decide(self, person: Person, t: float) -> None:
        """Their hours first, then the agenda, then a staff member's job, then the routine (see the
        module doc)."""
        if person.spec.hours is not None and self._hours(person, t):
            return
        task = person.task
        due = self.schedule.due(person, t)
        if person.spec.routine == "staff" and task.purpose in ("fetch", "escort") and due is None:
            self.escorts.staff_job(person, t)
            return
        if due is not None:
            if task.activity != due.id:
                self.routines.leave_chat(person)
                x, y, th = self.schedule.place(due, person.spec.name)
                thing = self.schedule.building.things[due.object]
                self.motion.walk(person, t, (x, y, th), "attend", activity=due.id, look_at=(thing.x, thing.y))
            elif task.kind == "walk":
                self.motion.walking(person, t)
            person.next_check_s = due.end_s if person.task.kind == "stand" else t
            return
        if task.purpose == "attend":
            person.escorted_to = ""
            self.routines.routine(person, t)
            return
        if person.spec.routine == "staff" and self.escorts.start_job(person, t):
            return
        if task.kind == "walk":
            self.motion.walking(person, t)
            if person.task.kind == "walk":
                return
        if t >= person.task.until_s:
            self.routines.routine(person, t)
            return
        person.next_check_s = min(person.task.until_s, self.schedule.next_due_s(person, t))
