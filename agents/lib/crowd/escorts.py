"""Staff fetching residents marked ``escort`` to their activities, and walking beside them.

Why apart from the schedule and the routines: a fetch is a job with its own course (set off at
``Schedule.fetch_s``, follow the resident as they move, pick them up beside them, walk with them
until they stand at their place) that overrides the staff member's routine and ends in it.
Which staff fetches whom is the schedule's (``Schedule.jobs``); this module carries the jobs out.
"""

from __future__ import annotations

import math

from agents.lib.crowd.model import Building
from agents.lib.crowd.motion import Motion, Pose
from agents.lib.crowd.person import Person, Task
from agents.lib.crowd.routines import Routines
from agents.lib.crowd.schedule import Schedule

BESIDE_M = 0.8              # the staff stops this far from the resident to pick them up
BESIDE_TURNS_RAD = (0.0, 0.785, -0.785, 1.571, -1.571, 3.142)   # ... on their side, else round them
FOLLOW_M = 0.5              # the resident moved this far from the pick-up point: walk to them anew
PICK_UP_M = 1.0             # ... and within this of them the resident comes along


class Escorts:
    """Carries out ``Schedule.jobs``: start a fetch when due, follow, pick up, walk beside."""

    def __init__(self, building: Building, people: dict[str, Person], motion: Motion, schedule: Schedule,
                 routines: Routines) -> None:
        self.building = building
        self.people = people
        self.motion = motion
        self.schedule = schedule
        self.routines = routines

    def start_job(self, staff: Person, t: float) -> bool:
        """Go and fetch a resident when it is time (the staff's next job by activity start)."""
        schedule = self.schedule
        for (activity_id, resident), name in sorted(schedule.jobs.items(),
                                                    key=lambda kv: schedule.appointments[kv[0][0]].start_s):
            if name != staff.spec.name or (activity_id, resident) in schedule.jobs_done:
                continue
            a = schedule.appointments[activity_id]
            if t >= a.end_s or self.people[resident].task.activity == activity_id:
                schedule.jobs_done.add((activity_id, resident))
                continue
            if t >= schedule.fetch_s(staff, activity_id, resident):
                self.routines.leave_chat(staff)
                self.motion.walk(staff, t, self.beside(staff, self.people[resident]), "fetch", activity=activity_id,
                                 other=resident)
                staff.task.activity = ""     # not a participant: only fetching
                staff.task.other = f"{resident}|{activity_id}"
                return True
        return False

    def beside(self, staff: Person, resident: Person) -> Pose:
        """Where the staff stops to pick a resident up: 0.8 m from them, on the staff's side."""
        pos = self.motion.pos
        rx, ry = pos[resident.index]
        sx, sy = pos[staff.index]
        a = math.atan2(sy - ry, sx - rx) if math.hypot(sx - rx, sy - ry) > 1e-6 else 0.0
        for turn in BESIDE_TURNS_RAD:
            x, y = rx + BESIDE_M * math.cos(a + turn), ry + BESIDE_M * math.sin(a + turn)
            if self.motion.fits(x, y):
                return (x, y, math.atan2(ry - y, rx - x))
        return (float(rx), float(ry), 0.0)

    def staff_job(self, staff: Person, t: float) -> None:
        """A staff member on a job decides: follow the resident, pick them up, or back to routine."""
        task = staff.task
        resident_name, _, activity_id = task.other.partition("|") if task.purpose == "fetch" else (task.other, "", "")
        resident = self.people.get(resident_name)
        if task.purpose == "fetch":
            a = self.schedule.appointments.get(activity_id)
            if resident is None or a is None or t >= a.end_s or resident.task.activity == activity_id:
                self.schedule.jobs_done.add((activity_id, resident_name))
                self.routines.routine(staff, t)
                return
            target = self.beside(staff, resident)
            if math.hypot(target[0] - task.target[0], target[1] - task.target[1]) > FOLLOW_M:
                task.target = target
                self.motion.route(staff)
            self.motion.walking(staff, t)
            pos = self.motion.pos
            if staff.task.kind == "walk" and math.hypot(*(pos[staff.index] - pos[resident.index])) < PICK_UP_M:
                self.pick_up(staff, t)
            return
        # escort: walk beside them until they stand at their place
        if resident is None or resident.task.kind == "stand" or not resident.escorted_to:
            self.routines.routine(staff, t)
            return
        staff.next_check_s = t

    def pick_up(self, staff: Person, t: float) -> None:
        """The staff reached the resident: both set off for the activity, the staff beside them."""
        resident_name, _, activity_id = staff.task.other.partition("|")
        resident = self.people[resident_name]
        self.schedule.jobs_done.add((activity_id, resident_name))
        a = self.schedule.appointments.get(activity_id)
        if a is None or t >= a.end_s:
            self.routines.routine(staff, t)
            return
        resident.escorted_to = activity_id
        self.routines.leave_chat(resident)
        x, y, th = self.schedule.place(a, resident_name)
        thing = self.building.things[a.object]
        self.motion.walk(resident, t, (x, y, th), "attend", activity=activity_id, look_at=(thing.x, thing.y))
        staff.task = Task("walk", "escort", (x, y, th), other=resident_name, progress_s=t)
        self.motion.orca.set_max_speed(staff.index, staff.spec.speed_mps)
        staff.next_check_s = t
