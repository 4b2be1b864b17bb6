"""The DSR protocol rules of docs/dsr_wire_format.md, through the real transport hooks.

Each replica here is a `Replica` that is never opened: received messages are handed to its
admission API (`admit_delta`, `admit_state`: what its Zenoh callbacks call) directly, and its
publisher is a function, so the rules (limits, clock offset, removals, trust in states,
digests, compaction, per-reason counters, local policy checks) are exercised exactly as over
Zenoh, without processes.
"""

from __future__ import annotations

import dataclasses
import logging
import time
from pathlib import Path

import orjson
import pytest

from dsr import DSRGraph, InvalidAttributeError, WireError, WriteRefusedError, wire
from dsr.crdt import REMOVAL_RECEIPT
from dsr.hlc import pack
from dsr.limits import LIMITS, Limits
from agents.world.write_policy import policy_from_env
from dsr.policy import AllowAll
from dsr.transport import Replica

POLICY = policy_from_env({})
#: a received message as `Replica.admit_delta` / `admit_state` take it: (key, payload)
Received = tuple[str, bytes]


class Publisher:
    def __init__(self, deliver) -> None:
        self.deliver = deliver

    def put(self, payload: bytes) -> None:
        self.deliver(payload)


class Net:
    """Replicas wired together in memory: every published delta or digest reaches the others'
    `admit_delta`, in order (like one Zenoh publisher per replica).  A joiner merges one
    member's state, then every member's (the round after the join); every member merges the
    joiner's (its token appeared): as over Zenoh, each running writer's watermark starts from
    its own state."""

    def __init__(self, policy: object = None) -> None:
        self.replicas: dict[str, Replica] = {}
        self.policy = policy

    def add(self, agent: str, joined: bool = True) -> Replica:
        graph = DSRGraph(agent)
        replica = Replica(graph, policy=self.policy)  # type: ignore[arg-type]
        replica.joined = joined
        for other in self.replicas.values():   # a joiner starts from someone's state
            replica.admit_state(*state_of(other))
            break
        replica._publisher = Publisher(lambda payload, a=agent: self._deliver(a, payload))
        graph.attach(replica._publish, linger_s=0.0)
        for name, other in self.replicas.items():
            other.members.add(agent)
            replica.members.add(name)
        for other in self.replicas.values():
            replica.admit_state(*state_of(other))
            other.admit_state(*state_of(replica))
        self.replicas[agent] = replica
        return replica

    def _deliver(self, sender: str, payload: bytes) -> None:
        for name, replica in self.replicas.items():
            if name != sender:
                replica.admit_delta(wire.delta_key("chronav", sender), payload)

    def maintain(self) -> None:
        for replica in self.replicas.values():
            replica.maintain()

    def route(self, sender: str, *receivers: str) -> None:
        """From now on ``sender``'s deltas reach only ``receivers`` (lost on the way to the rest)."""
        def deliver(payload: bytes) -> None:
            for name in receivers:
                self.replicas[name].admit_delta(wire.delta_key("chronav", sender), payload)
        self.replicas[sender]._publisher = Publisher(deliver)


def state_of(replica: Replica, payload: bytes | None = None) -> Received:
    """(key, payload) of `replica`'s state reply (or of `payload` on its state key)."""
    graph = replica.graph
    return (wire.state_key("chronav", graph.agent),
            payload if payload is not None else graph.state_message(replica.seen()))


def delta_of(agent: str, message: dict) -> Received:
    return wire.delta_key("chronav", agent), orjson.dumps(message)


def raw_delta(graph: DSRGraph, nodes: list[dict], edges: list[dict] | None = None) -> dict:
    return {"format": wire.FORMAT, "kind": "delta", "graph": "chronav", "agent": graph.agent,
            "replica": graph.replica_id, "nodes": nodes, "edges": edges or []}


# ---------------------------------------------------------------------------- integers, sizes
@pytest.mark.parametrize("literal", [b"9223372036854775808", b"18446744073709551616",
                                     b"-9223372036854775809", b"[1, 18446744073709551616]"])
def test_integers_beyond_int64_are_refused_not_turned_into_floats(literal):
    payload = (b'{"format":"chronav-dsr/1","kind":"delta","graph":"g","agent":"a","replica":5,'
               b'"nodes":[{"id":9,"attrs":{"x":[1,5,' + literal + b']}}]}')
    with pytest.raises(WireError, match="int64"):
        wire.decode(payload)


