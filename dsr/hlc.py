"""Hybrid logical clock packed into one 64-bit integer.

Why an HLC: last-writer-wins registers need timestamps that (1) respect causality, so a write
made after seeing another always wins over it, and (2) stay close to wall time, so concurrent
writes resolve the way a human would expect.  Packing `(unix_ms << 16) | logical` into one int
keeps the wire format small and comparisons cheap: ints compare like the (ms, logical) tuple.

Rules (docs/dsr_wire_format.md, "Clock"):
- send (local write): ``t = max(pack(now_ms), last + 1)``.  The logical part is 16 bits; when
  more than 65,535 events fall in one millisecond, ``last + 1`` carries into the millisecond
  part, so the clock runs ahead of wall time by the overflow and stays strictly monotonic.
- receive: a message stamped more than the maximum offset (dsr/limits.py,
  ``max_clock_offset_ms``) ahead of our wall clock is dropped whole; otherwise
  ``last = max(last, remote)``.  So no writer, buggy or hostile, can drag the clocks of the
  other replicas more than the maximum offset ahead of real time (HLC paper, epsilon).
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable

from dsr.limits import LIMITS

LOGICAL_BITS = 16
#: Remote timestamps further than this ahead of our wall clock are rejected (a bad or malicious
#: clock would otherwise drag every replica's clock into the future forever).
MAX_OFFSET_MS = LIMITS.max_clock_offset_ms


def pack(wall_ms: int, logical: int = 0) -> int:
    """Pack a wall-clock millisecond value and a logical counter into one HLC value."""
    return (wall_ms << LOGICAL_BITS) | logical


def wall_ms(hlc: int) -> int:
    """Wall-clock part (unix milliseconds) of a packed HLC value."""
    return hlc >> LOGICAL_BITS


def _now_ms() -> int:
    return time.time_ns() // 1_000_000


class HybridLogicalClock:
    """Monotonic HLC: every `tick()` is larger than every value ticked or observed before.

    Thread-safe because the transport's receive thread observes remote clocks while the agent's
    thread ticks for local writes.
    """

    def __init__(self, now_ms: Callable[[], int] = _now_ms,
                 max_offset_ms: int = MAX_OFFSET_MS) -> None:
        self._now_ms = now_ms
        self.max_offset_ms = max_offset_ms
        self._last = 0
        self._lock = threading.Lock()

    @property
    def last(self) -> int:
        return self._last

    def tick(self) -> int:
        """A fresh timestamp for a local event (hot path: nothing but arithmetic)."""
        now_ms = self._now_ms
        with self._lock:
            candidate = (time.time_ns() // 1_000_000 if now_ms is _now_ms else now_ms()) \
                << LOGICAL_BITS
            last = self._last
            self._last = last = candidate if candidate > last else last + 1
            return last

    def observe(self, remote: int) -> None:
        """Merge a remote timestamp so that our next tick orders after it."""
        with self._lock:
            if remote > self._last:
                self._last = remote

    def too_far_ahead(self, remote: int) -> bool:
        """True when `remote` claims a wall time more than the maximum offset beyond ours."""
        return wall_ms(remote) > self._now_ms() + self.max_offset_ms
