"""Local DSRGraph API: queries, writes, transactions, signals, views and documents."""

from __future__ import annotations

import math
import threading

import networkx as nx
import pytest

from dsr import (DSRGraph, EdgeNotFoundError, GraphFileError, InvalidAttributeError,
                 InvalidIdentifierError, NameTakenError, NodeNotFoundError, PoseError,
                 ReadOnlyGraphError, TransactionError, wire)


@pytest.fixture
def g() -> DSRGraph:
    return DSRGraph("tester")


def test_insert_query_update(g):
    w = g.insert_node("world", "world")
    alice = g.insert_node("person", "alice", {"role": "resident", "age": 81, "pose": [1, 2.5]})
    assert g.get_node(alice.id) == alice
    assert alice.attrs["pose"] == [1.0, 2.5] and isinstance(alice.attrs["pose"][0], float)
    assert g.get_node_by_name("alice").id == alice.id
    assert [n.name for n in g.nodes_of_type("person")] == ["alice"]
    g.update_node(alice.id, {"age": 82, "x": 1.5})
    assert g.get_node(alice.id).attrs == {"role": "resident", "age": 82, "pose": [1.0, 2.5],
                                          "x": 1.5}
    assert g.get_attr(alice.id, "x") == 1.5 and g.get_attr(alice.id, "nope", 7) == 7
    assert len(g) == 2 and w.id in g


def test_ids_are_unique_64_bit_and_explicit_ids_are_kept(g):
    ids = {g.insert_node("object", f"o{i}").id for i in range(100)}
    assert len(ids) == 100 and all(2**32 < i < 2**63 for i in ids)
    other = DSRGraph("other")
    assert not ids & {other.insert_node("object", f"o{i}").id for i in range(100)}
    assert g.insert_node("world", "world", id=1).id == 1
    with pytest.raises(InvalidIdentifierError):
        g.insert_node("world", "world2", id=1)


def test_edges_queries_and_delete_node_removes_edges(g):
    w, r, p = (g.insert_node(t, n) for t, n in [("world", "w"), ("room", "r"), ("person", "p")])
    g.insert_or_assign_edge(w.id, r.id, "RT", {"x": 1.0, "y": 0.0, "theta": 0.0})
    g.insert_or_assign_edge(r.id, p.id, "RT", {"x": 0.5, "y": 0.0, "theta": 0.0})
    g.insert_or_assign_edge(p.id, r.id, "in")
    assert [e.dst for e in g.edges_from(r.id)] == [p.id]
    assert {e.type for e in g.edges_to(r.id)} == {"RT", "in"}
    assert [e.src for e in g.edges_to(r.id, "in")] == [p.id]
    assert len(g.edges_of_type("RT")) == 2
    edge = g.insert_or_assign_edge(w.id, r.id, "RT", {"x": 2.0})
    assert edge.attrs == {"x": 2.0, "y": 0.0, "theta": 0.0}
    g.delete_edge(p.id, r.id, "in")
    assert g.get_edge(p.id, r.id, "in") is None
    with pytest.raises(EdgeNotFoundError):
        g.delete_edge(p.id, r.id, "in")
    g.delete_node(r.id)
    assert g.edges() == [] and g.edges_from(w.id) == [] and g.get_node(r.id) is None
    with pytest.raises(NodeNotFoundError):
        g.update_node(r.id, {"x": 1.0})
    with pytest.raises(NodeNotFoundError):
        g.insert_or_assign_edge(w.id, r.id, "RT")


@pytest.mark.parametrize("attrs", [{"x": float("nan")}, {"x": {"a": 1}}, {"x": [1, "a"]},
                                   {"": 1}, {"x": 2**64}, {"x": None}, {"x": [True]}])
def test_bad_attributes_are_refused_with_the_key(g, attrs):
    node = g.insert_node("object", "cup")
    with pytest.raises(InvalidAttributeError):
        g.update_node(node.id, attrs)
    assert g.get_node(node.id).attrs == {}


@pytest.mark.parametrize(("type_", "name"), [("", "a"), ("a b", "a"), ("room", ""),
                                              ("room", "x#1"), ("room", "a\nb")])
def test_bad_identifiers(g, type_, name):
    with pytest.raises(InvalidIdentifierError):
        g.insert_node(type_, name)


def test_names_are_unique_locally(g):
    g.insert_node("person", "alice")
    with pytest.raises(NameTakenError):
        g.insert_node("person", "alice")


