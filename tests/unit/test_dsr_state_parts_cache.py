"""The state a replica serves is the same bytes whether its elements come from the cache of
encoded elements (DSRGraph.state_parts) or are encoded afresh, through every kind of change:
local writes, transactions rolled back, remote deltas and states, removals, compaction."""

from __future__ import annotations

import random

import pytest

from dsr import DSRGraph, wire


def fresh_parts(graph: DSRGraph, per_part: int) -> list[bytes]:
    """What state_parts must return, encoded without any cache."""
    clock = graph.clock.last
    node_ids, edge_keys = list(graph.node_states), list(graph.edge_states)
    chunks = [(node_ids[i:i + per_part], []) for i in range(0, len(node_ids), per_part)]
    chunks += [([], edge_keys[i:i + per_part]) for i in range(0, len(edge_keys), per_part)]
    chunks = chunks or [([], [])]
    seen = {graph.replica_id: clock}
    return [wire.encode(kind="state", graph=graph.graph_name, agent=graph.agent,
                        replica=graph.replica_id,
                        nodes=[(i, graph.node_states[i]) for i in ids],
                        edges=[(k, graph.edge_states[k]) for k in keys],
                        writers=graph.served_writers(),
                        clock=clock if n == len(chunks) - 1 else 0,
                        seen=seen if n == len(chunks) - 1 else None)
            for n, (ids, keys) in enumerate(chunks)]


class Boom(Exception):
    pass


def random_step(rng: random.Random, me: DSRGraph, other: DSRGraph, other_out: list[bytes]) -> None:
    nodes = [n.id for n in me.nodes()]
    other_nodes = [n.id for n in other.nodes()]
    action = rng.randrange(9)
    if action == 0 or len(nodes) < 3:
        me.insert_node("object", f"n{rng.randrange(10**9)}", {"x": rng.random()})
    elif action == 1:
        me.update_node(rng.choice(nodes), {"x": rng.random(), "k": rng.randrange(3)})
    elif action == 2:
        me.update_nodes({i: {"y": rng.random()} for i in rng.sample(nodes, min(3, len(nodes)))})
    elif action == 3:
        me.delete_node(rng.choice(nodes))
    elif action == 4:
        src, dst = rng.sample(nodes, 2)
        me.insert_or_assign_edge(src, dst, "RT", {"x": rng.random(), "y": 0.0, "theta": 0.0})
    elif action == 5:
        edges = me.edges()
        if edges:
            edge = rng.choice(edges)
            me.delete_edge(edge.src, edge.dst, edge.type)
    elif action == 6:                       # a transaction that fails: rolled back
        with pytest.raises(Boom), me.transaction():
            me.update_node(rng.choice(nodes), {"x": -1.0})
            me.insert_node("object", f"t{rng.randrange(10**9)}")
            raise Boom
    elif action == 7:                       # the other replica writes; its deltas arrive here
        if other_nodes:
            other.update_node(rng.choice(other_nodes), {"x": rng.random()})
            if rng.random() < 0.5:
                other.delete_node(rng.choice(other_nodes))
        other.insert_node("object", f"o{rng.randrange(10**9)}", {"z": 1})
        for payload in other_out:
            me.apply_message(wire.decode(payload))
        other_out.clear()
    else:                                   # a whole state, and tombstones forgotten
        me.apply_message(wire.decode(other.state_message()))
        me.compact(lambda replica, hlc: True)


@pytest.mark.parametrize("seed", range(6))
def test_cached_state_parts_equal_a_fresh_encoding(seed: int) -> None:
    rng = random.Random(seed)
    me, other = DSRGraph("me"), DSRGraph("other")
    other_out: list[bytes] = []
    other.attach(other_out.append, linger_s=0.0)
    per_part = rng.choice([1, 3, 7, 2000])
    for step in range(150):
        random_step(rng, me, other, other_out)
        if step % 3 == 0:
            assert list(me.state_parts(per_part=per_part)) == fresh_parts(me, per_part), step


def test_a_change_reencodes_only_that_element() -> None:
    graph = DSRGraph("me")
    ids = [graph.insert_node("object", f"n{i}", {"x": i}).id for i in range(50)]
    list(graph.state_parts())
    table = graph._node_table         # the cache under test (dsr/table.py)
    cached = {i: table.cached(i) for i in ids}
    graph.update_node(ids[7], {"x": -7})
    parts = list(graph.state_parts())
    assert parts == fresh_parts(graph, 2000)
    changed = [i for i in ids if table.cached(i)[2] is not cached[i][2]]
    assert changed == [ids[7]]
