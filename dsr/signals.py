"""Change signals queued by any thread and delivered on the agent's own thread.

Why a queue: replication merges remote deltas on the replica's receiver thread
(dsr/receiver.py) while holding the graph lock; running agent callbacks there would let agent
code block replication or re-enter the graph under the lock.  Instead events are queued and
`dispatch()` (called from the agent's loop) runs the callbacks with no lock held.  Events are
only queued for signals that have at least one callback, so a replica nobody listens to does
not accumulate memory.

Why dispatch() polls a little before it sleeps (SpinPolicy): a thread that sleeps between two
messages is woken by the kernel tens of microseconds later, and on a virtual machine the idle
core it runs on must be woken too.  In a request/answer exchange between agents that wake-up,
twice per round trip, cost more than decoding and merging the delta, and polling brings the
DSR round trip closer to bare Zenoh's, more so once the polling thread also takes the deltas
off the replica's channel itself (below; the numbers: docs/performance.md).
Polling only starts when changes arrive densely (the previous one came within the window),
yields the core to any other runnable thread while it waits, and its CPU time is capped
(`max_share_pct` of one core), so an agent that hears a few changes a second never polls and
one that hears a stream pays at most that share.  CHRONAV_DSR_SPIN_US=0 turns it off (a
battery-powered host that prefers idle cores to latency).

Why the polling thread receives: even a polling dispatch() paid for hand-overs.  Zenoh's
callback thread decoded, checked and merged a delta (holding the GIL all along), posted the
event, finished its bookkeeping and returned; only then could the polling thread, asleep on
the GIL by that time, be woken to run the callback, which cost more than the decode and merge
(docs/performance.md).  So while dispatch() polls, it takes the received deltas itself from a poll source
(`receive_from`; dsr/receiver.py: the replica's Zenoh channel), decodes, checks and merges
them, in arrival order, and goes straight on to the callbacks.  Whoever handles a delta runs
the same code (dsr/transport.py), so nothing but the thread changes; when nobody polls (an
agent busy in a callback, or one that never dispatches), the replica's receiver thread
handles its deltas.  Agent callbacks never run on a receiving thread.
"""

from __future__ import annotations

import logging
import os
import queue
import threading
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, Protocol

from dsr.errors import ConfigError

SIGNALS: tuple[str, ...] = ("node_added", "node_updated", "node_deleted",
                            "edge_added", "edge_updated", "edge_deleted")
Event = tuple[str, tuple[Any, ...]]
log = logging.getLogger(__name__)

ENV_SPIN_US = "CHRONAV_DSR_SPIN_US"
ENV_SPIN_SHARE = "CHRONAV_DSR_SPIN_SHARE_PCT"


@dataclass(frozen=True, slots=True)
class SpinPolicy:
    """How long dispatch() polls for a change before it sleeps, and the CPU that may cost.

    window_us: poll up to this long, and only while changes come at most this far apart
    (0 = never poll).  max_share_pct: polling may use at most this percent of one core on
    average (0 = never poll); a credit of `burst_ms` x that share lets a short exchange poll
    throughout, and once it is spent dispatch() sleeps at once until it refills.
    """

    window_us: int = 1000
    max_share_pct: int = 25
    burst_ms: int = 1000

    @classmethod
    def from_env(cls, environ: Mapping[str, str] | None = None) -> SpinPolicy:
        """Defaults overridden by CHRONAV_DSR_SPIN_US / CHRONAV_DSR_SPIN_SHARE_PCT."""
        env = os.environ if environ is None else environ
        values: dict[str, int] = {}
        for name, var, most in (("window_us", ENV_SPIN_US, 100_000),
                                ("max_share_pct", ENV_SPIN_SHARE, 100)):
            text = (env.get(var) or "").strip()
            if not text:
                continue
            if not text.isdigit() or int(text) > most:
                raise ConfigError(f"{var}={text!r}: expected a whole number from 0 to {most}")
            values[name] = int(text)
        return cls(**values)


class PollSource(Protocol):
    """Received deltas a polling dispatch() may handle itself (dsr/receiver.py)."""

    def poll_begin(self) -> None: ...

    def poll_take(self) -> bool:
        """Handle the next waiting delta, if this thread may; True if it did."""

    def poll_end(self, idle: bool) -> None:
        """The poll is over; idle: nothing came and the thread goes to sleep."""