def test_transaction_is_one_delta_and_rolls_back(g):
    sent: list[bytes] = []
    g.attach(sent.append)
    with g.transaction():
        a = g.insert_node("room", "a")
        b = g.insert_node("room", "b")
        g.insert_or_assign_edge(a.id, b.id, "connected", {"door": "d1"})
        g.update_node(a.id, {"area": 3.0})
    assert len(sent) == 1
    message = wire.decode(sent[0])
    assert {i for i, _ in message.nodes} == {a.id, b.id} and len(message.edges) == 1
    before = g.digest()
    with pytest.raises(RuntimeError), g.transaction():
        g.delete_node(a.id)
        g.update_node(b.id, {"area": 9.0})
        g.insert_node("room", "c")
        raise RuntimeError("abort")
    assert g.digest() == before and len(sent) == 1
    assert g.get_node_by_name("c") is None and g.get_edge(a.id, b.id, "connected") is not None


def test_a_rolled_back_transaction_leaves_the_replicated_state_as_it_was(g):
    """Undo restores the CRDT state itself (nodes and edges alike, created, changed or removed
    in the block), not only what queries show: the replica equals one that never saw it."""
    sent: list[bytes] = []
    g.attach(sent.append)
    a = g.insert_node("room", "a", {"area": 1.0})
    b = g.insert_node("room", "b")
    g.insert_or_assign_edge(a.id, b.id, "connected", {"door": "d1"})
    reference = DSRGraph("reference")
    for payload in sent:
        reference.apply_message(wire.decode(payload))
    assert g.state_equals(reference)
    with pytest.raises(RuntimeError), g.transaction():
        c = g.insert_node("room", "c")
        g.insert_or_assign_edge(b.id, c.id, "connected")          # a new edge
        g.insert_or_assign_edge(a.id, b.id, "connected", {"door": "d2"})
        g.update_node(a.id, {"area": 2.0})
        g.delete_edge(a.id, b.id, "connected")                      # an edge removed
        raise RuntimeError("abort")
    assert g.state_equals(reference) and g.tombstones() == 0
    assert g.edges_from(b.id) == [] and g.edges_to(b.id)[0].attrs == {"door": "d1"}
    assert g.get_node_by_name("c") is None and len(sent) == 3


def test_signals_are_delivered_by_dispatch_only(g):
    seen: list[tuple] = []
    for signal in ("node_added", "node_updated", "node_deleted", "edge_added", "edge_updated",
                   "edge_deleted"):
        g.connect(signal, lambda *args, s=signal: seen.append((s, *args)))
    a = g.insert_node("room", "a")
    b = g.insert_node("room", "b")
    g.insert_or_assign_edge(a.id, b.id, "connected")
    g.insert_or_assign_edge(a.id, b.id, "connected", {"door": "x"})
    g.update_node(a.id, {"area": 1.0})
    g.delete_node(b.id)
    assert seen == []
    assert g.dispatch() == 7
    kinds = [s[0] for s in seen]
    assert kinds == ["node_added", "node_added", "edge_added", "edge_updated", "node_updated",
                     "edge_deleted", "node_deleted"]
    assert seen[3][2] == ["door"] and seen[4][2] == ["area"]
    assert seen[5][1:] == (a.id, b.id, "connected") and seen[6][1] == b.id


def test_callbacks_run_on_dispatching_thread_without_lock(g):
    threads: list[int] = []

    def on_added(node):
        threads.append(threading.get_ident())
        if node.name == "remote":
            g.insert_node("object", "reaction")   # would deadlock if called under another lock

    g.connect("node_added", on_added)
    other = DSRGraph("other")
    sent: list[bytes] = []
    other.attach(sent.append)
    other.insert_node("object", "remote")
    worker = threading.Thread(target=lambda: g.apply_message(wire.decode(sent[0])))
    worker.start()
    worker.join()
    assert threads == []
    assert g.dispatch(timeout=1.0) == 1
    g.dispatch()
    assert set(threads) == {threading.get_ident()}
    assert g.get_node_by_name("reaction") is not None


def test_dispatch_waits_for_a_remote_event(g):
    other = DSRGraph("other")
    sent: list[bytes] = []
    other.attach(sent.append)
    other.insert_node("object", "late")
    got: list[str] = []
    g.connect("node_added", lambda node: got.append(node.name))
    timer = threading.Timer(0.05, lambda: g.apply_message(wire.decode(sent[0])))
    timer.start()
    assert g.dispatch(timeout=5.0) == 1 and got == ["late"]
    assert g.dispatch(timeout=0.01) == 0


