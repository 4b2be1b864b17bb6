"""A writer's deltas leave in stamp order, whoever sends them.

Regression: the flusher thread took a batch and, descheduled on a loaded machine for longer than
the linger time, published it after a newer delta the writer had sent directly.  Receivers take
a delta's top stamp as their watermark of that writer, so the older batch's writes then looked
forged when another member's state relayed them (tests/integration/test_dsr_replication.py,
three concurrent writers, failed about once in twenty runs under load).
"""

from __future__ import annotations

import threading
import time

import orjson

from dsr import wire
from dsr.crdt import ElementState
from dsr.outbox import Outbox


def _stamps(payload: bytes) -> list[int]:
    return [reg[0] for node in orjson.loads(payload)["nodes"] for reg in node["attrs"].values()]


def _write(stamp: int) -> dict[int, ElementState]:
    return {stamp: ElementState(attrs={"v": (stamp, 1, stamp)})}


def test_a_direct_send_never_overtakes_a_batch_in_flight() -> None:
    published: list[bytes] = []
    in_publish, release = threading.Event(), threading.Event()

    def publish(payload: bytes) -> None:   # the flusher's publish, stalled until released
        in_publish.set()
        release.wait(5.0)
        published.append(payload)

    outbox = Outbox(wire.DeltaEncoder("g", "a", 1), publish, linger_s=0.001)
    first = outbox.add(_write(1), {}, top=1)
    assert first is not None, "after a quiet time a delta goes out at once"
    published.append(first)                                   # the writer publishes it
    assert outbox.add(_write(2), {}, top=2) is None            # within the linger: queued
    assert in_publish.wait(5.0), "the flusher took the batch and is publishing it"
    time.sleep(0.01)                                           # well past the linger time
    assert outbox.add(_write(3), {}, top=3) is None, "queued behind the batch in flight"
    release.set()
    outbox.flush()
    outbox.close()
    assert [s for payload in published for s in _stamps(payload)] == [1, 2, 3]
