"""Hypothesis strategies for hostile Zenoh payloads on the DSR delta and state keys.

Shared by tests/unit/test_dsr_payload_fuzz.py (in-process, thousands of cases) and
tests/integration/test_payload_fuzz.py (a real replica process behind a real router).
Three families: random bytes, random JSON (including JSON shaped like a DSR message), and valid
deltas / states of agent "fuzzer" with one mutation (a value replaced, a key dropped or added).
"""

from __future__ import annotations

import copy
from typing import Any

import orjson
from hypothesis import strategies as st

from dsr import DSRGraph, wire

FUZZER = "fuzzer"

json_scalars = (st.none() | st.booleans() | st.integers(min_value=-(2**63), max_value=2**64 - 1)
                | st.floats(allow_nan=False, allow_infinity=False) | st.text(max_size=12))
json_values = st.recursive(json_scalars, lambda inner: st.lists(inner, max_size=4)
                           | st.dictionaries(st.text(max_size=8), inner, max_size=4),
                           max_leaves=12)


def valid_messages() -> list[dict[str, Any]]:
    """Real deltas and a state written by a replica of agent FUZZER (all well formed)."""
    out: list[bytes] = []
    graph = DSRGraph(FUZZER)
    graph.attach(out.append)
    world = graph.insert_node("world", "w", {"x": 1.0, "tags": ["a", "b"]})
    robot = graph.insert_node("robot", "r", {"nav_active": False})
    graph.insert_or_assign_edge(world.id, robot.id, "RT", {"x": 1.0, "y": 2.0, "theta": 0.5})
    graph.update_node(robot.id, {"cmd_vx": 0.2, "n": 3, "name": "robot"})
    with graph.transaction():
        person = graph.insert_node("person", "p")
        graph.insert_or_assign_edge(person.id, world.id, "in")
    graph.delete_node(person.id)
    messages = [orjson.loads(p) for p in out]
    messages.append(orjson.loads(graph.state_message()))
    return messages


VALID = valid_messages()


def _paths(value: Any, prefix: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    found = [prefix]
    if isinstance(value, dict):
        for key, item in value.items():
            found += _paths(item, (*prefix, key))
    elif isinstance(value, list):
        for index, item in enumerate(value):
            found += _paths(item, (*prefix, index))
    return found


@st.composite
def mutated_messages(draw: st.DrawFn) -> tuple[str, bytes]:
    """(kind, payload): a valid message with one random mutation somewhere inside."""
    message = copy.deepcopy(draw(st.sampled_from(VALID)))
    path = draw(st.sampled_from(_paths(message)[1:]))
    parent = message
    for part in path[:-1]:
        parent = parent[part]
    last = path[-1]
    action = draw(st.sampled_from(["replace", "drop", "add"]))
    if action == "replace":
        parent[last] = draw(json_values)
    elif action == "drop":
        del parent[last]
    elif isinstance(parent, dict):
        parent[draw(st.text(min_size=1, max_size=8))] = draw(json_values)
    else:
        parent.append(draw(json_values))
    return str(message.get("kind", "delta")), orjson.dumps(message)


def dsr_shaped() -> st.SearchStrategy[bytes]:
    """JSON objects with the message's keys and arbitrary values."""
    return st.fixed_dictionaries(
        {"format": st.sampled_from([wire.FORMAT, "chronav-dsr/2"]) | json_values,
         "kind": st.sampled_from(["delta", "state"]) | json_values,
         "graph": st.just("chronav") | json_values,
         "agent": st.just(FUZZER) | json_values,
         "replica": st.integers(min_value=-5, max_value=2**64 - 1) | json_values},
        optional={"nodes": json_values, "edges": json_values, "writers": json_values},
    ).map(orjson.dumps)


payloads = st.one_of(st.binary(max_size=200), json_values.map(orjson.dumps), dsr_shaped(),
                     mutated_messages().map(lambda kind_payload: kind_payload[1]))
