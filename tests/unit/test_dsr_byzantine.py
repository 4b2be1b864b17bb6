"""A Byzantine member against honest replicas: no forged claim is ever served or applied.

Honest members (sim_robot, agenda, executive) run the real transport hooks (`Replica`, never
opened: tests/unit/test_dsr_protocol.py `Net`), write, exchange deltas, digests and states.  A
Byzantine member (`agenda_tool-evil`, holding a grant, so its states are not refused whole)
serves states built by hypothesis: writers tables giving fresh or honest replica ids to honest
agents (the receiving one included), registers stamped with honest replica ids at old or
future stamps with any value, removals stamped by honest ids, and honest states relayed
verbatim or altered.  After every step:

- no honest replica serves (DSRGraph.served_writers, i.e. its state replies' `writers`) a
  binding that is false;
- no honest replica holds a stamp of an honest replica id that this replica did not write, nor
  any stamp of an id the Byzantine member made up;
- honest members never count each other: every refusal names the Byzantine member's key.
"""

from __future__ import annotations

import orjson
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from dsr import DSRGraph, wire
from dsr.crdt import REMOVAL_RECEIPT
from dsr.transport import Replica
from tests.unit.test_dsr_protocol import POLICY, Net, Received, state_of

HONEST = ("sim_robot", "agenda", "executive")
EVIL = "agenda_tool-evil"


class Byzantine:
    """The Byzantine member: a real graph (its own writes are honest-looking) plus forgeries."""

    def __init__(self) -> None:
        self.graph = DSRGraph(EVIL)
        self.made_up: set[int] = set()

    def state(self, nodes: list[dict], edges: list[dict], writers: dict[str, str]) -> Received:
        document = orjson.loads(self.graph.state_message())
        document["nodes"] += nodes
        document["edges"] += edges
        document["writers"].update(writers)
        return wire.state_key("chronav", EVIL), orjson.dumps(document)


class World:
    def __init__(self) -> None:
        self.net = Net(POLICY)
        self.rejects: list[tuple[str, str, str]] = []
        self.written: set[tuple[int, int, str, bytes]] = set()   # (replica, hlc, key, value)
        self.dots: set[tuple[int, int]] = set()
        for agent in HONEST:
            self._watch(self.net.add(agent))
        self.evil = Byzantine()
        for replica in self.net.replicas.values():
            replica.members.add(EVIL)
        self.truth = {r.graph.replica_id: name for name, r in self.net.replicas.items()}
        sim = self.net.replicas["sim_robot"].graph
        with sim.transaction():
            self.world = sim.insert_node("world", "world").id
            self.clock = sim.insert_node("clock", "clock", {"now_s": 1.0, "mode": "idle"}).id
            self.room = sim.insert_node("room", "hall", {"polygon_x": [0.0, 1.0, 1.0]}).id
        agenda = self.net.replicas["agenda"].graph
        self.activity = agenda.insert_node("activity", "activity/a1", {"state": "pending"}).id
        self.net.maintain()

    def _watch(self, replica: Replica) -> None:
        """Record every write the honest replica publishes, and every refusal it counts."""
        publish = replica._publish
        name = replica.graph.agent

        def recording(payload: bytes) -> None:
            message = wire.decode(payload)
            for entries in (message.nodes, message.edges):
                for _, state in entries:
                    self.dots.update(state.add.items())
                    if state.meta is not None:
                        self.dots.add((state.meta[1], state.meta[0]))
                    for key, (hlc, writer, value) in state.attrs.items():
                        self.written.add((writer, hlc, key, orjson.dumps(value)))
            publish(payload)

        replica._publish = recording      # type: ignore[method-assign]
        replica.graph.attach(recording, linger_s=0.0)
        reject = replica._reject

        def counting(source: str, reason: str, text: str, count: int = 1) -> None:
            self.rejects.append((name, source, reason))
            reject(source, reason, text, count)

        replica._reject = counting        # type: ignore[method-assign]

    def honest_ids(self) -> list[int]:
        return sorted(self.truth)

    def check(self) -> None:
        evil_id = self.evil.graph.replica_id
        for name, replica in self.net.replicas.items():
            graph = replica.graph
            for rid, agent in graph.served_writers().items():
                if rid in self.truth or agent in HONEST:
                    assert self.truth.get(rid) == agent, (name, "serves", rid, agent)
                else:
                    assert rid == evil_id and agent == EVIL, (name, "serves", rid, agent)
            for entries in (graph.node_states.values(), graph.edge_states.values()):
                for state in entries:
                    stamps = list(state.add.items())
                    if state.meta is not None:
                        stamps.append((state.meta[1], state.meta[0]))
                    for replica_id, hlc in stamps:
                        assert replica_id not in self.evil.made_up, (name, "applied", replica_id)
                        if replica_id in self.truth:
                            assert (replica_id, hlc) in self.dots, (name, "forged dot", hlc)
                    for key, (hlc, writer, value) in state.attrs.items():
                        assert writer not in self.evil.made_up, (name, "applied", writer, key)
                        if writer in self.truth:
                            assert (writer, hlc, key, orjson.dumps(value)) in self.written, \
                                (name, "forged register", key, value)
        honest_keys = [k for a in HONEST for k in (wire.state_key("chronav", a),
                                                   wire.delta_key("chronav", a))]
        counted = [r for r in self.rejects if r[1] in honest_keys]
        assert not counted, f"honest members counted each other: {counted}"