class SignalHub:
    def __init__(self, spin: SpinPolicy | None = None) -> None:
        self._callbacks: dict[str, tuple[Callable[..., Any], ...]] = {s: () for s in SIGNALS}
        self._queue: queue.SimpleQueue[list[Event]] = queue.SimpleQueue()
        # Why a lock to wait on, not SimpleQueue.get(timeout=): on CPython 3.11 a get whose
        # wait is interrupted by a signal may then wait forever (measured: 1 run in 7 with a
        # signal every 14 ms), so an agent hit by SIGTERM in dispatch() hung until the next
        # DSR change and was SIGKILLed, its recording left without a footer.  A lock's timed
        # acquire runs the handlers and waits out the rest of its timeout.
        self._wake = threading.Lock()
        self._wake.acquire()                 # held while nothing is posted
        self.callback_errors = 0
        self.spin = SpinPolicy.from_env() if spin is None else spin
        self._window_s = self.spin.window_us / 1e6 if self.spin.max_share_pct else 0.0
        self._credit_cap_s = self.spin.burst_ms / 1e3 * self.spin.max_share_pct / 100
        self._credit_s = self._credit_cap_s     # polling time this process may still spend
        self._credit_at = time.perf_counter()
        self._dense = False                     # did the last change come within the window?
        #: polls that found a change / that gave up and slept; seconds spent polling
        self.spin_hits = 0
        self.spin_misses = 0
        self.spin_s = 0.0
        self._source: PollSource | None = None

    def receive_from(self, source: PollSource | None) -> None:
        """While dispatch() polls, let it handle what `source` received (None detaches)."""
        self._source = source

    def connect(self, signal: str, callback: Callable[..., Any]) -> None:
        if signal not in self._callbacks:
            raise ValueError(f"unknown signal {signal!r}; expected one of {', '.join(SIGNALS)}")
        if not callable(callback):
            raise TypeError(f"callback for {signal!r} is not callable: {callback!r}")
        self._callbacks[signal] = (*self._callbacks[signal], callback)

    def disconnect(self, signal: str, callback: Callable[..., Any]) -> None:
        if signal not in self._callbacks:
            raise ValueError(f"unknown signal {signal!r}; expected one of {', '.join(SIGNALS)}")
        self._callbacks[signal] = tuple(c for c in self._callbacks[signal] if c != callback)

    def wants(self, signal: str) -> bool:
        return bool(self._callbacks[signal])

    def post(self, events: list[Event]) -> None:
        if events:
            self._queue.put(events)
            self.wake()

    def wake(self) -> None:
        """Let a dispatch() that waits look at the queue (any thread, a signal handler too)."""
        try:
            self._wake.release()
        except RuntimeError:                 # already released: a wake is pending
            pass

    def pending(self) -> int:
        return self._queue.qsize()

    def _poll(self, timeout: float | None) -> bool:
        """Poll the queue, yielding the core, within the window and the CPU credit.

        True when a change arrived.  The credit refills at max_share_pct of the time that
        passes, up to burst_ms worth, so polling never takes more than that share of a core.
        """
        now = time.perf_counter()
        credit = min(self._credit_cap_s, self._credit_s
                     + (now - self._credit_at) * self.spin.max_share_pct / 100)
        budget = min(self._window_s, credit, self._window_s if timeout is None else timeout)
        if budget <= 0:
            self._credit_s, self._credit_at = credit, now
            return False
        source, end, clock, yield_core = self._queue, now + budget, time.perf_counter, os.sched_yield
        taker = self._source
        working = 0.0                 # time spent handling deltas: work, not polling
        found = False
        if taker is not None:
            taker.poll_begin()
        try:
            while not source.qsize():
                started = clock()
                if taker is not None and taker.poll_take():
                    stopped = clock()
                    working += stopped - started
                    if stopped >= end:            # a flood must not hold dispatch() here
                        break
                elif started >= end:
                    break
                else:
                    yield_core()      # releases the GIL: other threads can post meanwhile
            found = bool(source.qsize())
        finally:
            if taker is not None:
                taker.poll_end(idle=not found)
        done = clock()
        polled = max(0.0, done - now - working)
        self.spin_s += polled
        self._credit_s, self._credit_at = credit - polled, done
        if found:
            self.spin_hits += 1
        else:
            self.spin_misses += 1
        return found

    def dispatch(self, timeout: float | None = 0.0) -> int:
        """Run callbacks for queued events; wait up to `timeout` s for the first one.

        timeout=0 never blocks, None blocks until something arrives.  Returns the number of
        events delivered.  A callback that raises is logged and counted, and delivery goes on.
        (A C SimpleQueue of event batches and a lock to wait on: the hand-off from the Zenoh
        thread costs a few microseconds, against tens for a Python Condition.)
        """
        source = self._queue
        if not source.qsize():
            if timeout == 0:
                return 0
            started = time.perf_counter()
            deadline = None if timeout is None else time.monotonic() + timeout
            if not (self._dense and self._poll(timeout)):
                while not source.qsize():
                    left = -1 if deadline is None else deadline - time.monotonic()
                    if deadline is not None and left <= 0:
                        self._dense = False
                        return 0
                    self._wake.acquire(timeout=left)
                self._dense = time.perf_counter() - started <= self._window_s
            self._wake.acquire(blocking=False)   # consume a wake that is still pending
        try:
            batches = [source.get_nowait()]
        except queue.Empty:
            return 0
        while source.qsize():
            batches.append(source.get_nowait())
        events = batches[0] if len(batches) == 1 else [e for batch in batches for e in batch]
        for signal, args in events:
            for callback in self._callbacks[signal]:
                try:
                    callback(*args)
                except Exception:  # one bad callback must not stop the agent
                    self.callback_errors += 1
                    log.exception("DSR %s callback %r raised", signal, callback)
        return len(events)