def test_large_floats_written_as_floats_are_still_floats():
    payload = (b'{"format":"chronav-dsr/1","kind":"delta","graph":"g","agent":"a","replica":5,'
               b'"nodes":[{"id":9,"attrs":{"x":[1,5,1e19],"l":[1,5,[2.5e30]]}}]}')
    state = wire.decode(payload).nodes[0][1]
    assert state.attrs["x"][2] == 1e19 and state.attrs["l"][2] == [2.5e30]


def test_value_and_message_limits_on_local_writes_and_on_receipt():
    graph = DSRGraph("a")
    big = "x" * (LIMITS.max_value_bytes + 1)
    with pytest.raises(InvalidAttributeError, match="CHRONAV_DSR_MAX_VALUE_BYTES"):
        graph.insert_node("object", "o", {"blob": big})
    with pytest.raises(InvalidAttributeError, match="per value"):
        graph.insert_node("object", "o", {"l": [0.0] * (LIMITS.max_value_bytes // 8 + 1)})
    assert len(graph) == 0
    node = graph.insert_node("object", "o", {"ok": "y" * 1000})
    chunk = "z" * (LIMITS.max_value_bytes - 10)
    with pytest.raises(InvalidAttributeError, match="CHRONAV_DSR_MAX_DELTA_BYTES"), \
            graph.transaction():
        for i in range(LIMITS.max_delta_bytes // LIMITS.max_value_bytes + 1):
            graph.insert_node("object", f"part{i}", {"k": chunk})   # (a node holds < 4 MiB)
    assert graph.get_node(node.id).attrs == {"ok": "y" * 1000}     # undone whole
    assert len(graph) == 1
    message = raw_delta(graph, [{"id": node.id, "attrs": {"blob": [1, graph.replica_id, big]}}])
    with pytest.raises(WireError, match="per value"):
        wire.decode(orjson.dumps(message))
    guard = Replica(DSRGraph("guard"))
    huge = orjson.dumps(raw_delta(graph, [])) + b" " * LIMITS.max_delta_bytes
    guard.admit_delta(wire.delta_key("chronav", "a"), huge)
    assert guard.stats.rejects == {"too_large": 1}


def test_node_limits_count_attributes_and_bytes_locally_and_on_receipt():
    """Issue #31: a node of 60,000 attributes (3.35 MB) was accepted by every agent."""
    writer, guard = DSRGraph("a"), Replica(DSRGraph("guard"))
    sent: list[bytes] = []
    writer.attach(sent.append)
    node = writer.insert_node("object", "o", {"x": 1.0})
    many = {f"k{i}": 1.0 for i in range(LIMITS.max_node_attrs)}
    with pytest.raises(InvalidAttributeError, match="CHRONAV_DSR_MAX_NODE_ATTRS"):
        writer.update_node(node.id, many)
    chunk = "z" * (LIMITS.max_value_bytes - 10)
    with pytest.raises(InvalidAttributeError, match="CHRONAV_DSR_MAX_NODE_BYTES"):
        for i in range(LIMITS.max_node_bytes // LIMITS.max_value_bytes + 1):
            writer.update_node(node.id, {f"s{i}": chunk})
    writer.flush()
    for payload in sent:
        guard.admit_delta(wire.delta_key("chronav", "a"), payload)
    assert guard.stats.rejects == {}
    held = len(guard.graph.get_node(node.id).attrs)
    # a foreign writer that does not check: the receivers count each limit under its reason
    stamp = writer.clock.tick()
    over = raw_delta(writer, [{"id": node.id, "attrs": {
        f"n{i}": [stamp, writer.replica_id, 0.0] for i in range(LIMITS.max_node_attrs)}}])
    guard.admit_delta(*delta_of("a", over))
    big = raw_delta(writer, [{"id": node.id, "attrs": {
        "s_last": [stamp, writer.replica_id, chunk]}}])
    guard.admit_delta(*delta_of("a", big))
    assert guard.stats.rejects == {"too_many_attrs": 1, "node_too_large": 1}
    assert len(guard.graph.get_node(node.id).attrs) == held
    # in a state reply, the node's entry is dropped and the rest merged
    document = orjson.loads(writer.state_message())
    document["nodes"][0]["attrs"].update(over["nodes"][0]["attrs"])
    document["nodes"].append({"id": 5, "add": [[writer.replica_id, stamp]],
                              "meta": [stamp, writer.replica_id, "object", "fine"]})
    guard.admit_state(wire.state_key("chronav", "a"), orjson.dumps(document))
    assert guard.stats.rejects["too_many_attrs"] == 2
    assert guard.graph.get_node_by_name("fine") is not None
    assert len(guard.graph.get_node(node.id).attrs) == held


def test_limits_come_from_the_environment_and_bad_values_name_the_variable():
    assert Limits.from_env({"CHRONAV_DSR_MAX_VALUE_BYTES": "1_000"}).max_value_bytes == 1000
    with pytest.raises(ValueError, match="CHRONAV_DSR_MAX_CLOCK_OFFSET_MS"):
        Limits.from_env({"CHRONAV_DSR_MAX_CLOCK_OFFSET_MS": "soon"})
    assert Limits.from_env({"CHRONAV_DSR_MAX_WAITING_DELTAS": "50"}).max_waiting_deltas == 50


def test_every_limit_is_documented_with_its_variable():
    doc = (Path(__file__).resolve().parents[2] / "docs" / "dsr_wire_format.md").read_text()
    table = doc[doc.index("## Limits"):doc.index("## Refusals")]
    for field in dataclasses.fields(Limits):
        var = f"CHRONAV_DSR_{field.name.upper()}"
        row = next((line for line in table.splitlines() if f"`{var}`" in line), None)
        assert row is not None, f"{var} is not in the Limits table of docs/dsr_wire_format.md"


def test_every_counter_and_refusal_reason_is_documented():
    from dsr.transport import REASONS, ReplicaStats
    doc = (Path(__file__).resolve().parents[2] / "docs" / "dsr_wire_format.md").read_text()
    section = doc[doc.index("## Refusals and counters"):]
    rows = [line for line in section.splitlines() if line.startswith("| `")]
    for field in dataclasses.fields(ReplicaStats):
        assert any(f"`{field.name}`" in row.split("|")[1] for row in rows), field.name
    for reason in REASONS:
        assert any(row.startswith(f"| `{reason}` |") for row in rows), reason


# ---------------------------------------------------------------------------- clock
def test_a_stamp_beyond_the_maximum_offset_is_refused_and_does_not_drag_the_clock():
    writer, guard = DSRGraph("w"), Replica(DSRGraph("guard"))
    now = guard.graph.clock.tick() >> 16
    ahead = pack(now + 55_000)
    node = {"id": 77, "add": [[writer.replica_id, ahead]],
            "meta": [ahead, writer.replica_id, "object", "future"]}
    guard.admit_delta(*delta_of("w", raw_delta(writer, [node])))
    assert guard.stats.rejects == {"clock_ahead": 1} and len(guard.graph) == 0
    assert guard.graph.clock.tick() >> 16 < now + 1000
    near = pack(now + LIMITS.max_clock_offset_ms // 2)
    node = {"id": 78, "add": [[writer.replica_id, near]],
            "meta": [near, writer.replica_id, "object", "soon"]}
    guard.admit_delta(*delta_of("w", raw_delta(writer, [node])))
    assert guard.stats.applied == 1 and guard.graph.get_node_by_name("soon") is not None


# ---------------------------------------------------------------------------- removals
def test_one_rule_for_removals_in_deltas_and_in_states():
    net = Net(POLICY)
    tool = net.add("agenda_tool-ward")
    other = net.add("executive")
    request = tool.graph.insert_node("agenda_request", "agenda_request/1",
                                     {"change": "{}", "requested_by": "ward"})
    state = tool.graph.element_state("node", request.id)
    # A removal as a foreign client might write it, without the receipt: refused as a delta...
    hlc = tool.graph.clock.tick()
    bare = {"id": request.id, "rem": list(state.add.items()), "cleared": hlc}
    other.admit_delta(*delta_of(tool.graph.agent, raw_delta(tool.graph, [bare])))
    assert other.stats.rejects == {"removal_receipt": 1}
    assert other.graph.get_node(request.id) is not None
    # ... and the same removal relayed in a state is refused for the same reason.
    document = orjson.loads(tool.graph.state_message())
    document["nodes"] = [{**n, "rem": bare["rem"], "cleared": hlc} for n in document["nodes"]]
    other.admit_state(*state_of(tool, orjson.dumps(document)))
    assert other.stats.rejects == {"removal_receipt": 2}
    assert other.graph.get_node(request.id) is not None
    # With the receipt (what DSRGraph.delete_node sends) it passes both ways, and an agent that
    # restarts and joins from a state keeps the node deleted (the divergence of issue 13).
    tool.graph.delete_node(request.id)
    assert other.graph.get_node(request.id) is None and other.stats.rejected_policy == 0
    restarted = Replica(DSRGraph("executive"), policy=POLICY)
    restarted.admit_state(*state_of(tool))
    assert restarted.graph.get_node(request.id) is None
    assert restarted.stats.rejected == restarted.stats.rejected_policy == 0
    assert restarted.graph.digest() == other.graph.digest()


# ---------------------------------------------------------------------------- trust in states
def forge_world() -> tuple[Net, Replica, Replica, Replica, int]:
    net = Net(POLICY)
    sim = net.add("sim_robot")
    with sim.graph.transaction():
        world = sim.graph.insert_node("world", "world")
        clock = sim.graph.insert_node("clock", "clock", {"now_s": 100.0})
        room = sim.graph.insert_node("room", "hall")
        sim.graph.insert_or_assign_edge(world.id, room.id, "RT", {"x": 0.0, "y": 0.0, "theta": 0.0})
    guard = net.add("executive")
    tool = net.add("agenda_tool-x")
    net.maintain()
    return net, sim, guard, tool, clock.id


def test_a_state_stamping_a_running_agents_replica_is_refused_and_logged(caplog):
    _net, sim, guard, tool, clock_id = forge_world()
    document = orjson.loads(tool.graph.state_message(tool.seen()))
    entry = next(n for n in document["nodes"] if n["id"] == clock_id)
    stamp = entry["attrs"]["now_s"][0] + 1
    sim.graph.update_node(clock_id, {"mode": "running"})   # sim_robot has published past stamp
    entry["attrs"]["now_s"] = [stamp, sim.graph.replica_id, 0.0]
    with caplog.at_level(logging.WARNING):
        guard.admit_state(*state_of(tool, orjson.dumps(document)))
    assert guard.graph.get_attr(clock_id, "now_s") == 100.0
    assert guard.stats.rejects.get("forged_stamp") == 1
    assert "never published" in guard.stats.last_reject
    assert any("forged_stamp" in r.message for r in caplog.records)
    # a stamp beyond what sim_robot has published yet is left for sim_robot itself
    entry["attrs"]["now_s"] = [guard.graph.clock.tick() + 10, sim.graph.replica_id, 0.0]
    guard.admit_state(*state_of(tool, orjson.dumps(document)))
    assert guard.graph.get_attr(clock_id, "now_s") == 100.0 and guard.stats.deferred == 1


def test_a_lying_writers_table_cannot_lend_a_running_agents_rights():
    _net, sim, guard, tool, _ = forge_world()
    fake = 4242424242
    hlc = tool.graph.clock.tick()
    document = orjson.loads(tool.graph.state_message(tool.seen()))
    document["writers"][str(fake)] = "sim_robot"
    document["nodes"].append({"id": 99, "add": [[fake, hlc]], "meta": [hlc, fake, "laser", "laser"],
                              "attrs": {"ranges": [hlc, fake, [1.0, 2.0]]}})
    guard.admit_state(*state_of(tool, orjson.dumps(document)))
    assert guard.graph.get_node_by_name("laser") is None
    assert guard.stats.rejects.get("forged_writer") == 1
    assert "never used or vouched" in guard.stats.last_reject
    # sim_robot itself may vouch for its previous incarnations in its own state
    document = orjson.loads(sim.graph.state_message(sim.seen()))
    document["writers"][str(fake)] = "sim_robot"
    document["nodes"].append({"id": 98, "add": [[fake, hlc]], "meta": [hlc, fake, "room", "l2"]})
    guard.admit_state(*state_of(sim, orjson.dumps(document)))
    assert guard.graph.get_node_by_name("l2") is not None


# ---------------------------------------------------------------------------- observability
def test_refusals_are_counted_and_logged_per_reason(caplog):
    guard = Replica(DSRGraph("guard"), policy=POLICY)
    with caplog.at_level(logging.WARNING):
        for _ in range(30):
            guard.admit_delta(wire.delta_key("chronav", "x"), b"junk")
        rogue = DSRGraph("rogue")
        rogue.attach(lambda p: guard.admit_delta(wire.delta_key("chronav", "rogue"), p))
        rogue.insert_node("robot", "robot")
    assert guard.stats.rejects == {"invalid": 30, "policy": 1}
    lines = [r.message for r in caplog.records]
    assert sum("[invalid]" in line for line in lines) == 20     # its own budget ran out...
    assert any("[policy]" in line for line in lines)              # ...not the policy's


# ---------------------------------------------------------------------------- local policy
def test_local_writes_outside_the_grant_raise_naming_the_rule():
    net = Net(POLICY)
    sim = net.add("sim_robot")
    robot = sim.graph.insert_node("robot", "robot", {"pose_stamp": 1.0})
    nav = net.add("social_navigation")
    nav.graph.update_node(robot.id, {"cmd_vx": 0.2})                      # granted
    with pytest.raises(WriteRefusedError) as refused:
        nav.graph.update_node(robot.id, {"pose_stamp": 2.0})
    text = str(refused.value)
    assert "'social_navigation'" in text and "'pose_stamp'" in text and "'robot' node" in text
    assert "write_policy.yaml" in text
    with pytest.raises(WriteRefusedError, match="may not delete a 'robot' node"):
        nav.graph.delete_node(robot.id)
    with pytest.raises(WriteRefusedError, match="may not create a 'mission' node"), \
            nav.graph.transaction():
        nav.graph.insert_node("mission", "m")
    assert nav.graph.get_attr(robot.id, "pose_stamp") == 1.0 and len(nav.graph) == 1
    assert nav.graph.digest() == sim.graph.digest()                     # no divergence
    free = DSRGraph("social_navigation")                                 # library use
    Replica(free, policy=AllowAll())
    free.insert_node("robot", "robot", {"pose_stamp": 1.0})


# ---------------------------------------------------------------------------- memory
def test_deleted_values_are_not_kept_and_not_relayed():
    graph = DSRGraph("a")
    blob = "b" * 200_000
    node = graph.insert_node("object", "o", {"blob": blob})
    graph.delete_node(node.id)
    assert len(graph.state_message()) < 2_000
    assert set(graph.element_state("node", node.id).attrs) == {REMOVAL_RECEIPT}


def test_tombstones_are_compacted_once_every_member_has_seen_the_removal():
    """100,000 insert/delete cycles leave a state reply within 10% of the live content."""
    net = Net()
    a, b = net.add("a"), net.add("b")
    live = [a.graph.insert_node("object", f"live{i}", {"x": float(i)}) for i in range(50)]
    graph = a.graph
    for batch in range(1000):             # 100 cycles per delta, to keep the test fast
        with graph.transaction():
            for cycle in range(batch * 100, batch * 100 + 100):
                node = graph.insert_node("object", f"tmp{cycle % 7}", {"v": cycle, "s": "x"})
                graph.delete_node(node.id)
        if batch % 200 == 199:
            net.maintain()
    assert graph.tombstones() > 0            # b's last digest predates the last removals
    net.maintain()
    net.maintain()
    assert graph.tombstones() == 0 and b.graph.tombstones() == 0
    assert a.stats.compacted >= 100_000 and a.graph.digest() == b.graph.digest()
    reference = DSRGraph("a")
    with reference.transaction():
        for node in live:
            reference.insert_node("object", node.name, node.attrs, id=node.id)
    for replica in (a, b):
        size = len(replica.graph.state_message(replica.seen()))
        assert size <= 1.1 * len(reference.state_message()), size


def test_a_member_that_left_holds_compaction_back_until_its_retention_ends():
    net = Net()
    a, b = net.add("a"), net.add("b")
    net.maintain()
    node = a.graph.insert_node("object", "o")
    a.graph.delete_node(node.id)
    b_seen = a.members.members["b"]
    b_seen.live, b_seen.gone_at = False, time.monotonic()              # b cut off
    b.graph.attach(None)                                             # its digests stop
    a.maintain()
    assert a.graph.tombstones() == 1
    a.members.retention_s = -1.0
    a.maintain()
    assert a.graph.tombstones() == 0


def test_a_member_ahead_of_us_triggers_anti_entropy():
    net = Net()
    a, b, c = net.add("a"), net.add("b"), net.add("c")
    net.maintain()
    # c writes; the delta reaches b but is lost on its way to a; then b's digests show it
    net.route("c", "b")
    c.graph.insert_node("object", "missed")
    b.publish_digest()
    b.publish_digest()
    assert a.anti_entropy.requests.empty()           # a grace period for deltas in flight, backlogs
    a.anti_entropy.lag_grace_s = 0.0
    b.publish_digest()
    # the writer runs: its own state is fetched (only it is trusted for its writes)
    assert a.anti_entropy.take(0) == "c" and a.stats.anti_entropy == 1
    assert b.anti_entropy.requests.empty()
    a.members.members["c"].live = False       # a writer that is gone: the member holding its writes
    b.publish_digest()
    assert a.anti_entropy.take(0) == "b"


def test_a_writer_whose_stream_had_a_gap_is_not_judged_by_stale_watermarks():
    """Regression (netns partition test): b1's deltas made while its session was broken are
    lost; its later deltas must not make a1 call the lost writes forged when b2 relays them."""
    net = Net()
    a1, b1, b2 = net.add("a1"), net.add("b1"), net.add("b2")
    net.maintain()
    node = b1.graph.insert_node("object", "n", {"k": 0})
    lost = Publisher(lambda payload: b2.admit_delta(wire.delta_key("chronav", "b1"), payload))
    b1._publisher = lost                       # partition: a1 gets none of these
    b1.graph.update_node(node.id, {"k": 1})
    a1.member_seen("b1", live=False)
    b1._publisher = Publisher(lambda payload: net._deliver("b1", payload))   # healed
    b1.graph.update_node(node.id, {"other": 2})
    b1.publish_digest()
    a1.admit_state(*state_of(b2))          # b2 relays k=1 before b1's own state arrives
    assert a1.stats.rejects.get("forged_stamp") is None
    a1.admit_state(*state_of(b1))
    assert a1.graph.get_attr(node.id, "k") == 1 and a1.graph.digest() == b2.graph.digest()


def test_a_table_entry_for_an_agent_not_yet_heard_of_is_deferred_not_called_forged():
    """Regression (trust test): a member relays the replica id of an agent that has just
    started, before that agent's own messages reach this replica: nothing is a lie yet."""
    net = Net()
    sim = net.add("sim_robot")
    newcomer = DSRGraph("executive")
    newcomer.insert_node("mission", "m1", {"state": "pending"})
    sim.admit_state(wire.state_key("chronav", "executive"), newcomer.state_message())
    guard = Replica(DSRGraph("agenda"))
    guard.joined = True
    guard.members.add("executive")                 # its token is up
    guard.members.add("sim_robot")
    guard.admit_state(*state_of(sim))
    assert guard.stats.rejects == {} and guard.stats.deferred >= 1
    assert guard.graph.get_node_by_name("m1") is None                 # left for executive
    guard.admit_state(wire.state_key("chronav", "executive"),
                      newcomer.state_message())
    assert guard.graph.get_node_by_name("m1") is not None


def test_anti_entropy_settles_for_a_writer_that_left():
    """Regression: the watermark of a writer that is gone must be restored from the member
    that relays its writes, or every digest of that member would trigger another state fetch."""
    net = Net()
    a, b, c = net.add("a"), net.add("b"), net.add("c")
    net.maintain()
    net.route("c", "b")
    c.graph.insert_node("object", "missed")
    a.member_seen("c", live=False)
    a.anti_entropy.lag_grace_s = 0.0
    b.publish_digest()
    assert a.anti_entropy.take(0) == "b"
    a.admit_state(*state_of(b))                      # what the worker does
    assert a.graph.get_node_by_name("missed") is not None
    b.publish_digest()
    b.publish_digest()
    assert a.anti_entropy.requests.empty() and a.stats.anti_entropy == 1


def test_a_joiner_that_missed_a_delta_while_subscribing_does_not_call_it_forged():
    """Regression (CI, test_three_concurrent_writers_converge and the trust test): a joiner's
    subscription reaches the router a moment after it is declared; a delta of b published in
    that moment is lost to it.  Its first state came from c, and b's later deltas arrived in
    order, so a watermark for b taken from c's state and moved on by b's deltas claimed a
    write that never arrived, and c's next state was refused as forging it.  A running
    writer's watermark starts only from its own state."""
    net = Net()
    b, c = net.add("b"), net.add("c")
    net.maintain()
    joiner = Replica(DSRGraph("a"))
    for name in ("b", "c"):
        joiner.members.add(name)
    joiner.admit_state(*state_of(c))          # the first state of the join: from c
    joiner.joined = True
    missed = b.graph.insert_node("object", "missed")   # reaches c only
    net.replicas["a"] = joiner                         # now a's subscription is in place
    for name in ("b", "c"):
        net.replicas[name].members.add("a")
    b.graph.insert_node("object", "after")             # in order, after the missed one
    b.publish_digest()
    joiner.admit_state(*state_of(c))               # c relays the missed write
    assert joiner.stats.rejects == {}, joiner.stats.last_reject
    assert joiner.graph.get_node(missed.id) is None    # left for b itself ...
    joiner.admit_state(*state_of(b))               # ... whose own state brings it
    assert joiner.graph.get_node(missed.id) is not None
    assert joiner.graph.digest() == b.graph.digest() == c.graph.digest()
    assert joiner.seen()[b.graph.replica_id] >= b.graph.published_hlc()


def test_the_admission_api_says_whether_a_message_was_merged():
    """admit_delta / admit_state: the door every received message goes through (what the
    Zenoh callbacks call); True only when the message reached the graph."""
    writer = DSRGraph("w")
    sent: list[bytes] = []
    writer.attach(sent.append)
    node = writer.insert_node("object", "cup", {"k": 1})
    guard = Replica(DSRGraph("guard"))          # no write policy: only the admission checks
    key = wire.delta_key("chronav", "w")
    assert guard.admit_delta(wire.delta_key("chronav", "x"), sent[-1]) is False   # forged key
    assert guard.graph.get_node(node.id) is None
    assert guard.admit_delta(key, b"junk") is False
    assert guard.admit_delta(key, sent[-1]) is True
    assert guard.graph.get_node(node.id).attrs == {"k": 1}
    assert guard.stats.applied == 1 and guard.stats.rejects == {"forged_writer": 1, "invalid": 1}
    other = Replica(DSRGraph("other"))
    assert other.admit_state(wire.state_key("chronav", "guard"), b"{}") is False
    assert other.admit_state(*state_of(guard)) is True
    assert other.graph.state_equals(guard.graph) and other.stats.state_merged == 1


def test_a_read_only_watcher_forgets_tombstones_too():
    """The launcher watches a whole day read-only: it publishes no digest (nobody waits for it),
    but it forgets a removal once every writer acknowledged it, or a day's tombstones piled up
    in it (long runs, docs/long_runs.md)."""
    net = Net()
    a = net.add("a")
    net.add("b")
    watcher = Replica(DSRGraph("w", read_only=True), policy=None)  # type: ignore[arg-type]
    watcher.joined = True
    for name, other in net.replicas.items():
        watcher.members.add(name)
        watcher.admit_state(*state_of(other))
    net.replicas["w"] = watcher
    for cycle in range(20):
        node = a.graph.insert_node("object", f"tmp{cycle}")
        a.graph.delete_node(node.id)
    assert watcher.graph.tombstones() == 20
    net.maintain()
    net.maintain()
    assert watcher.graph.tombstones() == 0 and watcher.stats.compacted == 20
    assert watcher.stats.digests_sent == 0 and watcher.graph.digest() == a.graph.digest()


def test_node_limits_hold_inside_a_transaction_where_scalar_overwrites_skip_the_count():
    """update_node inside a transaction counts a node's limits unless the write only overwrites keys
    it has with scalars (dsr/graph.py _cannot_grow, the observer's hot path): new keys and strings
    are still counted and refused, and the scalar overwrite of a node already at its limit passes."""
    writer = DSRGraph("a")
    node = writer.insert_node("object", "o", {f"k{i}": 1.0 for i in range(LIMITS.max_node_attrs)})
    with writer.transaction():
        writer.update_node(node.id, {"k0": 2.0, "k1": 3})          # at the limit, overwritten: allowed
    assert writer.get_node(node.id).attrs["k0"] == 2.0
    with pytest.raises(InvalidAttributeError, match="CHRONAV_DSR_MAX_NODE_ATTRS"), writer.transaction():
        writer.update_node(node.id, {"k0": 4.0, "one_more": 1.0})
    assert writer.get_node(node.id).attrs["k0"] == 2.0, "the refused transaction changed nothing"
    small = writer.insert_node("object", "p", {"s": "x"})
    chunk = "z" * (LIMITS.max_value_bytes - 10)
    with pytest.raises(InvalidAttributeError, match="CHRONAV_DSR_MAX_NODE_BYTES"), writer.transaction():
        for i in range(LIMITS.max_node_bytes // LIMITS.max_value_bytes + 1):
            writer.update_node(small.id, {"s": "x", f"s{i}": chunk})
