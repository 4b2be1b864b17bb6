"""The write policy (agents/world/write_policy.yaml) as every replica enforces it on receipt.

Offline and in-process: each agent is a DSRGraph whose deltas are captured; a "guard" replica
runs the transport's admission API (`Replica.admit_delta` / `admit_state`, no network) with
the shipped policy.  The multi-process version with real Zenoh is
tests/integration/test_trust_policy.py.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import orjson
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from dsr import DSRGraph, wire
from dsr.errors import DSRError, PolicyError
from agents.world.write_policy import load_policy, policy_from_env
from dsr.policy import AllowAll, DenyTypes
from dsr.policy_rules import RulePolicy
from dsr.transport import Replica

POLICY = policy_from_env({})
OWNERS = ("sim_robot", "human_observer", "object_recognition", "agenda", "executive",
          "social_navigation", "agenda_tool-ward3")


class Guard:
    """A replica that receives through the real transport checks, without Zenoh."""

    def __init__(self, policy: object = POLICY, agent: str = "guard") -> None:
        self.graph = DSRGraph(agent)
        self.replica = Replica(self.graph, policy=policy)  # type: ignore[arg-type]

    def delta(self, agent: str, payload: bytes) -> None:
        self.replica.admit_delta(wire.delta_key("chronav", agent), payload)

    def state(self, source: DSRGraph) -> None:
        self.replica.admit_state(wire.state_key("chronav", source.agent),
                                 source.state_message())

    @property
    def stats(self):
        return self.replica.stats


class World:
    """The agents' graphs; legit deltas reach every graph, and the guards get everything."""

    def __init__(self) -> None:
        self.graphs: dict[str, DSRGraph] = {}
        self.guard = Guard()
        self.reference = Guard(policy=AllowAll(), agent="reference")  # legit deltas only
        for agent in OWNERS:
            self.agent(agent)
        self.ids = self._build()

    def agent(self, name: str, legit: bool = True) -> DSRGraph:
        """A graph for `name`, holding everything published so far."""
        graph = DSRGraph(name)
        if self.graphs:
            graph.apply_message(wire.decode(self.guard.graph.state_message()))
        graph.attach(lambda payload, a=name, g=graph: self._published(a, g, payload, legit))
        if legit:
            self.graphs[name] = graph
        return graph

    def _published(self, agent: str, source: DSRGraph, payload: bytes, legit: bool) -> None:
        self.guard.delta(agent, payload)
        if not legit:
            return
        self.reference.delta(agent, payload)
        for graph in self.graphs.values():
            if graph is not source:   # decode for each: a graph adopts the decoded states
                graph.apply_message(wire.decode(payload))

    def _build(self) -> dict[str, int]:
        g = self.graphs
        sim = g["sim_robot"]
        with sim.transaction():
            world = sim.insert_node("world", "world")
            room = sim.insert_node("room", "hall", {"polygon_x": [0.0, 5.0, 5.0],
                                                    "polygon_y": [0.0, 0.0, 5.0]})
            sim.insert_or_assign_edge(world.id, room.id, "RT", {"x": 0.0, "y": 0.0, "theta": 0.0})
            clock = sim.insert_node("clock", "clock", {"now_s": 100.0, "mode": "idle"})
            robot = sim.insert_node("robot", "robot", {"radius": 0.3, "nav_active": False})
            sim.insert_or_assign_edge(world.id, robot.id, "RT", {"x": 1.0, "y": 1.0, "theta": 0.0})
            sim.insert_or_assign_edge(robot.id, room.id, "in")
        obs = g["human_observer"]
        with obs.transaction():
            alice = obs.insert_node("person", "alice", {"role": "resident"})
            obs.insert_or_assign_edge(world.id, alice.id, "RT", {"x": 2.0, "y": 2.0, "theta": 0.0})
            obs.insert_or_assign_edge(alice.id, room.id, "in")
        rec = g["object_recognition"]
        with rec.transaction():
            table = rec.insert_node("object", "table", {"kind": "table"})
            rec.insert_or_assign_edge(world.id, table.id, "RT", {"x": 3.0, "y": 3.0, "theta": 0.0})
        agenda = g["agenda"]
        with agenda.transaction():
            activity = agenda.insert_node("activity", "activity/a1", {"state": "scheduled"})
            agenda.insert_or_assign_edge(activity.id, table.id, "has")
            agenda.insert_or_assign_edge(alice.id, activity.id, "participant")
            agenda.update_node(table.id, {"R": 0.5, "R_band": "medium", "active": False})
        executive = g["executive"]
        with executive.transaction():
            mission = executive.insert_node("mission", "mission/m1", {"state": "pending"})
            intention = executive.insert_node("intention", "intention/m1/0", {})
            executive.update_node(intention.id, {"state": "active", "goal_x": 1.0})
            executive.insert_or_assign_edge(intention.id, mission.id, "step_of")
        return {"world": world.id, "room": room.id, "clock": clock.id, "robot": robot.id,
                "alice": alice.id, "table": table.id, "activity": activity.id,
                "mission": mission.id, "intention": intention.id}


