"""Wire format: encode/decode round trip, validation errors, writer checks."""

from __future__ import annotations

import orjson
import pytest

from dsr import DSRGraph, WireError, wire


def delta_of(graph: DSRGraph, action) -> bytes:
    sent: list[bytes] = []
    graph.attach(sent.append)
    action(graph)
    graph.attach(None)
    assert len(sent) == 1
    return sent[0]


def test_round_trip_and_key_space():
    g = DSRGraph("alice", graph="demo")
    payload = delta_of(g, lambda x: x.insert_node("person", "bob", {"age": 3, "l": ["a"]}))
    message = wire.decode(payload)
    assert (message.kind, message.graph, message.agent) == ("delta", "demo", "alice")
    node = message.nodes[0]
    node_id, state = node
    assert state.meta[2] == ("person", "bob") and state.attrs["age"][2] == 3
    assert wire.foreign_writer(message) is None
    assert wire.delta_key("demo", "alice") == "chronav/demo/delta/alice"
    assert wire.state_key("demo", "a") == "chronav/demo/state/a"
    assert wire.member_key("demo", "a") == "chronav/demo/members/a"
    assert wire.last_chunk("chronav/demo/delta/alice") == "alice"


def base(**over):
    message = {"format": "chronav-dsr/1", "kind": "delta", "graph": "g", "agent": "a",
               "replica": 5, "nodes": [{"id": 9, "add": [[5, 100]],
                                        "meta": [100, 5, "room", "r"],
                                        "attrs": {"x": [100, 5, 1.5]}}]}
    message.update(over)
    return orjson.dumps(message)


@pytest.mark.parametrize("payload", [
    b"\x00\xff garbage", b"", b"[]", b'{"format": "chronav-dsr/2"}',
    base(kind="gossip"), base(replica=0), base(replica="5"), base(extra=1),
    base(nodes=[{"id": 0}]), base(nodes=[{"id": 9, "attrs": {"x": [1, 5, {"a": 1}]}}]),
    base(nodes=[{"id": 9, "attrs": {"x": [1, 5, [1.0, "a"]]}}]),
    base(nodes=[{"id": 9, "meta": [1, 5, "bad type", "r"]}]),
    base(nodes=[{"id": 9, "add": [[5, -1]]}]), base(edges=[{"src": 1, "dst": 2}]),
    base(graph="a/b"), base(nodes=[{"id": 9, "attrs": {"x": [1, 5, True, 1]}}]),
    b'{"format":"chronav-dsr/1","kind":"delta","graph":"g","agent":"a","replica":5,'
    b'"nodes":[{"id":9,"attrs":{"x":[1,5,NaN]}}]}',
])
def test_invalid_messages_raise_wire_error(payload):
    with pytest.raises(WireError, match="invalid DSR message"):
        wire.decode(payload)


def test_error_names_the_field():
    with pytest.raises(WireError, match=r"nodes\.0\.id"):
        wire.decode(base(nodes=[{"id": -3}]))


def test_foreign_writer_detected():
    assert wire.foreign_writer(wire.decode(base())) is None
    forged = base(nodes=[{"id": 9, "add": [[6, 100]]}])
    assert "replica 6" in wire.foreign_writer(wire.decode(forged))
    forged = base(nodes=[{"id": 9, "attrs": {"x": [100, 7, 1.0]}}])
    assert "replica 7" in wire.foreign_writer(wire.decode(forged))
    observed = base(nodes=[{"id": 9, "rem": [[6, 100]], "cleared": 101}])
    assert wire.foreign_writer(wire.decode(observed)) is None
    assert wire.max_hlc(wire.decode(observed)) == 101


def test_value_types_survive_the_wire():
    g = DSRGraph("a")
    values = {"b": True, "i": 1, "f": 1.0, "s": "1", "lf": [1.0, 2.0], "ls": ["x"], "e": []}
    payload = delta_of(g, lambda x: x.insert_node("object", "o", values))
    fresh = DSRGraph("b")
    fresh.apply_message(wire.decode(payload))
    attrs = fresh.get_node_by_name("o").attrs
    assert attrs == values
    assert {k: type(v) for k, v in attrs.items()} == {k: type(v) for k, v in values.items()}


# ---- the fast validator must never accept what the pydantic schema refuses -----------------

from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

