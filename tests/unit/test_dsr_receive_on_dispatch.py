"""While an agent thread polls in dispatch(), it handles the deltas Zenoh's thread receives.

Why (dsr/signals.py, "Why the polling thread receives"): Zenoh's thread used to decode, check
and merge every delta and only then hand the event to the agent thread, which had to be woken
for it.  Now, while dispatch() polls, Zenoh's thread only queues the sample and the polling
thread does the rest itself.  What must not change: every delta is handled exactly once, in
the order it arrived, by the same checks, after another thread's transaction, and dispatch()
still returns within its window when deltas keep coming.

The receiving replica here is a real `Replica` that is never opened: a writer thread hands
samples to its `_on_delta`, as Zenoh's callback thread does.
"""

from __future__ import annotations

import collections
import threading
import time
from dataclasses import dataclass

from dsr import DSRGraph, wire
from dsr.signals import SignalHub, SpinPolicy
from dsr.transport import Replica

POLL = SpinPolicy(window_us=300_000, max_share_pct=100, burst_ms=1000)


@dataclass
class Sample:
    key_expr: str
    data: bytes

    @property
    def payload(self) -> Sample:
        return self

    def to_bytes(self) -> bytes:
        return self.data


class Pair:
    """A writer graph whose deltas reach `replica._on_delta` on the writer's thread."""

    def __init__(self, spin: SpinPolicy = POLL) -> None:
        self.writer = DSRGraph("writer")
        self.graph = DSRGraph("agent", spin=spin)
        self.replica = Replica(self.graph)
        self.replica._joined = True
        self.replica.receive_on_dispatch()
        self.merged_on: list[int] = []        # thread ident of each apply_message
        apply = self.graph.apply_message

        def traced(message: wire.Decoded) -> int:
            self.merged_on.append(threading.get_ident())
            return apply(message)
        self.graph.apply_message = traced  # type: ignore[method-assign]
        key = wire.delta_key("chronav", "writer")
        self.writer.attach(lambda payload: self.replica._on_delta(Sample(key, payload)),
                           linger_s=0.0)
        self.ball = self.writer.insert_node("thing", "ball", {"v": 0}).id
        self.values: list[int] = []
        self.threads: list[threading.Thread] = []
        self.graph.connect("node_updated",
                           lambda node, keys: self.values.append(node.attrs["v"]))

    def make_dense(self) -> None:
        """One change that dispatch() waits for: the next dispatch() polls."""
        self.write_later(0.01, 1)
        assert self.graph.dispatch(timeout=5.0) == 1

    def write_later(self, delay_s: float, *values: int, pause_s: float = 0.0) -> threading.Thread:
        def run() -> None:
            time.sleep(delay_s)
            for value in values:
                self.writer.update_node(self.ball, {"v": value})
                if pause_s:
                    time.sleep(pause_s)
        thread = threading.Thread(target=run)
        thread.start()
        self.threads.append(thread)
        return thread


def test_a_delta_that_comes_while_dispatch_polls_is_merged_on_the_polling_thread() -> None:
    pair = Pair()
    pair.make_dense()
    assert pair.replica.stats.received_by_agent == 0, "nobody polled: Zenoh's thread merged"
    assert pair.merged_on[1:] == [pair.threads[0].ident]   # (the first: the ball's insert)
    writer = pair.write_later(0.02, 2)
    assert pair.graph.dispatch(timeout=5.0) == 1
    writer.join(5.0)
    assert pair.values == [1, 2]
    assert pair.merged_on[-1] == threading.get_ident(), "merged by the thread in dispatch()"
    stats = pair.replica.stats
    assert (stats.received, stats.applied, stats.received_by_agent, stats.errors) == (3, 3, 1, 0)
    assert pair.graph.get_attr(pair.graph.get_node_by_name("ball").id, "v") == 2


def test_deltas_are_merged_once_and_in_arrival_order_whichever_thread_takes_them() -> None:
    pair = Pair(SpinPolicy(window_us=2_000, max_share_pct=100, burst_ms=1000))
    pair.make_dense()
    values = list(range(2, 302))
    writer = pair.write_later(0.0, *values, pause_s=0.0002)
    deadline = time.monotonic() + 30
    while pair.values[-1:] != [values[-1]] and time.monotonic() < deadline:
        pair.graph.dispatch(timeout=0.05)
        if len(pair.values) % 40 == 0:
            time.sleep(0.003)               # now and then nobody polls: Zenoh's thread merges
    writer.join(5.0)
    assert pair.values == [1, *values], "every update seen once, in the order it was written"
    stats = pair.replica.stats
    assert stats.applied == len(values) + 2 and stats.errors == 0   # + the insert, the 1
    assert 0 < stats.received_by_agent < len(values), "both threads took part"


def test_a_transaction_of_another_thread_holds_the_polling_thread_s_merge_back() -> None:
    pair = Pair()
    pair.make_dense()
    in_tx, done = threading.Event(), threading.Event()

    def other() -> None:
        with pair.graph.transaction():
            pair.graph.insert_node("thing", "cup")
            in_tx.set()
            done.wait(5.0)
    holder = threading.Thread(target=other)
    holder.start()
    assert in_tx.wait(5.0)
    writer = pair.write_later(0.0, 2)
    threading.Timer(0.1, done.set).start()
    delivered = 0
    deadline = time.monotonic() + 5
    while pair.values != [1, 2] and time.monotonic() < deadline:
        delivered += pair.graph.dispatch(timeout=0.5)
    holder.join(5.0)
    writer.join(5.0)
    assert pair.values == [1, 2], "merged once the transaction was committed"
    assert pair.replica.stats.errors == 0


def test_a_flood_of_received_deltas_does_not_hold_dispatch_beyond_its_window() -> None:
    hub = SignalHub(SpinPolicy(window_us=20_000, max_share_pct=100, burst_ms=1000))
    hub.connect("node_deleted", lambda node_id: None)
    inbox: collections.deque[int] = collections.deque(range(100_000))
    handled: list[int] = []

    def receive() -> None:       # each delta takes 1 ms and changes nothing anybody watches
        while inbox:
            handled.append(inbox.popleft())
            time.sleep(0.001)
            if len(handled) % 5 == 0:
                return
    hub.receive_from(inbox, receive)
    hub._dense = True                   # changes came densely: dispatch() polls
    started = time.perf_counter()
    assert hub.dispatch(timeout=0.3) == 0
    elapsed = time.perf_counter() - started
    assert elapsed < 1.0, f"dispatch(timeout=0.3) stayed {elapsed:.2f} s in a flood"
    assert len(handled) <= 40, f"the polling thread took {len(handled)} deltas in a 20 ms window"
    assert not hub.receiving, "after polling, Zenoh's thread handles what comes"