Action = Callable[[DSRGraph, dict[str, int]], object]

#: what each agent legitimately does during a run (read from agents/*/agent.py)
LEGIT: list[tuple[str, str, Action]] = [
    ("sim_robot", "move the robot", lambda g, i: g.insert_or_assign_edge(
        i["world"], i["robot"], "RT", {"x": 1.5, "y": 1.0, "theta": 0.1})),
    ("sim_robot", "stamp pose and laser", lambda g, i: g.update_node(
        i["robot"], {"pose_stamp": 101.0, "laser_ranges": [1.0, 2.0]})),
    ("sim_robot", "advance the clock", lambda g, i: g.update_node(i["clock"], {"now_s": 101.0})),
    ("social_navigation", "command the robot", lambda g, i: g.update_node(
        i["robot"], {"cmd_vx": 0.2, "cmd_omega": 0.0, "cmd_stamp": 101.0, "nav_active": True})),
    ("social_navigation", "publish its path", lambda g, i: g.update_node(
        i["robot"], {"path_x": [1.0, 2.0], "path_y": [1.0, 1.0], "planned_s": 101.0})),
    ("social_navigation", "finish the intention", lambda g, i: g.update_node(
        i["intention"], {"state": "done", "reason": ""})),
    ("human_observer", "move a person", lambda g, i: g.insert_or_assign_edge(
        i["world"], i["alice"], "RT", {"x": 2.5, "y": 2.0, "theta": 0.0})),
    ("human_observer", "see an interaction", lambda g, i: g.insert_or_assign_edge(
        i["alice"], i["table"], "interacting")),
    ("object_recognition", "update an object", lambda g, i: g.update_node(
        i["table"], {"kind": "table", "footprint_dims": [0.0, 1.0, 1.0]})),
    ("agenda", "update R(t)", lambda g, i: g.update_node(i["table"], {"R": 0.9, "active": True})),
    ("agenda", "run an activity", lambda g, i: g.update_node(i["activity"], {"state": "running"})),
    ("agenda", "add an activity", lambda g, i: g.insert_node(
        "activity", f"activity/x{len(g)}", {"state": "scheduled"})),
    ("executive", "activate a mission", lambda g, i: g.update_node(
        i["mission"], {"state": "active", "started_s": 101.0})),
    ("executive", "issue an intention", lambda g, i: g.insert_node(
        "intention", f"intention/m1/{len(g)}", {"state": "active"})),
    ("agenda_tool-ward3", "request an agenda change", lambda g, i: g.insert_node(
        "agenda_request", f"agenda_request/{len(g)}",
        {"change": '{"op": "cancel", "id": "a1"}', "state": "pending", "requested_by": "ward3"})),
]

