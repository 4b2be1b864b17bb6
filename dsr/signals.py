"""Change signals queued by any thread and delivered on the agent's own thread.

Why a queue: replication merges remote deltas on Zenoh's callback thread while holding the
graph lock; running agent callbacks there would let agent code block replication or re-enter
the graph under the lock.  Instead events are queued and `dispatch()` (called from the agent's
loop) runs the callbacks with no lock held.  Events are only queued for signals that have at
least one callback, so a replica nobody listens to does not accumulate memory.
"""

from __future__ import annotations

import logging
import queue
import threading
import time
from collections.abc import Callable
from typing import Any

SIGNALS: tuple[str, ...] = ("node_added", "node_updated", "node_deleted",
                            "edge_added", "edge_updated", "edge_deleted")
Event = tuple[str, tuple[Any, ...]]
log = logging.getLogger(__name__)


class SignalHub:
    def __init__(self) -> None:
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
            deadline = None if timeout is None else time.monotonic() + timeout
            while not source.qsize():
                left = -1 if deadline is None else deadline - time.monotonic()
                if deadline is not None and left <= 0:
                    return 0
                self._wake.acquire(timeout=left)
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
                except Exception:  # noqa: BLE001 - one bad callback must not stop the agent
                    self.callback_errors += 1
                    log.exception("DSR %s callback %r raised", signal, callback)
        return len(events)