# ---------------------------------------------------------------------------- the attacks
@st.composite
def forgery(draw: st.DrawFn) -> tuple:
    return draw(st.one_of(
        st.tuples(st.just("table"), st.sampled_from(HONEST), st.booleans(), st.booleans()),
        st.tuples(st.just("stamp"), st.sampled_from(HONEST), st.sampled_from(["clock", "room",
                                                                             "activity"]),
                  st.integers(-10**6, 10**6), st.one_of(st.floats(allow_nan=False,
                                                                  allow_infinity=False),
                                                        st.text(max_size=8))),
        st.tuples(st.just("removal"), st.sampled_from(HONEST), st.sampled_from(["room",
                                                                              "activity"]),
                  st.booleans()),
        st.tuples(st.just("reassign"), st.sampled_from(HONEST), st.sampled_from(HONEST)),
        st.tuples(st.just("relay"), st.sampled_from(HONEST), st.booleans()),
        st.tuples(st.just("honest"), st.sampled_from(HONEST), st.floats(0, 100)),
        st.tuples(st.just("token"), st.sampled_from(HONEST), st.sampled_from(HONEST)),
    ))


def attack(world: World, step: tuple) -> None:
    evil = world.evil
    replicas = world.net.replicas
    kind = step[0]
    now = evil.graph.clock.tick()
    sample = None
    if kind == "honest":                  # honest traffic between the attacks
        _, agent, value = step
        graph = replicas[agent].graph
        if agent == "sim_robot":
            graph.update_node(world.clock, {"now_s": value})
        elif agent == "agenda":
            graph.update_node(world.activity, {"start_s": value})
        else:
            graph.insert_node("mission", f"mission/{len(graph)}", {"state": "pending"})
        world.net.maintain()
        for name, replica in replicas.items():     # an anti-entropy round among honest ones
            for other_name, other in replicas.items():
                if other_name != name:
                    replica.admit_state(*state_of(other))
        return
    if kind == "token":                   # a member's token comes back (a restart, a
        _, watcher, member = step         # partition): its own state is not merged yet
        if watcher != member:
            replicas[watcher].member_seen(member, live=True)
        return
    if kind == "table":                   # a fresh id given to a running honest agent
        _, agent, fresh_stamp, with_node = step
        fake = (now % (2**40)) * 7919 + 17
        evil.made_up.add(fake)
        hlc = now if fresh_stamp else 1 << 20
        nodes = []
        if with_node:
            node_type = {"sim_robot": "room", "agenda": "activity", "executive": "mission"}[agent]
            nodes.append({"id": fake % (2**31) + 5, "add": [[fake, hlc]],
                          "meta": [hlc, fake, node_type, f"forged{fake}"],
                          "attrs": {"state": [hlc, fake, "accepted"]}})
        sample = evil.state(nodes, [], {str(fake): agent})
    elif kind == "stamp":                 # a register stamped with an honest replica's id
        _, agent, target, offset, value = step
        owner = replicas[agent].graph
        node_id = {"clock": world.clock, "room": world.room, "activity": world.activity}[target]
        hlc = max(1, owner.published_hlc() + offset)
        key = {"clock": "now_s", "room": "polygon_x", "activity": "state"}[target]
        sample = evil.state([{"id": node_id, "attrs": {key: [hlc, owner.replica_id, value]}}],
                            [], {})
    elif kind == "removal":               # a removal receipt in an honest replica's name
        _, agent, target, old = step
        owner = replicas[agent].graph
        node_id = {"room": world.room, "activity": world.activity}[target]
        state = owner.element_state("node", node_id)
        hlc = owner.published_hlc() - 5 if old else now
        add = [[r, h] for r, h in state.add.items()] if state is not None else []
        sample = evil.state([{"id": node_id, "rem": add, "cleared": hlc,
                              "attrs": {REMOVAL_RECEIPT: [hlc, owner.replica_id, True]}}], [], {})
    elif kind == "reassign":              # an honest id given to another honest agent
        _, agent, other = step
        sample = evil.state([], [], {str(replicas[agent].graph.replica_id): other})
    elif kind == "relay":                 # an honest state relayed, possibly with its table
        _, agent, keep_table = step
        document = orjson.loads(replicas[agent].graph.state_message())
        document["agent"], document["replica"] = EVIL, evil.graph.replica_id
        document["writers"] = {**(document["writers"] if keep_table else {}),
                               str(evil.graph.replica_id): EVIL}
        document.pop("clock", None)
        document.pop("seen", None)
        sample = wire.state_key("chronav", EVIL), orjson.dumps(document)
    assert sample is not None
    for replica in replicas.values():
        replica.admit_state(*sample)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(forgery(), min_size=1, max_size=12))