#: (owner allowed to do it, what, action): every other agent must be refused
OWNED: list[tuple[frozenset[str], str, Action]] = [
    (frozenset({"sim_robot"}), "move the robot", LEGIT[0][2]),
    (frozenset({"sim_robot"}), "stamp the robot pose", LEGIT[1][2]),
    (frozenset({"sim_robot"}), "set the clock", LEGIT[2][2]),
    (frozenset({"sim_robot"}), "delete the robot", lambda g, i: g.delete_node(i["robot"])),
    (frozenset({"social_navigation"}), "command the robot", LEGIT[3][2]),
    (frozenset({"human_observer"}), "move a person", LEGIT[6][2]),
    (frozenset({"object_recognition"}), "move an object", lambda g, i: g.insert_or_assign_edge(
        i["world"], i["table"], "RT", {"x": 9.0, "y": 9.0, "theta": 0.0})),
    (frozenset({"agenda"}), "set an object's R", LEGIT[9][2]),
    (frozenset({"agenda"}), "create an activity", LEGIT[11][2]),
    (frozenset({"agenda"}), "change an activity", LEGIT[10][2]),
    (frozenset({"agenda"}), "delete an activity", lambda g, i: g.delete_node(i["activity"])),
    (frozenset({"executive"}), "create a mission", lambda g, i: g.insert_node(
        "mission", f"mission/x{len(g)}", {"state": "pending"})),
    (frozenset({"executive"}), "change a mission", LEGIT[12][2]),
    (frozenset({"executive"}), "change an intention's goal", lambda g, i: g.update_node(
        i["intention"], {"goal_x": 9.0})),
    (frozenset({"executive", "social_navigation"}), "end an intention", LEGIT[5][2]),
    (frozenset({"agenda", "agenda_tool-ward3"}), "create an agenda request", LEGIT[14][2]),
]
ROGUES = (*OWNERS, "rogue", "agenda_tool", "sim_robot2")
FORBIDDEN = [(agent, what, action) for owners, what, action in OWNED for agent in ROGUES
             if agent not in owners]


def test_shipped_policy_loads_and_agents_hold_grants():
    assert isinstance(POLICY, RulePolicy)
    for agent in OWNERS:
        assert POLICY.has_rights(agent), agent
    assert not POLICY.has_rights("rogue") and not POLICY.has_rights("launcher")


def test_the_whole_world_written_by_its_owners_is_accepted():
    world = World()
    assert world.guard.stats.rejected_policy == 0, world.guard.stats.last_reject
    assert world.guard.stats.applied == world.reference.stats.applied > 0
    assert world.guard.graph.state_equals(world.reference.graph)


@pytest.mark.parametrize(("agent", "what", "action"), LEGIT, ids=[f"{a}: {w}" for a, w, _ in LEGIT])
def test_legitimate_writes_pass(agent, what, action):
    world = World()
    applied = world.guard.stats.applied
    action(world.graphs[agent], world.ids)
    assert world.guard.stats.rejected_policy == 0, world.guard.stats.last_reject
    assert world.guard.stats.applied == applied + 1
    assert world.guard.graph.state_equals(world.graphs[agent])


@pytest.mark.parametrize(("agent", "what", "action"), FORBIDDEN,
                         ids=[f"{a}: {w}" for a, w, _ in FORBIDDEN])
def test_forbidden_writes_are_refused_and_leave_the_graph_untouched(agent, what, action, caplog):
    world = World()
    before = world.guard.graph.digest()
    rogue = world.agent(agent, legit=False)
    action(rogue, world.ids)
    stats = world.guard.stats
    assert stats.rejected_policy == 1 and stats.rejected == 0, stats
    assert f"agent {agent!r} may not" in stats.last_reject or "holds no grant" in stats.last_reject
    assert "write_policy.yaml" in stats.last_reject
    assert world.guard.graph.digest() == before
    assert any("dropped message" in r.message for r in caplog.records)


def test_deleting_an_activity_deletes_its_edges_and_is_allowed_to_the_agenda():
    world = World()
    world.graphs["agenda"].delete_node(world.ids["activity"])
    assert world.guard.stats.rejected_policy == 0, world.guard.stats.last_reject
    assert world.guard.graph.get_node(world.ids["activity"]) is None
    assert not world.guard.graph.edges_of_type("participant")


def test_object_recognition_cannot_smuggle_R_into_a_new_object():
    world = World()
    rec = world.graphs["object_recognition"]
    rec.insert_node("object", "chair", {"kind": "chair"})
    assert world.guard.stats.rejected_policy == 0
    rec.insert_node("object", "sofa", {"kind": "sofa", "R": 1.0})
    assert world.guard.stats.rejected_policy == 1
    assert "may not create a 'object' node with 'R'" in world.guard.stats.last_reject


def test_retyping_a_node_needs_rights_on_both_types():
    """An agent allowed to create activities re-sends the robot's id as an activity."""
    world = World()
    agenda = world.graphs["agenda"]
    hlc = agenda.clock.tick()
    forged = orjson.dumps({
        "format": wire.FORMAT, "kind": "delta", "graph": "chronav", "agent": "agenda",
        "replica": agenda.replica_id,
        "nodes": [{"id": world.ids["robot"], "add": [[agenda.replica_id, hlc]],
                   "meta": [hlc, agenda.replica_id, "activity", "robot"]}], "edges": []})
    before = world.guard.graph.digest()
    world.guard.delta("agenda", forged)
    assert world.guard.stats.rejected_policy == 1
    assert "may not create a 'robot' node" in world.guard.stats.last_reject
    assert world.guard.graph.digest() == before