def test_dispatch_inside_transaction_and_bad_signal(g):
    with pytest.raises(TransactionError), g.transaction():
        g.dispatch()
    with pytest.raises(ValueError, match="unknown signal"):
        g.connect("node_moved", print)


def test_failing_callback_is_counted_not_fatal(g):
    g.connect("node_added", lambda node: 1 / 0)
    got: list[int] = []
    g.connect("node_added", lambda node: got.append(node.id))
    g.insert_node("object", "x")
    assert g.dispatch() == 1 and g.callback_errors == 1 and len(got) == 1


def test_read_only_refuses_writes():
    g = DSRGraph("viewer", read_only=True)
    with pytest.raises(ReadOnlyGraphError):
        g.insert_node("object", "x")


def test_world_pose_composes_rt_chain(g):
    w = g.insert_node("world", "world")
    room = g.insert_node("room", "room")
    robot = g.insert_node("robot", "robot")
    g.insert_or_assign_edge(w.id, room.id, "RT", {"x": 10.0, "y": 0.0, "theta": math.pi / 2})
    g.insert_or_assign_edge(room.id, robot.id, "RT", {"x": 1.0, "y": 0.0, "theta": 0.0})
    x, y, theta = g.world_pose(robot.id)
    assert (x, y, theta) == pytest.approx((10.0, 1.0, math.pi / 2))
    assert g.world_pose(w.id) == (0.0, 0.0, 0.0)
    assert g.rt_parent(robot.id).src == room.id
    g.insert_or_assign_edge(robot.id, w.id, "RT", {"x": 0.0, "y": 0.0, "theta": 0.0})
    with pytest.raises(PoseError, match="cycle"):
        g.world_pose(robot.id)


def test_world_pose_needs_pose_attributes(g):
    w = g.insert_node("world", "world")
    r = g.insert_node("room", "room")
    g.insert_or_assign_edge(w.id, r.id, "RT", {"x": 1.0})
    with pytest.raises(PoseError, match="theta"):
        g.world_pose(r.id)


def test_networkx_view(g):
    a = g.insert_node("room", "a", {"area": 2.0})
    b = g.insert_node("room", "b")
    g.insert_or_assign_edge(a.id, b.id, "connected", {"door": "d"})
    view = g.to_networkx()
    assert isinstance(view, nx.MultiDiGraph)
    assert view.nodes[a.id] == {"area": 2.0, "type": "room", "name": "a"}
    assert view.edges[a.id, b.id, "connected"] == {"door": "d", "type": "connected"}


def test_json_round_trip(g):
    w = g.insert_node("world", "world", id=1)
    r = g.insert_node("room", "kitchen", {"area": 12.5, "tags": ["a", "b"], "open": True})
    g.insert_or_assign_edge(w.id, r.id, "RT", {"x": 1.0, "y": 2.0, "theta": 0.0})
    copy = DSRGraph.from_json(g.to_json(), agent="copy")
    assert copy.digest() == g.digest()
    assert copy.get_node_by_name("kitchen").attrs["open"] is True


def test_document_with_names_and_file_errors(tmp_path):
    path = tmp_path / "world.json"
    path.write_text('{"nodes": [{"id": 1, "type": "world", "name": "world"},'
                    ' {"type": "room", "name": "hall", "attrs": {"area": 3}}],'
                    ' "edges": [{"src": "world", "dst": "hall", "type": "RT",'
                    ' "attrs": {"x": 1.0, "y": 1.0, "theta": 0.0}}]}')
    g = DSRGraph.load(str(path), agent="loader")
    hall = g.get_node_by_name("hall")
    assert g.world_pose(hall.id) == (1.0, 1.0, 0.0)
    path.write_text('{"nodes": [{"type": "room", "name": "a", "attrs": {"x": [1, "b"]}}]}')
    with pytest.raises(GraphFileError, match=r"world.json: nodes.0.attrs.x"):
        DSRGraph.load(str(path), agent="loader")
    path.write_text('{"nodes": [{"type": "room", "name": "a"}, {"type": "room", "name": "a"}]}')
    with pytest.raises(GraphFileError, match="already used"):
        DSRGraph.load(str(path), agent="loader")
    path.write_text('{"nodes": [], "edges": [{"src": "ghost", "dst": 1, "type": "in"}]}')
    with pytest.raises(GraphFileError, match="ghost"):
        DSRGraph.load(str(path), agent="loader")
    with pytest.raises(GraphFileError, match="cannot read"):
        DSRGraph.load(str(tmp_path / "missing.json"), agent="loader")
