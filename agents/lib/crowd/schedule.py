"""The agenda as the people live it: who attends what, where they stand, when they leave.

Why apart from the routines and the motion: an activity's participants, their places around its
object (formations.py), the time each must set off to arrive ``ARRIVE_EARLY_S`` early and which
staff member fetches an escorted resident all follow from the agenda alone (and the resting robot,
which no place may be drawn on).  ``Schedule.read`` recomputes them when the agenda's version
changes; the behaviour (crowd.py, escorts.py) asks ``due`` and ``next_due_s``.
"""

from __future__ import annotations

import math

import numpy as np

from agents.lib.crowd.formations import ring_places, screen_places
from agents.lib.crowd.model import Agenda, Appointment, Building
from agents.lib.crowd.motion import ROBOT_CLEARANCE_M, Motion
from agents.lib.crowd.orca import PARKED
from agents.lib.crowd.person import Person

ARRIVE_EARLY_S = 150.0      # aim to be at an activity this long before it starts (within 5 min)
START_SLACK_S = 20.0        # time to get up and turn at the start of a walk
DETOUR = 1.4                # route length over straight distance, for the departure estimate
ESCORT_WAIT_S = 150.0       # a resident waits this long for the staff who fetches them
ESCORT_BUSY_S = 900.0       # a staff member fetches nobody else within this of a fetch or their own activity
FETCH_EARLY_S = 30.0        # the staff sets off this long before the resident would have to

Place = tuple[float, float, float]