def test_states_keep_only_what_their_writers_were_allowed_to_write():
    world = World()
    fresh = Guard(agent="joiner")
    fresh.state(world.graphs["executive"])         # relays every agent's legit writes
    assert fresh.stats.state_merged == 1 and fresh.stats.rejected_policy == 0
    assert fresh.graph.state_equals(world.guard.graph)
    # A human_observer that wrote the robot pose locally serves it in its state: that register
    # is dropped, the rest of the state is merged.
    liar = world.agent("human_observer", legit=False)
    LEGIT[0][2](liar, world.ids)
    fresh = Guard(agent="joiner")
    fresh.state(liar)
    assert fresh.stats.rejected_policy == 1 and fresh.stats.state_merged == 1
    assert "'human_observer' may not set" in fresh.stats.last_reject
    assert "'RT' edge (world -> robot)" in fresh.stats.last_reject
    rt = fresh.graph.get_edge(world.ids["world"], world.ids["robot"], "RT")
    assert rt is not None and rt.attrs.get("x") != 1.5
    assert fresh.graph.get_node(world.ids["mission"]) is not None
    fresh.state(world.graphs["executive"])         # the legit pose comes with another state
    assert fresh.graph.state_equals(world.guard.graph)
    # An agent without any grant is not trusted to relay anything, even faithful copies.
    relay = world.agent("rogue", legit=False)
    fresh.state(relay)
    assert fresh.stats.rejected_policy == 2 and "holds no grant" in fresh.stats.last_reject


def test_relayed_removals_need_a_receipt_from_an_allowed_remover():
    world = World()
    laggard = Guard(agent="laggard")
    laggard.state(world.graphs["executive"])
    # The agenda deletes an activity; the laggard misses the delta, then gets it by a state
    # that executive relays: the receipt names the agenda, which may delete activities.
    state_before_delete = world.graphs["executive"].state_message()
    world.graphs["agenda"].delete_node(world.ids["activity"])
    relayed = world.graphs["executive"].state_message()
    without_receipts = relayed.replace(b'"~removed"', b'"~other"')
    assert without_receipts != relayed
    laggard.replica.admit_state(wire.state_key("chronav", "executive"),
                                without_receipts)
    assert world.ids["activity"] in laggard.graph, "a removal without receipt was merged"
    assert "without a receipt" in laggard.stats.last_reject
    laggard.state(world.graphs["executive"])
    assert world.ids["activity"] not in laggard.graph
    assert laggard.graph.digest() == world.guard.graph.digest()
    # A buggy object_recognition deletes a mission locally: refused as a delta, and its state,
    # which carries the removal, cannot delete it either.
    other = Guard(agent="other")
    other.replica.admit_state(wire.state_key("chronav", "executive"),
                              state_before_delete)
    buggy = world.agent("object_recognition", legit=False)
    buggy.delete_node(world.ids["mission"])
    assert world.guard.stats.rejected_policy == 1
    other.state(buggy)
    assert world.ids["mission"] in other.graph
    assert "'object_recognition' may not delete a 'mission' node" in other.stats.last_reject


def test_a_state_cannot_reassign_a_known_replica_to_another_agent():
    world = World()
    sim = world.graphs["sim_robot"]
    payload = world.graphs["executive"].state_message()
    forged = payload.replace(f'"{sim.replica_id}":"sim_robot"'.encode(),
                             f'"{sim.replica_id}":"executive"'.encode())
    assert forged != payload
    guard = world.guard
    guard.replica.admit_state(wire.state_key("chronav", "executive"), forged)
    assert guard.stats.rejected == 1 and "forged writer" in guard.stats.last_reject


def test_coarse_type_policy_still_works():
    guard = Guard(policy=DenyTypes({"robot"}, agents={"rogue"}))
    rogue = DSRGraph("rogue")
    rogue.attach(lambda p: guard.delta("rogue", p))
    rogue.insert_node("person", "p")
    rogue.insert_node("robot", "r")
    assert guard.stats.applied == 1 and guard.stats.rejected_policy == 1


