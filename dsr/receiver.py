"""Who takes a replica's received deltas off Zenoh's channel: a receiver thread, or the agent's
thread while it polls in dispatch().

Why not a Zenoh callback: Zenoh runs a subscriber's Python callback on a thread of its own.
Each delta then cost two thread hand-overs before the agent's callback could run: Zenoh's
network thread woke the callback thread, and the callback thread and the agent's polling
thread passed the GIL between them, each time waking a thread that slept waiting for it, and
a bare Zenoh ping-pong whose poller takes samples from a channel (`try_recv`) instead of a
callback ran faster per round trip (docs/performance.md).  So deltas arrive in a Zenoh FIFO channel, which the network
thread fills without the GIL, and are taken from it by:

- the agent's thread while it polls in dispatch() (dsr/signals.py): it takes each sample
  with `try_recv`, decodes, checks and merges it, and goes straight on to the callbacks;
- otherwise this module's receiver thread, which sleeps in the channel's blocking `recv()`
  as Zenoh's callback thread did.

Order: a writer's deltas must be handled in the order they came (dsr/membership.py,
`advance`).  Two threads taking from one channel could each hold a sample and handle them
the wrong way round, so every sample is taken and handled under one lock, and a blocking
`recv()`, which cannot be taken under that lock, happens only while the agent's thread takes
nothing.  Ownership goes back and forth like this:

- the receiver thread owns the channel (it may be asleep in `recv()`); a polling agent thread
  asks for it, and the receiver hands it over after the next sample it handles;
- while the agent's thread owns it, the receiver thread never calls `recv()`; it wakes every
  `park_s` and, if the agent is not polling right then (busy in a callback), handles what
  waits, so the graph stays current; after `reclaim_s` without polling it takes the channel
  back, and so it does when a poll of the agent's thread finds nothing and it goes to sleep.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from typing import Any

log = logging.getLogger(__name__)

#: how long the parked receiver thread sleeps between looks while the agent's thread owns the
#: channel (so a busy agent's graph lags by at most this much; each look costs the polling
#: agent a GIL hand-over, so not much more often), and how long without a poll before it takes
#: the channel back
PARK_S = 0.01
RECLAIM_S = 0.05


class ChannelClosed(Exception):
    """The channel's blocking take found it closed: the receiver thread ends."""


class DeltaReceiver:
    """Takes samples from one channel and hands each to `handle`, in order (module docstring).

    take_nowait() returns the next sample or None; take() blocks for the next one and raises
    ChannelClosed once the channel is closed.  handle_by_agent (default: handle) is used on
    the agent's thread.  Implements the poll source of dsr.signals.SignalHub (poll_begin /
    poll_take / poll_end)."""

    def __init__(self, take_nowait: Callable[[], Any], take: Callable[[], Any],
                 handle: Callable[[Any], None], *,
                 handle_by_agent: Callable[[Any], None] | None = None, name: str = "dsr-rx",
                 park_s: float = PARK_S, reclaim_s: float = RECLAIM_S) -> None:
        self._take_nowait = take_nowait
        self._take = take
        self._handle = handle
        self._handle_by_agent = handle if handle_by_agent is None else handle_by_agent
        self.park_s, self.reclaim_s = park_s, reclaim_s
        self._lock = threading.Lock()            # taking + handling one sample
        self._agent_owns = False                 # the agent's thread takes, with take_nowait
        self._wanted = False                     # a polling agent thread asked for the channel
        self._polling = False                    # an agent thread is inside a poll right now
        self._last_poll = 0.0
        self._unpark = threading.Event()
        self._closed = False
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)

    def start(self) -> None:
        self._thread.start()

    def close(self, timeout: float = 2.0) -> None:
        """Stop handling samples; the caller closes the channel so that a blocked take()
        returns (ChannelClosed)."""
        self._closed = True
        self._unpark.set()
        if self._thread.is_alive() and self._thread is not threading.current_thread():
            self._thread.join(timeout)

    # ------------------------------------------------------------------ the agent's thread
    def poll_begin(self) -> None:
        self._polling = True
        self._last_poll = time.monotonic()
        if not self._agent_owns:
            self._wanted = True

    def poll_take(self) -> bool:
        """Handle the next waiting sample if this thread owns the channel; True if it did."""
        if not self._agent_owns:
            return False
        with self._lock:
            if not self._agent_owns or self._closed:
                return False
            try:
                sample = self._take_nowait()
            except Exception:  # noqa: BLE001 - the channel closed under a polling agent
                return False
            if sample is None:
                return False
            self._handle_by_agent(sample)
        return True

    def poll_end(self, idle: bool) -> None:
        """The poll is over; `idle`: it found nothing and the agent's thread goes to sleep, so
        the receiver thread must take the channel back now."""
        self._polling = False
        self._last_poll = time.monotonic()
        if idle:
            self._give_back()

    def _give_back(self) -> None:
        with self._lock:        # (the receiver reads _wanted under it: no hand-over is lost)
            owned, self._agent_owns, self._wanted = self._agent_owns, False, False
        if owned:
            self._unpark.set()

    # ------------------------------------------------------------------ the receiver thread
    def _run(self) -> None:
        while not self._closed:
            try:
                if self._agent_owns:
                    self._parked()
                else:
                    self._receive_one()
            except ChannelClosed:
                return
            except Exception:  # the thread must go on; handle() logs its own
                log.exception("DSR receiver %s failed", self._thread.name)
                time.sleep(self.park_s)

    def _receive_one(self) -> None:
        sample = self._take()                    # blocks (the GIL is released meanwhile)
        with self._lock:
            if self._closed:
                return
            self._handle(sample)
            if self._wanted:                     # a polling agent thread takes over from here
                self._agent_owns = True
                self._wanted = False

    def _parked(self) -> None:
        self._unpark.wait(self.park_s)
        self._unpark.clear()
        if self._closed or not self._agent_owns or self._polling:
            return
        if time.monotonic() - self._last_poll >= self.reclaim_s:
            self._give_back()                    # the agent stopped polling: back to recv()
        with self._lock:                         # the agent is busy: keep the graph current
            while not self._closed and not self._polling:    # (until it polls again)
                try:
                    sample = self._take_nowait()
                except Exception:  # noqa: BLE001 - closed: the next take() says so
                    return
                if sample is None:
                    break
                self._handle(sample)


def receiver_of(channel: Any, handle: Callable[[Any], None],
                handle_by_agent: Callable[[Any], None], closed_error: type[Exception], *,
                name: str) -> DeltaReceiver:
    """A receiver of a Zenoh channel handler (`subscriber.handler`: its `recv()` raises
    `closed_error` once the subscriber is undeclared or the session closed)."""
    def take() -> Any:
        try:
            return channel.recv()
        except closed_error:
            raise ChannelClosed from None
    return DeltaReceiver(channel.try_recv, take, handle, handle_by_agent=handle_by_agent,
                         name=name)
