"""Adaptive coalescing of outgoing deltas, published in stamp order.

Why coalesce: each Zenoh sample costs the receiver a fixed ~20-50 us of Python work (callback,
decode, checks), whatever its size, so an agent writing thousands of attributes per second
would saturate its peers.  Samples are rationed like tokens from a bucket that refills by one
every `linger_s` and holds at most DIRECT_BURST: while a token is left, a delta is sent at once,
on the writer's thread (no latency cost on the request/response path, even for an answer
that follows the previous send by less than `linger_s`, as long as the exchange averages at
most one sample per `linger_s`); a stream that outruns the bucket has its deltas
joined into one pending delta (a join of delta-states is a valid delta), sent by a flusher
thread at most `linger_s` after the previous send, or as soon as `max_entries` elements are
pending.  So a writer publishes at most one sample per `linger_s` on average.  (A bucket of
one, sending only after a quiet `linger_s`, delayed every answer of an exchange faster than
that by up to `linger_s` plus a thread wake-up, measured in bench_dsr's ping-pong.)

Why order: receivers take a writer's deltas as arriving in stamp order (a delta's top stamp is
their watermark of that writer, dsr/transport.py), so a send must never overtake an older one.
Payloads leave from several threads (writers publish their own direct deltas after releasing
the graph lock; the flusher publishes batches), and any of them may be descheduled between
taking its payload and publishing it.  So every payload gets a ticket when it leaves the
outbox, under the outbox lock and therefore in stamp order (writers stamp and hand their delta
over under the graph lock), and send() publishes tickets strictly in ticket order.  Whoever
takes an Outgoing must send() it, even on error: a missing ticket holds back every later one
(for at most TURN_TIMEOUT_S, after which the order gives way and an error is logged).
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import cast

from dsr import crdt, wire
from dsr.crdt import ElementState

log = logging.getLogger(__name__)
EdgeKey = tuple[int, int, str]

#: how long a payload waits for an older one to be published before it goes anyway
TURN_TIMEOUT_S = 2.0
#: samples a writer may send at once after a quiet time (see the module docstring)
DIRECT_BURST = 2.0


@dataclass(slots=True, frozen=True)
class Outgoing:
    """One payload that has left the outbox: its place in the send order and its top stamp."""
    ticket: int
    payload: bytes
    top: int


class Outbox:
    def __init__(self, encoder: wire.DeltaEncoder, publish: Callable[[bytes], None], *,
                 linger_s: float = 0.0003, max_entries: int = 1000) -> None:
        self._encoder = encoder
        self._publish = publish
        self.linger_s = linger_s
        self.max_entries = max_entries
        self._lock = threading.Lock()
        self._wake = threading.Condition(self._lock)
        self._nodes: dict[int, ElementState] = {}
        self._edges: dict[EdgeKey, ElementState] = {}
        self._last_send = 0.0
        self._tokens = DIRECT_BURST               # at _tokens_at (see _tokens_now)
        self._tokens_at = 0.0
        self._pending_top = 0
        self._tickets = 0                         # next ticket to give (under _lock)
        self._turn = 0                            # next ticket allowed to publish
        self._turn_changed = threading.Condition()
        #: largest HLC of the deltas this outbox has published (see DSRGraph.published_hlc)
        self.sent_top = 0
        self._closed = False
        self._thread: threading.Thread | None = None
        self.messages = 0

    # ------------------------------------------------------------------ taking payloads
    def add(self, nodes: dict[int, ElementState], edges: dict[EdgeKey, ElementState],
            top: int = 0) -> Outgoing | None:
        """Queue a delta whose stamps are at most `top`; returns an Outgoing the caller must
        send() now (or None if queued)."""
        with self._lock:
            now = time.perf_counter()
            if self._direct_ok(now):
                return self._issue(self._encode(nodes, edges), top, now)
            if top > self._pending_top:
                self._pending_top = top
            for node_id, state in nodes.items():
                pending = self._nodes.get(node_id)
                if pending is None:
                    self._nodes[node_id] = state
                else:
                    crdt.join_states(pending, state)
            for key, edge in edges.items():
                pending = self._edges.get(key)
                if pending is None:
                    self._edges[key] = edge
                else:
                    crdt.join_states(pending, edge)
            if len(self._nodes) + len(self._edges) >= self.max_entries:
                return self._take(now)            # the caller sends it next
            if self._thread is None:
                self._thread = threading.Thread(target=self._run, name="dsr-outbox", daemon=True)
                self._thread.start()
            self._wake.notify()
            return None

    def add_attrs(self, node_id: int, regs: dict[str, tuple[int, int, object]],
                  top: int) -> Outgoing | None:
        """add() for one node's attribute update (the hot path: no intermediate objects)."""
        now = time.perf_counter()
        if self._direct_ok(now):
            with self._lock:
                if self._direct_ok(now):
                    return self._issue(self._encoder.node_attrs(node_id, regs), top, now)
        return self.add({node_id: ElementState(attrs=regs)}, {}, top)

    def add_entries(self, entries: list[dict[str, object]], top: int) -> Outgoing | None:
        """add() for a batch of node attribute updates already in wire form ({"id", "attrs"})."""
        now = time.perf_counter()
        with self._lock:   # a big batch is worth a sample of its own: no lingering for it
            if not self._nodes and not self._edges and (
                    len(entries) * 4 >= self.max_entries or self._tokens_now(now) >= 1.0):
                return self._issue(self._encoder.encode(entries, []), top, now)
        return self.add({cast(int, entry["id"]): ElementState(attrs=cast("dict[str, crdt.Register]", entry["attrs"]))
                         for entry in entries}, {}, top)

    def _encode(self, nodes: dict[int, ElementState], edges: dict[EdgeKey, ElementState]) -> bytes:
        return self._encoder.encode([wire.node_entry(i, s) for i, s in nodes.items()],
                                    [wire.edge_entry(k, s) for k, s in edges.items()])

    def _direct_ok(self, now: float) -> bool:
        """May a delta go out at once, on the writer's thread?  Only with nothing queued (the
        queued writes are older: their batch must get the earlier ticket) and a token left."""
        return not self._nodes and not self._edges and self._tokens_now(now) >= 1.0

    def _tokens_now(self, now: float) -> float:
        """Samples that may go out at once: one more per `linger_s` since the last send."""
        if self.linger_s <= 0:
            return DIRECT_BURST
        return min(DIRECT_BURST, self._tokens + (now - self._tokens_at) / self.linger_s)

    def _issue(self, payload: bytes, top: int, now: float) -> Outgoing:
        """Give a payload its ticket (caller holds _lock); every sample takes a token."""
        ticket = self._tickets
        self._tickets = ticket + 1
        self._tokens = self._tokens_now(now) - 1.0
        self._tokens_at = now
        self._last_send = now
        self.messages += 1
        return Outgoing(ticket, payload, top)

    def _take(self, now: float) -> Outgoing | None:
        """The pending delta as one ticketed payload (caller holds _lock)."""
        if not self._nodes and not self._edges:
            return None
        nodes, edges = self._nodes, self._edges
        self._nodes, self._edges = {}, {}
        top, self._pending_top = self._pending_top, 0
        return self._issue(self._encode(nodes, edges), top, now)

    # ------------------------------------------------------------------ publishing
    def send(self, out: Outgoing | None) -> None:
        """Publish `out` once every older ticket is published (on the caller's thread)."""
        if out is None:
            return
        turn = self._turn_changed
        with turn:
            if not turn.wait_for(lambda: self._turn >= out.ticket, timeout=TURN_TIMEOUT_S):
                log.error("DSR outbox: delta %d waited %.1f s for an older one (%d) that was "
                          "never sent; publishing out of order", out.ticket, TURN_TIMEOUT_S,
                          self._turn)
        try:
            self._publish(out.payload)
        except Exception:  # session closing under us; state stays for anti-entropy
            log.warning("DSR outbox: publish failed", exc_info=True)
        else:
            if out.top > self.sent_top:
                self.sent_top = out.top
        finally:
            with turn:
                if out.ticket + 1 > self._turn:
                    self._turn = out.ticket + 1
                turn.notify_all()

    def _run(self) -> None:
        while True:
            with self._lock:
                while not self._nodes and not self._edges and not self._closed:
                    self._wake.wait()
                if self._closed:
                    return
                delay = self._last_send + self.linger_s - time.perf_counter()
            if delay > 0:
                time.sleep(delay)
            with self._lock:
                out = self._take(time.perf_counter())
            self.send(out)

    def flush(self) -> None:
        """Send whatever is pending now (on the caller's thread); returns once every payload
        that left the outbox before the call has been published."""
        with self._lock:
            out = self._take(time.perf_counter())
            issued = self._tickets
        self.send(out)
        with self._turn_changed:
            self._turn_changed.wait_for(lambda: self._turn >= issued, timeout=TURN_TIMEOUT_S)

    def close(self) -> None:
        self.flush()
        with self._lock:
            self._closed = True
            self._wake.notify_all()
        thread = self._thread
        if thread is not None and thread is not threading.current_thread():
            thread.join(timeout=1.0)
