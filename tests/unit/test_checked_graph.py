"""The graph agents are handed refuses writes outside the vocabulary, and goes on
(agents/runtime/checked_graph.py).  The live path: tests/integration/test_vocabulary_live.py."""

from __future__ import annotations

import logging

import pytest

from agents.runtime.checked_graph import REASON, CheckedGraph
from agents.world.vocabulary import CLOCK, ClockAttr, EdgeType, MissionState, NodeType
from dsr import DSRGraph
from dsr.transport import ReplicaStats


class _Replica:
    def __init__(self) -> None:
        self.stats = ReplicaStats()


@pytest.fixture
def graphs() -> tuple[DSRGraph, CheckedGraph]:
    raw = DSRGraph("sim_robot")
    raw.replica = _Replica()
    checked = CheckedGraph(raw, "sim_robot")
    world = checked.insert_node(NodeType.WORLD, "world", {})
    checked.insert_node(type=NodeType.CLOCK, name=CLOCK, attrs={ClockAttr.NOW_S: 0.0, ClockAttr.MODE: "idle"})
    robot = checked.insert_node(NodeType.ROBOT, "robot", {"radius": 0.3})
    checked.insert_or_assign_edge(world.id, robot.id, EdgeType.RT, {"x": 1.0, "y": 2.0, "theta": 0.0})
    return raw, checked


def test_the_vocabularys_typo_is_refused_named_and_counted_and_nothing_changes(graphs, caplog) -> None:
    raw, checked = graphs
    before, published = raw.digest(), raw.version
    clock = checked.get_node_by_name(CLOCK)
    with caplog.at_level(logging.WARNING, logger="chronav.vocabulary"):
        assert checked.update_node(clock.id, {"now_S": 12.0}) is None
    assert raw.digest() == before and raw.version == published
    expected = ("agent 'sim_robot' may not set attributes of 'clock': a clock node has no attribute 'now_S'; "
                "known: end_s, finished, mode, now_s, rate, start_s")
    assert checked.last_refusal.startswith(expected) and checked.refused == 1
    assert expected in caplog.text
    assert raw.replica.stats.rejects == {REASON: 1} and expected in raw.replica.stats.last_reject
    checked.update_node(clock.id, {"now_s": 12.0})                 # and it goes on
    assert raw.get_node_by_name(CLOCK).attrs["now_s"] == 12.0


@pytest.mark.parametrize(("write", "message"), [
    (lambda g: g.insert_node("robt", "r2", {}), "unknown node type 'robt'"),
    (lambda g: g.insert_node(NodeType.MISSION, "mission/m", {"state": "finished"}),
     "mission.state cannot be 'finished'; it is one of: pending, active, done, failed"),
    (lambda g: g.update_node(g.get_node_by_name(CLOCK).id, {"mode": "sleeping"}), "clock.mode cannot be 'sleeping'"),
    (lambda g: g.update_node(g.get_node_by_name(CLOCK).id, {"now_s": "ten"}), "clock.now_s must be float"),
    (lambda g: g.update_nodes({g.get_node_by_name(CLOCK).id: {"now_s": 1.0},
                               g.get_node_by_name("robot").id: {"pose_stmp": 1.0}}),
     "a robot node has no attribute 'pose_stmp'"),
    (lambda g: g.insert_or_assign_edge(g.get_node_by_name("world").id, g.get_node_by_name("robot").id, "rt", {}),
     "unknown edge type 'rt'"),
    (lambda g: g.insert_or_assign_edge(g.get_node_by_name("world").id, g.get_node_by_name("robot").id,
                                       EdgeType.RT, {"z": 1.0}), "a RT edge has no attribute 'z'"),
])
def test_unknown_types_attributes_and_states_are_refused(graphs, write, message) -> None:
    raw, checked = graphs
    before = raw.digest()
    with checked.transaction() as tx:
        assert tx is checked
        assert write(tx) is None
    assert message in checked.last_refusal and checked.refused == 1
    assert raw.digest() == before


def test_writes_inside_the_vocabulary_pass_unchanged(graphs) -> None:
    raw, checked = graphs
    mission = checked.insert_node(NodeType.MISSION, "mission/m", {"state": MissionState.PENDING, "time_s": 3.0})
    checked.update_nodes({mission.id: {"state": MissionState.ACTIVE}})
    assert raw.get_node(mission.id).attrs["state"] == "active" and type(raw.get_node(mission.id).type) is str
    assert checked.refused == 0 and raw.replica.stats.rejects == {}
    assert checked.nodes_of_type(NodeType.MISSION)[0].name == "mission/m"      # reads pass through
