"""How many restarts an agent may have: N per rolling hour of wall time, not N per run.

Why rolling: a robot that works every day for months will see its fourth crash some day; with a
budget per run, that crash stopped the agent for good.  With N per rolling hour, a crash loop
(an agent that dies at once, again and again) still ends within minutes, while crashes hours
apart are each restarted.  The clock is injected so the window is tested without waiting an hour.
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field

#: the window the budget counts restarts in (wall seconds)
WINDOW_S = 3600.0


@dataclass
class RestartRecord:
    """One restart, for result.json: who, why, and when (wall clock, seconds since the epoch)."""

    agent: str
    reason: str
    at_unix_s: float

    def as_json(self) -> dict[str, object]:
        return {"agent": self.agent, "reason": self.reason, "at_unix_s": round(self.at_unix_s, 3)}


@dataclass
class RestartBudget:
    """``limit`` restarts per agent within any ``window_s`` of wall time (``clock``: monotonic seconds).

    One budget may outlive one supervisor: the week runner hands the same budget to each day's
    launch, so a crash loop late on day 1 still counts early on day 2."""

    limit: int
    window_s: float = WINDOW_S
    clock: Callable[[], float] = time.monotonic
    wall_clock: Callable[[], float] = time.time
    _recent: dict[str, deque[float]] = field(default_factory=dict)
    log: list[RestartRecord] = field(default_factory=list)

    def _window(self, agent: str) -> deque[float]:
        recent = self._recent.setdefault(agent, deque())
        horizon = self.clock() - self.window_s
        while recent and recent[0] <= horizon:
            recent.popleft()
        return recent

    def used(self, agent: str) -> int:
        """Restarts of ``agent`` within the last window."""
        return len(self._window(agent))

    def allows(self, agent: str) -> bool:
        return self.used(agent) < self.limit

    def take(self, agent: str, reason: str) -> int:
        """Count one restart of ``agent`` now (the caller checked ``allows``); the count in the window."""
        recent = self._window(agent)
        recent.append(self.clock())
        self.log.append(RestartRecord(agent=agent, reason=reason, at_unix_s=self.wall_clock()))
        return len(recent)

    def describe(self) -> str:
        hours = self.window_s / 3600.0
        span = "hour" if hours == 1 else f"{hours:g} h"
        return f"{self.limit} per rolling {span}"