class Schedule:
    """Today's appointments as read from the latest agenda, the places of their participants and
    the escort jobs (``jobs``: (activity, resident) -> staff; ``jobs_done``: fetched or over)."""

    def __init__(self, building: Building, people: dict[str, Person], motion: Motion) -> None:
        self.building = building
        self.people = people
        self.motion = motion
        self.version: object = object()
        self.appointments: dict[str, Appointment] = {}
        self.by_person: dict[str, list[Appointment]] = {}
        self.places: dict[str, list[Place]] = {}
        self.place_points = np.zeros((0, 2))
        self.jobs: dict[tuple[str, str], str] = {}
        self.jobs_done: set[tuple[str, str]] = set()

    def read(self, agenda: Agenda) -> None:
        """Take a new agenda in (nothing when its version is the one read): everyone decides again."""
        if agenda.version == self.version:
            return
        self.version = agenda.version
        self.appointments = {a.id: a for a in agenda.appointments if a.object in self.building.things}
        self.by_person = {}
        for a in sorted(self.appointments.values(), key=lambda a: (a.start_s, a.id)):
            for name in a.participants:
                if name in self.people and self.people[name].spec.dynamic:
                    self.by_person.setdefault(name, []).append(a)
        self.places = {a.id: self.formation(a) for a in self.appointments.values()}
        self._index_places()
        self.jobs = self._escort_jobs()
        for person in self.people.values():
            person.next_check_s = -math.inf

    def _index_places(self) -> None:
        points = [p[:2] for places in self.places.values() for p in places]
        self.place_points = np.asarray(points, dtype=float).reshape(-1, 2)

    def formation(self, a: Appointment) -> list[Place]:
        """The participants' places around the activity's object (a second ring when they are many)."""
        thing = self.building.things[a.object]
        count = len(a.participants)
        fits = self.motion.fits
        if thing.screen:
            places = screen_places(thing.x, thing.y, thing.theta, count, fits)
        else:
            places = ring_places(thing.footprint, count, fits)
        while len(places) < count:   # more participants than places: a second ring, farther out
            extra = ring_places(thing.footprint.buffer(0.7), count - len(places), fits) or \
                [(thing.x + 1.5, thing.y, math.pi)]
            places.extend(extra[: count - len(places)])
        return places

    def place(self, a: Appointment, name: str) -> Place:
        return self.places[a.id][a.participants.index(name)]

    def clear_places_of_robot(self) -> None:
        """The robot came to rest where an activity's formation has a place (it parked by the table
        it was sent to): that formation is drawn again clear of it, and whoever attends walks to their
        new place, so nobody stands inside the robot's intimate distance (Hall's 0.45 m between the
        bodies: ``ROBOT_CLEARANCE_M``), however long the clock then skips."""
        rest = self.motion.robot_parked
        if rest is None or rest == PARKED or not self.places:
            return
        limit = self.motion.robot_radius + ROBOT_CLEARANCE_M
        for aid, places in list(self.places.items()):
            if all(math.hypot(x - rest[0], y - rest[1]) >= limit for x, y, _ in places):
                continue
            a = self.appointments[aid]
            self.places[aid] = new = self.formation(a)
            for old, place, name in zip(places, new, a.participants, strict=False):
                person = self.people.get(name)
                if person is not None and math.hypot(old[0] - place[0], old[1] - place[1]) > 1e-6:
                    if person.task.activity == aid:
                        person.task.activity = ""          # the composer sends them to their new place
                    person.next_check_s = -math.inf
        self._index_places()

    def _escort_jobs(self) -> dict[tuple[str, str], str]:
        """Which staff member fetches which escorted resident to which activity: the first ``staff``
        by name at work then (their ``hours``) who takes part in nothing around then and fetches
        nobody else within 15 min."""
        staff = [p.spec.name for p in self.people.values() if p.spec.routine == "staff"]
        jobs: dict[tuple[str, str], str] = {}
        busy: dict[str, list[float]] = {}
        for a in sorted(self.appointments.values(), key=lambda a: (a.start_s, a.id)):
            for name in a.participants:
                person = self.people.get(name)
                if person is None or not person.spec.escort or not person.spec.dynamic:
                    continue
                for s in sorted(staff):
                    hours = self.people[s].spec.hours
                    if hours is not None and not (hours[0] <= a.start_s - ESCORT_WAIT_S and a.start_s < hours[1]):
                        continue                  # not at work in time to fetch them (their hours)
                    in_activity = any(s in b.participants and b.start_s - ESCORT_BUSY_S < a.start_s < b.end_s
                                      for b in self.appointments.values())
                    if in_activity or any(abs(t - a.start_s) < ESCORT_BUSY_S for t in busy.get(s, [])):
                        continue
                    jobs[(a.id, name)] = s
                    busy.setdefault(s, []).append(a.start_s)
                    break
        return jobs

    def waits_for_escort(self, activity_id: str, name: str) -> bool:
        """``name`` is to be fetched to the activity and has not been yet."""
        return (activity_id, name) in self.jobs and (activity_id, name) not in self.jobs_done

    def travel_s(self, person: Person, x: float, y: float) -> float:
        i = person.index
        distance = math.hypot(x - self.motion.pos[i, 0], y - self.motion.pos[i, 1])
        return DETOUR * distance / person.spec.speed_mps + START_SLACK_S

    def departure_s(self, person: Person, a: Appointment) -> float:
        x, y, _ = self.place(a, person.spec.name)
        return a.start_s - ARRIVE_EARLY_S - self.travel_s(person, x, y)

    def due(self, person: Person, t: float) -> Appointment | None:
        """The activity this person should now be walking to or attending, if any."""
        name = person.spec.name
        for a in self.by_person.get(name, ()):
            if t >= a.end_s:
                continue
            if person.escorted_to == a.id or person.task.activity == a.id:
                return a    # on the way (the estimate shrinks as they walk) or there: until it ends
            leave = self.departure_s(person, a)
            if self.waits_for_escort(a.id, name):
                leave += ESCORT_WAIT_S
            if t >= leave:
                return a
        return None

    def next_due_s(self, person: Person, t: float) -> float:
        """When this (standing) person's next departure for an activity is due."""
        name = person.spec.name
        soonest = math.inf
        for a in self.by_person.get(name, ()):
            if t >= a.end_s:
                continue
            leave = self.departure_s(person, a)
            if self.waits_for_escort(a.id, name):
                leave += ESCORT_WAIT_S
            soonest = min(soonest, leave if leave > t else a.end_s)
        if person.spec.routine == "staff":
            for (activity_id, resident), staff in self.jobs.items():
                if staff == name and (activity_id, resident) not in self.jobs_done:
                    soonest = min(soonest, self.fetch_s(person, activity_id, resident))
        return soonest

    def fetch_s(self, staff: Person, activity_id: str, resident: str) -> float:
        """When ``staff`` sets off to fetch ``resident``: to be with them before they would leave."""
        a = self.appointments[activity_id]
        r = self.people[resident]
        rx, ry = self.motion.pos[r.index]
        return self.departure_s(r, a) - self.travel_s(staff, rx, ry) - FETCH_EARLY_S