@example([("token", "sim_robot", "agenda"), ("table", "agenda", True, True),
          ("honest", "agenda", 3.0), ("table", "agenda", True, False)])   # issue #31's case
@example([("token", "executive", "sim_robot"), ("stamp", "sim_robot", "clock", 10**6, 5.0),
          ("relay", "executive", True), ("honest", "sim_robot", 2.0)])
def test_no_honest_replica_serves_or_applies_a_forged_claim(steps):
    world = World()
    for step in steps:
        attack(world, step)
        world.check()
    # and the honest replicas still agree with each other
    digests = {r.graph.digest() for r in world.net.replicas.values()}
    assert len(digests) == 1


def test_a_forged_claim_about_a_member_is_counted_by_it_and_answered_with_its_state():
    """Regression (issue #31): a state said a new id belongs to `agenda`; every agent deferred
    it, then served the fake entry as its own.  Now agenda counts it (forged_writer) and
    publishes a digest at once; members that had not merged agenda's own state yet fetch it,
    and from then on refuse the claim; nobody serves it."""
    world = World()
    agenda = world.net.replicas["agenda"]
    sim = world.net.replicas["sim_robot"]
    sim.members.vouched.discard("agenda")          # as just after agenda (re)started
    fake = 987654321987
    world.evil.made_up.add(fake)
    hlc = world.evil.graph.clock.tick()
    forged = world.evil.state([{"id": 77, "add": [[fake, hlc]], "meta": [hlc, fake, "activity",
                                                                        "activity/fake"]}],
                              [], {str(fake): "agenda"})
    digests_before = agenda.stats.digests_sent
    sim.admit_state(*forged)
    assert sim.stats.deferred >= 1 and not sim.stats.rejects
    agenda.admit_state(*forged)
    assert agenda.stats.rejects == {"forged_writer": 1}
    assert agenda.stats.forgeries_about_me == 1
    assert agenda.stats.digests_sent == digests_before + 1
    assert sim.anti_entropy.take(0) == "agenda"        # sim fetches agenda's state
    sim.admit_state(*state_of(agenda))
    sim.admit_state(*forged)
    assert sim.stats.rejects == {"forged_writer": 1}
    for replica in world.net.replicas.values():
        assert fake not in replica.graph.served_writers()
        assert replica.graph.get_node_by_name("activity/fake") is None
    world.check()