_scalars = st.one_of(
    st.none(), st.booleans(), st.integers(-(2**70), 2**70),
    st.sampled_from([0, 1, -1, 2**63 - 1, 2**63, -(2**63), -(2**63) - 1, 2**64]),
    st.floats(allow_nan=False, allow_infinity=False), st.sampled_from([1e19, -1e19, 0.5]),
    st.text(max_size=6), st.sampled_from(["room", "a b", "x\n", "", "#1", "agent.1", "a/b",
                                          "a\\b", "q\"", "\x7f", "\u00e9t\u00e9", "x" * 300]),
    st.sampled_from([["a", "b"], [1, "a"], ["a", 1], [1, 2.5], ["\n"], [True], [2**63],
                     [-(2**63)], [[5, 1], [5, 9]], [[5, 9], [6, 1], [5, 1]]]))
_json = st.recursive(_scalars, lambda inner: st.one_of(
    st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=4), inner, max_size=3)),
    max_leaves=8)
_PATHS = [("format",), ("kind",), ("graph",), ("agent",), ("replica",), ("writers",),
          ("nodes",), ("edges",), ("nodes", 0), ("nodes", 0, "id"), ("nodes", 0, "add"),
          ("nodes", 0, "add", 0), ("nodes", 0, "add", 0, 1), ("nodes", 0, "rem"),
          ("nodes", 0, "cleared"), ("nodes", 0, "meta"), ("nodes", 0, "meta", 2),
          ("nodes", 0, "meta", 3), ("nodes", 0, "attrs"), ("nodes", 0, "attrs", "x"),
          ("nodes", 0, "attrs", "x", 2), ("nodes", 0, "attrs", "x", 1), ("nodes", 0, "extra"),
          ("edges", 0, "src"), ("edges", 0, "type"), ("edges", 0, "attrs", "w", 2),
          ("edges", 0, "rem", 0, 0), ("writers", "5"), ("clock",), ("seen",), ("seen", "5"),
          ("nodes", 0, "attrs", "l", 2), ("nodes", 0, "attrs", "k\\1"),
          ("nodes", 0, "attrs", "k\n"), ("edges", 0, "add"), ("edges", 0, "dst"), ("writers", "05"),
          ("seen", "9223372036854775808"),
          ("edges", 0, "attrs", "w")]


def _template() -> dict:
    return {"format": "chronav-dsr/1", "kind": "state", "graph": "g", "agent": "a", "replica": 5,
            "writers": {"5": "a"}, "clock": 200, "seen": {"5": 200, "6": 50},
            "nodes": [{"id": 9, "add": [[5, 100]], "rem": [[6, 50]], "cleared": 60,
                       "meta": [100, 5, "room", "r"],
                       "attrs": {"x": [100, 5, 1.5], "l": [100, 5, [1, 2.5]]}}],
            "edges": [{"src": 9, "dst": 9, "type": "in", "add": [[5, 101], [5, 7]],
                       "rem": [[5, 1]], "attrs": {"w": [101, 5, "s"]}}]}


def _put(document: dict, path: tuple, value: object) -> None:
    """Replace the value at `path` (skipped if an earlier mutation removed the path)."""
    target = document
    try:
        for step in path[:-1]:
            target = target[step]
        if (isinstance(target, list) and isinstance(path[-1], int) and path[-1] < len(target)) \
                or isinstance(target, dict):
            target[path[-1]] = value
    except (KeyError, IndexError, TypeError):
        pass


def _same(a: wire.Decoded, b: wire.Decoded) -> bool:
    return all(getattr(a, f) == getattr(b, f) for f in
               ("kind", "graph", "agent", "replica", "writers", "nodes", "edges", "top_hlc",
                "clock", "seen"))


def _check_validators_agree(document: dict, ascii_only: bool = False) -> wire.Decoded | None:
    """If the fast path accepts `document` it builds what pydantic builds; decode() raises
    exactly when pydantic refuses.  Returns the fast path's result."""
    import json
    try:
        payload = json.dumps(document).encode() if ascii_only else orjson.dumps(document)
    except TypeError:   # e.g. an int beyond 64 bits: orjson refuses, encode as text
        payload = json.dumps(document).encode()
    structs = wire.struct_decode(payload)
    try:
        slow = wire._from_model(wire.Message.model_validate_json(payload))
    except Exception:  # noqa: BLE001
        slow = None
    if structs is not None:
        assert slow is not None, f"the fast path accepted what pydantic refuses: {document}"
        assert _same(structs, slow)
    if slow is None:
        with pytest.raises(WireError, match="invalid DSR message"):
            wire.decode(payload)
    else:
        assert _same(wire.decode(payload), slow)
    return structs


