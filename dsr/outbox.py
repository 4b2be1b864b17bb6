"""Adaptive coalescing of outgoing deltas.

Why: each Zenoh sample costs the receiver a fixed ~20-50 us of Python work (callback, decode,
checks), whatever its size, so an agent writing thousands of attributes per second would
saturate its peers.  The first delta after a quiet period is sent at once (no latency cost on
the request/response path); deltas that follow within `linger_s` of the previous send are
joined into one pending delta (a join of delta-states is a valid delta) and sent by a flusher
thread at most `linger_s` later, or as soon as `max_entries` elements are pending.

Order: receivers take a writer's deltas as arriving in stamp order (a delta's top stamp is their
watermark of that writer, dsr/transport.py), so a send must never overtake an older one.  A
batch the flusher has taken is in flight until published; meanwhile nothing goes out directly
(it queues behind), and the flusher and flush() send one batch at a time.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable

from dsr import crdt, wire
from dsr.crdt import ElementState

log = logging.getLogger(__name__)
EdgeKey = tuple[int, int, str]


class Outbox:
    def __init__(self, encoder: wire.DeltaEncoder, publish: Callable[[bytes], None], *,
                 linger_s: float = 0.0003, max_entries: int = 1000) -> None:
        self._encoder = encoder
        self._publish = publish
        self.linger_s = linger_s
        self.max_entries = max_entries
        self._lock = threading.Lock()
        self._wake = threading.Condition(self._lock)
        self._send_lock = threading.Lock()   # one batch taken and published at a time
        self._in_flight = 0                  # batches taken, not yet published
        self._nodes: dict[int, ElementState] = {}
        self._edges: dict[EdgeKey, ElementState] = {}
        self._last_send = 0.0
        self._pending_top = 0
        #: largest HLC of the deltas this outbox has published (see DSRGraph.published_hlc)
        self.sent_top = 0
        self._closed = False
        self._thread: threading.Thread | None = None
        self.messages = 0

    def add(self, nodes: dict[int, ElementState], edges: dict[EdgeKey, ElementState],
            top: int = 0) -> bytes | None:
        """Queue a delta whose stamps are at most `top`; returns a payload the caller must
        publish now (or None if queued)."""
        with self._lock:
            now = time.perf_counter()
            if self._direct_ok(now):
                self._last_send = now
                self.messages += 1
                return self._encode(nodes, edges)
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
            if len(self._nodes) + len(self._edges) >= self.max_entries and not self._in_flight:
                taken = self._take(now, in_flight=False)   # the caller publishes it next
                return taken[0] if taken is not None else None
            if self._thread is None:
                self._thread = threading.Thread(target=self._run, name="dsr-outbox", daemon=True)
                self._thread.start()
            self._wake.notify()
            return None

    def add_attrs(self, node_id: int, regs: dict[str, tuple[int, int, object]],
                  top: int) -> bytes | None:
        """add() for one node's attribute update (the hot path: no intermediate objects)."""
        now = time.perf_counter()
        if self._direct_ok(now):
            with self._lock:
                if self._direct_ok(now):
                    self._last_send = now
                    self.messages += 1
                    return self._encoder.node_attrs(node_id, regs)
        return self.add({node_id: ElementState(attrs=regs)}, {}, top)

    def add_entries(self, entries: list[dict[str, object]], top: int) -> bytes | None:
        """add() for a batch of node attribute updates already in wire form ({"id", "attrs"})."""
        now = time.perf_counter()
        with self._lock:   # a big batch is worth a sample of its own: no lingering for it
            if not self._nodes and not self._edges and not self._in_flight and (
                    len(entries) * 4 >= self.max_entries or now - self._last_send >= self.linger_s):
                self._last_send = now
                self.messages += 1
                return self._encoder.encode(entries, [])
        return self.add({entry["id"]: ElementState(attrs=entry["attrs"])  # type: ignore[misc]
                         for entry in entries}, {}, top)

    def _encode(self, nodes: dict[int, ElementState], edges: dict[EdgeKey, ElementState]) -> bytes:
        return self._encoder.encode([wire.node_entry(i, s) for i, s in nodes.items()],
                                    [wire.edge_entry(k, s) for k, s in edges.items()])

    def _direct_ok(self, now: float) -> bool:
        """May a delta go out at once, on the writer's thread?  Only with nothing queued or in
        flight before it (it would overtake them) and after a quiet `linger_s`."""
        return not self._nodes and not self._edges and not self._in_flight \
            and now - self._last_send >= self.linger_s

    def _take(self, now: float, in_flight: bool = True) -> tuple[bytes, int] | None:
        """The pending delta as one payload (caller holds _lock); counted in flight until
        _send() has published it, unless the caller publishes it itself right away."""
        if not self._nodes and not self._edges:
            return None
        nodes, edges = self._nodes, self._edges
        self._nodes, self._edges = {}, {}
        top, self._pending_top = self._pending_top, 0
        self._last_send = now
        self.messages += 1
        if in_flight:
            self._in_flight += 1
        return self._encode(nodes, edges), top

    def _send(self, taken: tuple[bytes, int] | None) -> None:
        if taken is None:
            return
        try:
            self._publish(taken[0])
        except Exception:  # noqa: BLE001 - session closing under us; state stays for anti-entropy
            log.warning("DSR outbox: publish failed", exc_info=True)
        else:
            if taken[1] > self.sent_top:
                self.sent_top = taken[1]
        finally:
            with self._lock:
                self._in_flight -= 1

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
            with self._send_lock:
                with self._lock:
                    payload = self._take(time.perf_counter())
                self._send(payload)

    def flush(self) -> None:
        """Send whatever is pending now (on the caller's thread), after any batch in flight."""
        with self._send_lock:
            with self._lock:
                payload = self._take(time.perf_counter())
            self._send(payload)

    def close(self) -> None:
        self.flush()
        with self._lock:
            self._closed = True
            self._wake.notify_all()
        thread = self._thread
        if thread is not None and thread is not threading.current_thread():
            thread.join(timeout=1.0)