def test_a_forged_old_stamp_under_ones_own_id_is_counted_by_oneself():
    world = World()
    sim = world.net.replicas["sim_robot"]
    stamp = sim.graph.element_state("node", world.clock).attrs["now_s"][0]
    sim.graph.update_node(world.clock, {"mode": "running"})    # sim_robot publishes past it
    forged = world.evil.state([{"id": world.clock, "attrs": {
        "now_s": [stamp + 1, sim.graph.replica_id, 42.0]}}], [], {})
    sim.admit_state(*forged)
    assert sim.stats.rejects.get("forged_stamp") == 1 and sim.stats.deferred == 0
    assert sim.graph.get_attr(world.clock, "now_s") == 1.0
    assert sim.stats.forgeries_about_me == 1


def test_an_old_removal_one_member_still_holds_is_not_called_forged_after_a_restart():
    """Regression (issue #31, point 3): a person's `in` edge is removed, most members forget
    the removal (compaction), one does not before the edge is added again; its state then
    carries the old removal (rem dots, `cleared`, receipt) on a present edge.  A member that
    (re)joined from a compacted copy refused that part as forged_stamp every time it merged
    the honest member's state.  The old removal hides nothing it holds: not a forgery."""
    net = Net(POLICY)
    sim, observer, keeper = (net.add(a) for a in ("sim_robot", "human_observer",
                                                  "social_navigation"))
    room = sim.graph.insert_node("room", "hall").id
    person = observer.graph.insert_node("person", "ana").id
    observer.graph.insert_or_assign_edge(person, room, "in")
    net.maintain()
    observer.graph.delete_edge(person, room, "in")
    for _ in range(3):                   # everybody acknowledges; all but `keeper` compact
        keeper.publish_digest()
        sim.maintain()
        observer.maintain()
    assert sim.graph.tombstones() == 0 and keeper.graph.tombstones() == 1
    observer.graph.insert_or_assign_edge(person, room, "in")          # the person is back
    assert keeper.graph.element_state("edge", (person, room, "in")).cleared > 0
    restarted = net.add("executive")     # joins from sim's compacted copy, then merges all
    for _ in range(3):
        restarted.admit_state(*state_of(keeper))
    assert restarted.stats.rejects == {}, restarted.stats.last_reject
    assert restarted.graph.get_edge(person, room, "in") is not None
    # a removal that would hide the edge, stamped by the observer and never published by it,
    # is still a forgery
    edge = restarted.graph.element_state("edge", (person, room, "in"))
    hlc = observer.graph.published_hlc()
    document = orjson.loads(keeper.graph.state_message(keeper.seen()))
    entry = next(e for e in document["edges"] if (e["src"], e["dst"]) == (person, room))
    entry.update(rem=[[r, h] for r, h in edge.add.items()], cleared=hlc,
                 attrs={REMOVAL_RECEIPT: [hlc, observer.graph.replica_id, True]})
    restarted.admit_state(*state_of(keeper, orjson.dumps(document)))
    assert restarted.stats.rejects == {"forged_stamp": 1}
    assert restarted.graph.get_edge(person, room, "in") is not None


def test_a_joiner_relays_what_it_joined_with_attributed():
    """A member that has just joined serves the bindings of the state it joined with, running
    agents' included: a second joiner starting from it would otherwise refuse their writes
    (`policy`: a register no agent vouches for) though nobody lied."""
    net = Net(POLICY)
    sim, observer = net.add("sim_robot"), net.add("human_observer")
    sim.graph.insert_node("room", "hall")
    observer.graph.insert_node("person", "ana")
    net.maintain()
    first = Replica(DSRGraph("executive"), policy=POLICY)
    second = Replica(DSRGraph("agenda"), policy=POLICY)
    for joiner in (first, second):
        for name in ("sim_robot", "human_observer"):
            joiner.members.add(name)
    first.admit_state(*state_of(sim))          # its join: before any message of the others
    first.joined = True
    second.members.add("executive")
    second.admit_state(*state_of(first))       # its join, from the first joiner
    assert second.stats.rejects == {}, second.stats.last_reject
    assert second.graph.get_node_by_name("ana") is not None