@settings(max_examples=400, deadline=None)
@given(mutations=st.lists(st.tuples(st.sampled_from(_PATHS), _json), max_size=3))
def test_fast_validator_agrees_with_pydantic(mutations):
    document = _template()
    for path, value in mutations:
        _put(document, path, value)
    structs = _check_validators_agree(document)
    if not mutations:
        assert structs is not None


# well-formed shapes with leaves at and beyond every bound (the mutations above mostly break the
# shape, so they rarely reach the fast path's value checks)
_u63 = st.one_of(st.integers(0, 2**63 - 1), st.sampled_from([0, 2**63 - 1, 2**63, -1, 2**64]))
_replica = st.one_of(st.integers(1, 2**63 - 1), st.sampled_from([1, 2**63 - 1, 0, 2**63]))
_float = st.one_of(st.floats(allow_nan=False, allow_infinity=False),
                   st.sampled_from([2.0**63, -(2.0**63), 9.2e18, -9.2e18, -0.0]))
_number = st.one_of(st.integers(-(2**64), 2**64), _float,
                    st.sampled_from([2**63 - 1, -(2**63), 2**63, -(2**63) - 1]))
_texts = st.one_of(st.text(max_size=4), st.sampled_from(["room", "a-b", "9x", "", "x" * 65,
                                                          "a\nb", "\u00e9", "q\"\\", "~removed"]))
_value = st.one_of(st.booleans(), _number, _texts, st.lists(_number, max_size=3),
                   st.lists(_texts, max_size=3), st.lists(st.one_of(_number, _texts), max_size=3))
_dots = st.lists(st.tuples(_replica, _u63).map(list), max_size=3)
_attrs = st.dictionaries(_texts, st.tuples(_u63, _replica, _value).map(list), max_size=3)
_entry = {"add": _dots, "rem": _dots, "cleared": _u63, "attrs": _attrs}
_node = st.fixed_dictionaries({"id": _replica}, optional={
    **_entry, "meta": st.one_of(st.none(), st.tuples(_u63, _replica, _texts, _texts).map(list))})
_edge = st.fixed_dictionaries({"src": _replica, "dst": _replica, "type": _texts},
                              optional=_entry)
_agent = st.one_of(st.sampled_from(["a", "g", "agent.1", "a/b", "", "-a"]), st.text(max_size=3))
_replica_key = st.sampled_from(["5", "05", "9223372036854775807", "9223372036854775808", "x"])
_message = st.fixed_dictionaries(
    {"format": st.just("chronav-dsr/1"), "kind": st.sampled_from(["delta", "state", "digest"]),
     "graph": _agent, "agent": _agent, "replica": _replica},
    optional={"writers": st.dictionaries(_replica_key, _agent, max_size=2), "clock": _u63,
              "seen": st.dictionaries(_replica_key, _u63, max_size=2),
              "nodes": st.lists(_node, max_size=3), "edges": st.lists(_edge, max_size=3)})


@settings(max_examples=300, deadline=None)
@given(document=_message, ascii_only=st.booleans())
def test_struct_validator_agrees_with_pydantic_on_well_formed_shapes(document, ascii_only):
    _check_validators_agree(document, ascii_only)


def test_struct_path_limits_and_escapes():
    """The struct path's conservative cuts defer to pydantic, never refuse."""
    from dsr.limits import LIMITS
    cap = LIMITS.max_value_bytes // 4
    for text, struct_takes in (("x" * cap, True), ("x" * (cap + 1), False),
                               ("\u00e9" * cap, True), ("a\\b", True)):
        payload = base(nodes=[{"id": 9, "attrs": {"s": [1, 5, text]}}])
        assert (wire.struct_decode(payload) is not None) is struct_takes, len(text)
        assert wire.decode(payload).nodes[0][1].attrs["s"][2] == text
    escaped = base(nodes=[{"id": 9, "meta": [1, 5, "room", "a\nb"]}])
    assert wire.struct_decode(escaped) is None
    with pytest.raises(WireError, match="invalid DSR message"):
        wire.decode(escaped)
    huge = "x" * (LIMITS.max_value_bytes + 1)
    with pytest.raises(WireError, match="bytes per value"):
        wire.decode(base(nodes=[{"id": 9, "attrs": {"s": [1, 5, [huge]]}}]))
    strings = base(nodes=[{"id": 9, "attrs": {"s": [1, 5, ["a", "b"]], "f": [1, 5, [1, 2]]}}])
    decoded = wire.struct_decode(strings)
    assert decoded is not None and decoded.nodes[0][1].attrs["f"][2] == [1.0, 2.0]
