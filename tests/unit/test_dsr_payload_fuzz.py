"""Fuzzing the receive path of a replica with hostile payloads (in-process, no network).

Every payload goes through the transport's admission API (`Replica.admit_delta`,
`Replica.admit_state`: what the Zenoh callbacks call).  Invariants: the handler never raises,
nothing is counted as an unexpected error, every message is either refused (counted, logged)
or - only when it is a valid message of an agent allowed to write it - merged; with the
shipped write policy, agent "fuzzer" holds no grant, so the guarded graph never changes.
"""

from __future__ import annotations

import logging

import orjson

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from dsr import DSRGraph, wire
from agents.world.write_policy import policy_from_env
from dsr.policy import AllowAll
from dsr.transport import Replica
from tests.fuzz_payloads import FUZZER, VALID, mutated_messages, payloads


def guarded(policy: object) -> Replica:
    graph = DSRGraph("guard")
    with graph.transaction():
        world = graph.insert_node("world", "world")
        robot = graph.insert_node("robot", "robot", {"nav_active": False})
        graph.insert_or_assign_edge(world.id, robot.id, "RT", {"x": 0.0, "y": 0.0, "theta": 0.0})
    return Replica(graph, policy=policy)  # type: ignore[arg-type]


GUARD = guarded(policy_from_env({}))
OPEN = guarded(AllowAll())
DELTA_KEY = wire.delta_key("chronav", FUZZER)
STATE_KEY = wire.state_key("chronav", FUZZER)
FAST = settings(max_examples=400, deadline=None,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])


def refused_or_merged(replica: Replica, before: dict[str, int], merged_key: str) -> None:
    after = replica.stats.as_dict()
    assert after["errors"] == before["errors"] == 0
    refused = (after["rejected"] + after["rejected_policy"]) - (before["rejected"]
                                                                + before["rejected_policy"])
    merged = after[merged_key] - before[merged_key]
    assert refused + merged == 1, (before, after)


@FAST
@given(payload=payloads, on_state_key=st.booleans())
def test_guarded_replica_refuses_every_hostile_payload(payload, on_state_key):
    digest = GUARD.graph.digest()
    before = GUARD.stats.as_dict()
    if on_state_key:
        GUARD.admit_state(STATE_KEY, payload)
        refused_or_merged(GUARD, before, "state_merged")
    else:
        GUARD.admit_delta(DELTA_KEY, payload)
        refused_or_merged(GUARD, before, "applied")
    assert GUARD.stats.state_merged == 0 and GUARD.stats.applied == 0
    assert GUARD.graph.digest() == digest
    assert GUARD.stats.last_reject.startswith("chronav/chronav/")


@FAST
@given(kind_payload=mutated_messages())
def test_open_replica_survives_mutated_messages(kind_payload):
    """Without a policy, a mutation may still be a valid message and merge: then the graph
    must stay queryable (no half-merged, corrupt state)."""
    kind, payload = kind_payload
    before = OPEN.stats.as_dict()
    if kind == "state":
        OPEN.admit_state(STATE_KEY, payload)
        refused_or_merged(OPEN, before, "state_merged")
    else:
        OPEN.admit_delta(DELTA_KEY, payload)
        refused_or_merged(OPEN, before, "applied")
    graph = OPEN.graph
    graph.digest()
    for node in graph.nodes():
        graph.edges_from(node.id)
    graph.state_message()


def test_valid_templates_do_merge_on_an_open_replica():
    """The mutation base is real: unmutated, these messages are accepted."""
    replica = guarded(AllowAll())
    for message in VALID:
        data = orjson.dumps(message)
        if message["kind"] == "state":
            replica.admit_state(STATE_KEY, data)
        else:
            replica.admit_delta(DELTA_KEY, data)
    stats = replica.stats
    assert stats.rejected == 0 and stats.applied == len(VALID) - 1 and stats.state_merged == 1


def test_refusals_are_logged(caplog):
    replica = guarded(policy_from_env({}))
    with caplog.at_level(logging.WARNING, logger="dsr.transport"):
        replica.admit_delta(DELTA_KEY, b"\xff not json")
        replica.admit_state(STATE_KEY, b'{"format": "chronav-dsr/1", "kind": "state"}')
    assert replica.stats.rejected == 2
    assert sum("dropped message from chronav/chronav/" in r.message for r in caplog.records) == 2
