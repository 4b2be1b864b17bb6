"""Recorded people in the crowd (``routine: replay``): present while their record says, walking it.

Why in the crowd and not beside it: replayed people are bodies the others (the simulated people,
the reactive replayed ones) avoid, the simulator's laser sees and the observer tracks, so they are
people of the one ``Crowd`` like anyone else (docs/crowds.md).  Two ways to follow a record:

- **exact** (SocNavBench's replay): at every time the person is where the record, linearly
  interpolated between its annotations, puts them, whatever the robot does.  They are ORCA
  bodies moving at their recorded velocity (the others avoid them), never pushed.
- **reactive**: they appear where the record starts and head along it to its end: their preferred
  velocity points at where the record is ``LOOKAHEAD_S`` later (at the record's end, its last
  point), so they keep its pace and come back to it after a detour, and ORCA makes them avoid the
  robot and the others.  Their speed is bounded by ``MAX_SPEED_MPS``.

People enter when their record starts and leave when it ends (both modes): outside that interval
they are off stage, an ORCA body parked far from everything with speed 0, and ``truth`` says None.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from agents.lib.crowd.model import PersonTruth
from agents.lib.crowd.motion import OFFSTAGE_M, Motion
from agents.lib.crowd.person import Person

LOOKAHEAD_S = 1.0        # reactive: aim at where the record is this much later
MAX_SPEED_MPS = 2.0      # reactive: the fastest a replayed person catches up with their record
STILL_MPS = 0.05         # below this a replayed person keeps the heading they had
BLOCKED_SHARE = 0.3      # reactive: moving at under this share of the wished speed is being blocked ...
KEEP_RIGHT_RAD = 0.6     # ... and a blocked walker turns this much to the right (head-on ORCA deadlocks)


class Replayed:
    """The crowd's ``routine: replay`` people (``Walker.record``, ``Walker.present``)."""

    def __init__(self, people: Sequence[Person], motion: Motion) -> None:
        self.people = list(people)
        self.motion = motion
        self.on_stage: dict[int, bool] = {}
        self.wished: dict[int, tuple[float, float]] = {}    # reactive: the last preferred velocity
        self.blocked: set[int] = set()

    @staticmethod
    def present(person: Person, t: float) -> bool:
        t0, t1 = person.spec.present or (math.inf, -math.inf)
        return t0 - 1e-9 <= t <= t1 + 1e-9

    def busy(self, t0: float, t1: float) -> bool:
        """Someone replayed is on stage during [t0, t1] (the crowd must step, not jump)."""
        return any((p.spec.present or (math.inf, -math.inf))[0] <= t1 and (p.spec.present or (0, -math.inf))[1] >= t0
                   for p in self.people)

    def next_entry_s(self, t: float) -> float:
        """The next time someone enters after ``t`` (the crowd's quiet jump stops there)."""
        return min((p.spec.present[0] for p in self.people if p.spec.present and p.spec.present[0] > t + 1e-9),
                   default=math.inf)

    def stage(self, t: float) -> None:
        """Put everyone where they are at ``t``: on their record's point, or off stage."""
        for person in self.people:
            self._place(person, t, entering=True)
        self.motion.prev = (self.motion.pos.copy(), self.motion.theta.copy(), self.motion.vel.copy())

    def _offstage(self, person: Person) -> None:
        self.motion.offstage(person.index)
        self.on_stage[person.index] = False

    def _place(self, person: Person, t: float, entering: bool) -> None:
        """Before a step at ``t``: the exact ones placed on their record (moving at its velocity),
        the reactive ones given their preferred velocity (placed on the record as they enter)."""
        if not self.present(person, t):
            if self.on_stage.get(person.index, True):
                self._offstage(person)
            return
        assert person.spec.record is not None
        i, orca = person.index, self.motion.orca
        x, y, vx, vy = person.spec.record(t)
        new = entering or not self.on_stage.get(i, False)
        if not person.spec.reactive or new:
            orca.place(i, x, y, vx, vy)
            self.motion.pos[i] = (x, y)
            self.motion.vel[i] = (vx, vy)
            if vx * vx + vy * vy > STILL_MPS ** 2:
                self.motion.theta[i] = math.atan2(vy, vx)
            elif new:
                self.motion.theta[i] = self._heading(person, t)
        self.on_stage[i] = True
        if person.spec.reactive:
            t1 = person.spec.present[1] if person.spec.present else t
            tx, ty, _, _ = person.spec.record(min(t + LOOKAHEAD_S, t1))
            px, py = self.motion.pos[i]
            ahead = max(min(LOOKAHEAD_S, t1 - t), self.motion.step_s)
            wx, wy = (tx - px) / ahead, (ty - py) / ahead
            speed = math.hypot(wx, wy)
            if speed > MAX_SPEED_MPS:
                wx, wy = wx * MAX_SPEED_MPS / speed, wy * MAX_SPEED_MPS / speed
            if i in self.blocked:                      # a symmetric head-on stand-off: keep right, as people do
                c, s_ = math.cos(-KEEP_RIGHT_RAD), math.sin(-KEEP_RIGHT_RAD)
                wx, wy = c * wx - s_ * wy, s_ * wx + c * wy
            self.wished[i] = (wx, wy)
            orca.set_max_speed(i, MAX_SPEED_MPS)
            orca.prefer(i, wx, wy)
        else:
            orca.set_max_speed(i, max(MAX_SPEED_MPS, math.hypot(vx, vy)))
            orca.prefer(i, vx, vy)

    @staticmethod
    def _heading(person: Person, t: float) -> float:
        """A still person's heading: the way their record goes next (or came from)."""
        assert person.spec.record is not None and person.spec.present is not None
        t0, t1 = person.spec.present
        x0, y0, _, _ = person.spec.record(t)
        x1, y1, _, _ = person.spec.record(t1 if t < t1 else t0)
        d = (x1 - x0, y1 - y0) if t < t1 else (x0 - x1, y0 - y1)
        return math.atan2(d[1], d[0]) if math.hypot(*d) > 1e-6 else 0.0

    def before_step(self, t: float) -> None:
        for person in self.people:
            self._place(person, t, entering=False)

    def after_step(self, t1: float) -> None:
        """After ORCA's step to ``t1``: the reactive ones where ORCA took them, the exact ones on
        their record at ``t1`` (held there: they are never pushed)."""
        motion = self.motion
        for person in self.people:
            i = person.index
            if not self.on_stage.get(i, False):
                continue
            if person.spec.reactive:
                x, y = motion.orca.position(i)
                vx, vy = motion.orca.velocity(i)
                wish = math.hypot(*self.wished.get(i, (0.0, 0.0)))
                if wish > 0.2 and math.hypot(vx, vy) < BLOCKED_SHARE * wish:
                    self.blocked.add(i)
                else:
                    self.blocked.discard(i)
            else:
                assert person.spec.record is not None
                x, y, vx, vy = person.spec.record(t1)
                motion.orca.place(i, x, y, vx, vy)
            motion.pos[i] = (x, y)
            motion.vel[i] = (vx, vy)
            if vx * vx + vy * vy > STILL_MPS ** 2:
                motion.theta[i] = math.atan2(vy, vx)

    def truth(self, person: Person, t: float, f: float) -> PersonTruth | None:
        """Where a replayed person is at ``t`` (None: not in the scene).  Exact: the record itself
        (no step grid); reactive: the crowd's state, interpolated as everyone's (``f``)."""
        if not self.present(person, t):
            return None
        spec = person.spec
        assert spec.record is not None
        if spec.reactive and self.motion.prev[0][person.index, 0] < OFFSTAGE_M / 2:
            return PersonTruth(spec.name, spec.role, *self.motion.interpolated(person.index, f))
        x, y, vx, vy = spec.record(t)
        theta = math.atan2(vy, vx) if vx * vx + vy * vy > STILL_MPS ** 2 else self._heading(person, t)
        return PersonTruth(spec.name, spec.role, x, y, theta, vx, vy)