def test_coarse_type_policy_reviews_the_senders_own_state():
    """Regression (flake of tests/integration/test_dsr_replication.py
    ::test_write_policy_drops_refused_deltas): the guard fetches a new member's state when its
    token appears; under load that fetch ran after the member's first writes, and the coarse
    policy merged states unreviewed, so the node whose delta it had refused came back in the
    state.  A state must not bring what the policy refuses in a delta."""
    guard = Guard(policy=DenyTypes({"robot"}, agents={"rogue"}))
    rogue = DSRGraph("rogue")
    rogue.attach(lambda p: guard.delta("rogue", p))
    rogue.insert_node("robot", "r2d2")
    bob = rogue.insert_node("person", "bob")
    assert guard.stats.rejected_policy == 1
    guard.state(rogue)                         # the late fetch of rogue's state
    assert guard.graph.get_node_by_name("r2d2") is None
    assert guard.graph.get_node(bob.id) is not None
    assert guard.stats.rejected_policy == 2
    assert "'robot'" in guard.stats.last_reject and "'rogue'" in guard.stats.last_reject


@pytest.mark.parametrize("joined", [False, True])
def test_coarse_type_policy_reviews_states_relaying_a_refused_writer(joined):
    """The refused node relayed by another member's state (a joiner's first state included:
    its `writers` table is trusted, so it attributes the node to its writer) is dropped too;
    unattributed, a node of a type the policy refuses to some agent is dropped as well."""
    rogue = DSRGraph("rogue")
    rogue.insert_node("robot", "r2d2")
    friend = DSRGraph("friend")
    friend.insert_node("person", "ana")
    friend.apply_message(wire.decode(rogue.state_message()))
    friend.writers.note(rogue.replica_id, "rogue")
    guard = Guard(policy=DenyTypes({"robot"}, agents={"rogue"}))
    guard.replica.joined = joined
    guard.state(friend)
    assert guard.graph.get_node_by_name("ana") is not None
    assert guard.graph.get_node_by_name("r2d2") is None
    assert guard.stats.rejected_policy == 1


def test_coarse_type_policy_keeps_what_other_agents_may_write_in_a_state():
    guard = Guard(policy=DenyTypes({"robot"}, agents={"rogue"}))
    owner = DSRGraph("sim_robot")
    owner.insert_node("robot", "shadow")
    guard.state(owner)
    assert guard.graph.get_node_by_name("shadow") is not None
    assert guard.stats.rejected_policy == 0


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.one_of(st.tuples(st.just("legit"), st.integers(0, len(LEGIT) - 1)),
                          st.tuples(st.just("forbidden"), st.integers(0, len(FORBIDDEN) - 1))),
                min_size=1, max_size=12))
def test_property_forbidden_writes_never_change_the_guarded_graph(script):
    """Whatever mix of legit and forbidden writes, the guard ends exactly where a replica that
    only ever received the legit ones ends."""
    world = World()
    rogues: dict[str, DSRGraph] = {}
    forbidden = 0
    for kind, index in script:
        if kind == "legit":
            agent, _what, action = LEGIT[index]
            graph = world.graphs[agent]
        else:
            agent, _what, action = FORBIDDEN[index]
            graph = rogues.get(agent) or rogues.setdefault(agent, world.agent(agent, legit=False))
        try:
            action(graph, world.ids)
        except DSRError:
            continue       # e.g. the rogue deleted that node already in its own copy
        forbidden += kind == "forbidden"
    assert world.guard.stats.rejected_policy >= forbidden
    assert world.guard.graph.state_equals(world.reference.graph)


# ---------------------------------------------------------------------------- policy files
def write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "policy.yaml"
    path.write_text(text)
    return path


@pytest.mark.parametrize(("text", "where"), [
    ("format: chronav-write-policy/1\nrules:\n  - writers: [a]\n    nodes: [x]\n"
     "    ops: [create, frobnicate]\n", "policy.yaml:5:"),
    ("format: chronav-write-policy/1\nrules:\n  - writers: [a]\n    nodes: [x]\n"
     "    edges: [y]\n    ops: [create]\n", "policy.yaml:3:"),
    ("format: chronav-write-policy/1\nrules:\n  - writers: [a]\n    nodes: [x]\n"
     "    from: [world]\n    ops: [create]\n", "policy.yaml:3:"),
    ("format: chronav-write-policy/1\nrules:\n  - writers: [a]\n    nodes: [x]\n", "policy.yaml:3:"),
    ("format: chronav-write-policy/1\nrules:\n  - writers: [a]\n    nodes: [x]\n"
     "    attrs: [b]\n    colour: red\n", "policy.yaml:6:"),
    ("format: other/2\nrules: []\n", "policy.yaml:1:"),
    ("format: chronav-write-policy/1\nrules: [\n", "policy.yaml:"),
    ("- just a list\n", "policy.yaml:1:"),
])
def test_bad_policy_files_name_file_and_line(tmp_path, text, where):
    with pytest.raises(PolicyError, match=where):
        load_policy(write(tmp_path, text))


