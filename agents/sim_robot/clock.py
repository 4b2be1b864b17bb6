"""How far the simulator's clock may move on, given the wall clock: the pace of each clock mode.

Why a class of its own: the simulator decides *which* mode the clock is in from the DSR (a
navigation drives, agents plan, nothing is due, the day has not started; agents/sim_robot/agent.py),
but *how fast* each mode runs is plain arithmetic over two anchors, the wall and sim times at the
last mode change.  Kept apart, that arithmetic is one small thing a test can drive with made-up
wall times, and the reasons for each pace are written down once:

- **driving** (lockstep with the controller): a ``control_dt`` step at a time, never faster than
  ``rate`` sim seconds per wall second, so a fast machine does not outrun the scene's rate.
- **busy** (agents plan, or a due mission is being started): ``busy_rate``, at most one
  ``control_dt`` per step; ``busy_rate=0`` holds the clock until they are done, so the sim times
  of a run do not depend on how fast this machine plans (``chronav evaluate``).
- **idle** (nothing to do): with ``skip_idle`` the clock jumps to the next deadline, in pieces of at
  most ``MAX_SKIP_S`` that end at each scheduled event (the people walk through every skipped
  second, the loop beats its heartbeat between pieces, an event fires on time); without it, it
  runs at ``rate`` (``busy_rate`` when a mission is due), at most 5 s and never past the next event
  per step.
- **external** (``--robot ros``): real time, whatever ``rate`` says: a real robot moves in real
  seconds.  Steps shorter than ``control_dt`` wait; one step is at most 1 s.

Days, not nights: one run is one day; a multi-day run (tools/week.py) is a run per day, so the
nights are skipped between runs, not by this clock.
"""

from __future__ import annotations

from dataclasses import dataclass

MAX_SKIP_S = 900.0          # an idle skip moves the clock at most this far per loop
IDLE_STEP_MAX_S = 5.0       # an idle clock without skips moves at most this far per loop
EXTERNAL_STEP_MAX_S = 1.0   # real time (--robot ros): at most this far per loop, after a stall
MIN_EVENT_STEP_S = 1e-3     # an idle step that reaches an event due now still moves a little


@dataclass
class ClockPace:
    """The pace of each clock mode from the wall and sim times of the last re-anchor (a mode change
    or a skip).  Every method takes the current wall time and sim time and returns how far the sim
    clock may go; none of them moves it (the simulator does, with the people and the robot)."""

    rate: float              # sim s per wall s while driving and idle (the scene's clock.rate, -o rate)
    busy_rate: float         # sim s per wall s while agents plan or a due mission starts (0: hold)
    control_dt: float        # the controller's step (s)
    skip_idle: bool          # the scene's clock.skip_idle: jump over idle time
    wall_anchor: float = 0.0
    sim_anchor: float = 0.0

    def reanchor(self, wall_now: float, sim_now: float) -> None:
        """Count the pace from here (a mode change, a skip): time spent in another mode is not owed."""
        self.wall_anchor, self.sim_anchor = wall_now, sim_now

    def _owed(self, wall_now: float, sim_now: float, rate: float) -> float:
        """Sim seconds the clock is behind ``rate`` since the anchor (negative: ahead)."""
        return (wall_now - self.wall_anchor) * rate - (sim_now - self.sim_anchor)

    def driving_allows(self, wall_now: float, sim_now: float) -> bool:
        """May the lockstep take its next ``control_dt`` step without running ahead of ``rate``?"""
        return (sim_now + self.control_dt - self.sim_anchor) <= (wall_now - self.wall_anchor) * self.rate + self.control_dt

    def busy_step(self, wall_now: float, sim_now: float) -> float:
        """How far the clock moves while agents plan: at ``busy_rate``, at most ``control_dt`` (0: not yet)."""
        return min(self.control_dt, max(0.0, self._owed(wall_now, sim_now, self.busy_rate)))

    def idle_skip(self, sim_now: float, deadline: float | None, end_s: float, next_event_s: float) -> float | None:
        """Where an idle clock jumps to: the next deadline, cut at the day's end, at ``MAX_SKIP_S``
        and at the next scheduled event; None when it does not skip (no ``skip_idle``, or nothing
        is due later)."""
        if not self.skip_idle or deadline is None or deadline <= sim_now:
            return None
        return min(deadline, end_s, sim_now + MAX_SKIP_S, next_event_s)

    def idle_step(self, wall_now: float, sim_now: float, mission_due: bool, next_event_s: float) -> float:
        """How far an idle clock that does not skip moves: at ``rate`` (``busy_rate`` while a due
        mission is being started), at most ``IDLE_STEP_MAX_S``, up to the next event; 0: not yet."""
        owed = self._owed(wall_now, sim_now, self.busy_rate if mission_due else self.rate)
        if owed <= 0:
            return 0.0
        return min(owed, IDLE_STEP_MAX_S, max(next_event_s - sim_now, MIN_EVENT_STEP_S))

    def external_step(self, wall_now: float, sim_now: float) -> float:
        """How far the clock moves with a ROS robot: real time, in steps of at least ``control_dt``
        (0: not yet) and at most ``EXTERNAL_STEP_MAX_S``."""
        owed = self._owed(wall_now, sim_now, 1.0)
        return 0.0 if owed < self.control_dt else min(owed, EXTERNAL_STEP_MAX_S)
