"""A writer's deltas leave in stamp order, whoever sends them and whoever is descheduled.

Regressions, both found by tests/integration/test_dsr_replication.py (three concurrent writers)
failing now and then under CPU load with a false "forged stamp": receivers take a delta's top
stamp as their watermark of that writer, so an older delta published after a newer one looked
forged when another member's state relayed its writes.
- The flusher thread took a batch and, descheduled for longer than the linger time, published it
  after a newer delta the writer had sent directly.
- A writer thread took a direct delta and, descheduled after releasing the graph lock but before
  publishing, was overtaken by the flusher's batch of another thread's newer writes.
"""

from __future__ import annotations

import threading
import time

import orjson

from dsr import wire
from dsr.crdt import ElementState
from dsr.graph import DSRGraph
from dsr.outbox import DIRECT_BURST, Outbox


def _stamps(payload: bytes) -> list[int]:
    """The attribute stamps of a delta (its inserts' stamps too: their meta register)."""
    stamps = []
    for node in orjson.loads(payload)["nodes"]:
        stamps += [reg[0] for reg in node.get("attrs", {}).values()]
        if "meta" in node:
            stamps.append(node["meta"][0])
    return stamps


def _write(stamp: int) -> dict[int, ElementState]:
    return {stamp: ElementState(attrs={"v": (stamp, 1, stamp)})}


def _sent_stamps(published: list[bytes]) -> list[int]:
    return [s for payload in published for s in _stamps(payload)]


def test_a_direct_send_never_overtakes_a_batch_in_flight() -> None:
    published: list[bytes] = []
    in_publish, release = threading.Event(), threading.Event()
    burst = int(DIRECT_BURST)

    def publish(payload: bytes) -> None:   # stalls the payload after the burst (the batch)
        if len(published) >= burst:
            in_publish.set()
            release.wait(5.0)
        published.append(payload)

    outbox = Outbox(wire.DeltaEncoder("g", "a", 1), publish, linger_s=0.001)
    for stamp in range(1, burst + 1):
        outbox.send(outbox.add(_write(stamp), {}, top=stamp))
    assert len(published) == burst, "after a quiet time a burst of deltas goes out at once"
    assert outbox.add(_write(burst + 1), {}, top=burst + 1) is None   # beyond it: queued
    assert in_publish.wait(5.0), "the flusher took the batch and is publishing it"
    time.sleep(0.01)                                           # well past the linger time
    last = outbox.add(_write(burst + 2), {}, top=burst + 2)
    sender = threading.Thread(target=outbox.send, args=(last,))
    sender.start()
    time.sleep(0.05)
    assert _sent_stamps(published) == list(range(1, burst + 1)), \
        "the newer delta waits for the batch in flight"
    release.set()
    sender.join(5.0)
    outbox.close()
    assert _sent_stamps(published) == list(range(1, burst + 3))
    assert outbox.sent_top == burst + 2


def test_a_batch_never_overtakes_a_direct_delta_its_writer_has_not_sent_yet() -> None:
    published: list[bytes] = []
    outbox = Outbox(wire.DeltaEncoder("g", "a", 1), published.append, linger_s=0.001)
    for stamp in range(1, int(DIRECT_BURST)):        # all but the last token of the burst
        outbox.send(outbox.add(_write(stamp), {}, top=stamp))
    sent = len(published)
    a = sent + 1
    stalled = outbox.add(_write(a), {}, top=a)    # writer A: a direct delta, then descheduled
    assert stalled is not None
    assert outbox.add(_write(a + 1), {}, top=a + 1) is None   # writer B, beyond the burst
    time.sleep(0.05)                                  # the flusher has long taken B's batch
    assert len(published) == sent, "the batch waits for the older direct delta"
    outbox.send(stalled)                              # writer A runs again
    outbox.flush()
    outbox.close()
    assert _sent_stamps(published) == list(range(1, a + 2))


def test_answers_faster_than_the_linger_time_go_out_at_once_and_streams_are_coalesced() -> None:
    """Regression (bench_dsr ping-pong): with a bucket of one token, the answer to a request
    that came less than `linger_s` after the previous answer waited for the flusher thread,
    up to `linger_s` plus a wake-up.  Two deltas in quick succession now both leave at once,
    on the writer's thread; a stream that outruns one sample per `linger_s` is joined."""
    published: list[bytes] = []
    outbox = Outbox(wire.DeltaEncoder("g", "a", 1), published.append, linger_s=0.05)
    for stamp in (1, 2):
        out = outbox.add(_write(stamp), {}, top=stamp)
        assert out is not None, f"delta {stamp} of a pair goes out at once"
        outbox.send(out)
    for stamp in range(3, 103):                       # a tight stream: joined
        outbox.send(outbox.add(_write(stamp), {}, top=stamp))
    outbox.flush()
    outbox.close()
    assert _sent_stamps(published) == list(range(1, 103))
    assert len(published) <= 4, f"a stream of 100 deltas took {len(published) - 2} samples"


def test_concurrent_writer_threads_publish_in_stamp_order() -> None:
    """Through the graph, as agents write: several threads, direct sends and batches mixed,
    with a publisher that sometimes yields the CPU mid-publish."""
    published: list[bytes] = []

    def publish(payload: bytes) -> None:
        if len(published) % 7 == 3:
            time.sleep(0.0005)
        published.append(payload)

    graph = DSRGraph("writer", replica_id=5)
    graph.attach(publish, linger_s=0.0002)
    node_ids = [graph.insert_node("thing", f"thing_{i}").id for i in range(4)]

    def writer(node_id: int) -> None:
        for step in range(300):
            graph.update_node(node_id, {"step": step})
            if step % 50 == 0:
                time.sleep(0.001)

    threads = [threading.Thread(target=writer, args=(i,)) for i in node_ids]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(30.0)
    graph.flush()
    tops = [max(_stamps(payload) or [0]) for payload in published]
    lows = [min(_stamps(payload) or [0]) for payload in published]
    assert all(lows[i] > tops[i - 1] for i in range(1, len(tops))), \
        "a delta's stamps are all above every stamp published before it"
    assert graph.published_hlc() == max(tops)
