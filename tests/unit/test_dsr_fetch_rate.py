"""State fetches caused by digests: at most one per member per change, rate-limited.

Issue #31: a tool holding a presence token and putting its current clock in `seen` had its
state fetched 33-49 times per 15-20 s (113-121 when its state was refused).  Here an honest
replica (the real transport hooks, simulated time) hears such a tool's digests every 0.5 s
for 60 s and fetches (merges) the tool's state whenever it asks for it; the number of fetches
is what a live run would see.
"""

from __future__ import annotations

import orjson
import pytest

from dsr import DSRGraph, wire
from dsr.transport import Replica
from tests.unit.test_dsr_protocol import POLICY

TOOL = "agenda_tool-desk"


def run(state_kind: str, seconds: float = 60.0, digest_every: float = 0.5) -> tuple[int, Replica]:
    """Fetches of the tool's state by one honest replica over `seconds` of simulated time."""
    clock = [0.0]
    honest = Replica(DSRGraph("executive"), policy=POLICY)
    honest.anti_entropy.now = lambda: clock[0]               # type: ignore[method-assign]
    honest.joined = True
    honest.members.add(TOOL)
    tool = DSRGraph(TOOL)
    tool.insert_node("agenda_request", "agenda_request/1", {"state": "pending", "change": "{}"})
    fetches = 0
    while clock[0] < seconds:
        stamp = tool.clock.tick()                # the tool's clock runs, it writes nothing
        digest = {"format": wire.FORMAT, "kind": "digest", "graph": "chronav", "agent": TOOL,
                  "replica": tool.replica_id, "clock": stamp,
                  "seen": {str(tool.replica_id): stamp}}
        honest.admit_delta(wire.delta_key("chronav", TOOL), orjson.dumps(digest))
        while not honest.anti_entropy.requests.empty():  # what the sync worker does
            target = honest.anti_entropy.take(0)
            assert target == TOOL
            fetches += 1
            document = orjson.loads(tool.state_message())
            if state_kind == "no_watermarks":    # a client that leaves out clock and seen
                document.pop("clock")
                document.pop("seen")
            elif state_kind == "refused":        # a state the policy refuses whole
                document["agent"] = "nobody"
            key = wire.state_key("chronav", document["agent"])
            honest.admit_state(key, orjson.dumps(document))
        clock[0] += digest_every
    return fetches, honest


@pytest.mark.parametrize("state_kind", ["no_watermarks", "refused"])
def test_a_member_whose_state_never_settles_is_fetched_with_a_growing_pause(state_kind):
    fetches, honest = run(state_kind)
    # 0 s, then pauses of 2, 4, 8, 16, 30 s: 6 fetches in 60 s (issue: ~2 per second)
    assert 3 <= fetches <= 7, fetches
    assert honest.stats.fetches_postponed > 100


def test_a_member_that_follows_the_doc_is_fetched_once():
    fetches, honest = run("complete")
    assert fetches == 1
    assert honest.stats.rejects == {} and honest.stats.fetches_postponed == 0