def test_policy_from_env(tmp_path):
    assert isinstance(policy_from_env({"CHRONAV_WRITE_POLICY": "allow-all"}), AllowAll)
    path = write(tmp_path, "format: chronav-write-policy/1\nrules:\n  - writers: [a*]\n"
                           "    nodes: [x]\n    ops: [create]\n")
    policy = policy_from_env({"CHRONAV_WRITE_POLICY": str(path)})
    assert isinstance(policy, RulePolicy) and policy.has_rights("abc") and not policy.has_rights("b")
    with pytest.raises(PolicyError, match="CHRONAV_WRITE_POLICY"):
        policy_from_env({"CHRONAV_WRITE_POLICY": str(tmp_path / "missing.yaml")})


def test_a_tool_cannot_create_a_request_already_answered():
    """Issue #31: "create includes the values given at creation" let a tool create an
    agenda_request saying state=accepted.  `init_values` restricts it to `pending`: in deltas,
    in relayed states, and on the tool's own replica before anything is sent."""
    from dsr.errors import WriteRefusedError
    guard = Guard()
    tool = DSRGraph("agenda_tool-ward3")
    sent: list[bytes] = []
    tool.attach(sent.append)
    asked = tool.insert_node("agenda_request", "agenda_request/ok", {"state": "pending",
                                                                    "change": "{}"})
    answered = tool.insert_node("agenda_request", "agenda_request/forged",
                                {"state": "accepted", "change": "{}"})
    tool.flush()
    for payload in sent:
        guard.delta("agenda_tool-ward3", payload)
    assert guard.graph.get_node(asked.id) is not None
    assert guard.graph.get_node(answered.id) is None
    assert guard.stats.rejects == {"policy": 1}
    assert "'state' = 'accepted'" in guard.stats.last_reject
    relay = Guard(agent="relay")
    relay.state(tool)                         # a state relaying the tool's writes
    assert relay.graph.get_node(asked.id) is not None
    assert "state" not in relay.graph.get_node(answered.id).attrs
    assert relay.stats.rejects == {"policy": 1}
    checked = Guard(agent="agenda_tool-ward3")    # the tool's own replica, policy attached
    with pytest.raises(WriteRefusedError, match="'state' = 'refused'"):
        checked.graph.insert_node("agenda_request", "agenda_request/x", {"state": "refused"})
    # the agenda itself still answers requests
    agenda = DSRGraph("agenda")
    agenda.apply_message(wire.decode(tool.state_message()))
    sent.clear()
    agenda.attach(sent.append)
    agenda.update_node(asked.id, {"state": "accepted"})
    agenda.flush()
    for payload in sent:
        guard.delta("agenda", payload)
    assert guard.graph.get_attr(asked.id, "state") == "accepted"


def test_attr_writes_are_the_local_writes_of_an_attribute_only_change() -> None:
    """dsr.writes.attr_writes (the local policy check's fast path for attribute updates) lists the
    writes local_writes lists for the same delta: nodes of known and unknown type, edges."""
    from dsr import DSRGraph
    from dsr.writes import attr_writes, local_writes

    graph = DSRGraph("observer")
    world = graph.insert_node("world", "world", {})
    person = graph.insert_node("person", "p1", {"role": "resident"})
    graph.insert_or_assign_edge(world.id, person.id, "RT", {"x": 0.0, "y": 0.0, "theta": 0.0})
    regs = {"x": (5, graph.replica_id, 1.0), "seen_s": (5, graph.replica_id, 2.0)}
    for element, key in (("node", person.id), ("node", 12345), ("edge", (world.id, person.id, "RT")),
                         ("edge", (world.id, 999, "in"))):
        for attrs in (regs, dict.fromkeys(regs, (0, 0, 0)), {}):
            assert attr_writes(graph, "observer", element, key, attrs) == \
                list(local_writes(graph, "observer", element, key, {"attrs": attrs})), (element, key, attrs)
