"""The DSR vocabulary (agents/world/vocabulary.py) and the write policy agree, both ways."""

from __future__ import annotations

import pytest

from agents.world.vocabulary import EDGES, NODES, VocabularyError, check_attrs
from agents.world.write_policy import DEFAULT_POLICY_FILE, load_policy
from dsr.writes import Write

POLICY = load_policy(DEFAULT_POLICY_FILE)


def test_every_declared_write_is_granted() -> None:
    refused = []
    for spec in NODES.values():
        for creator in spec.creators:
            if not POLICY.allowed(Write(creator.replace("*", "x"), "node", spec.type, "create")):
                refused.append(f"{creator} create {spec.type}")
        for key, (_, writers) in spec.attrs.items():
            for writer in writers:
                name = writer.replace("*", "x")
                # a creator may give the value at creation only (the robot's radius, say)
                at_creation = writer in spec.creators and POLICY.allowed(Write(name, "node", spec.type, "init", attr=key))
                if not (at_creation or POLICY.allowed(Write(name, "node", spec.type, "attr", attr=key))):
                    refused.append(f"{writer} set {spec.type}.{key}")
    for edge in EDGES:
        for writer in edge.writers:
            for src in edge.src:
                for dst in edge.dst:
                    if not POLICY.allowed(Write(writer, "edge", edge.type, "create", src=src, dst=dst)):
                        refused.append(f"{writer} create {src}-{edge.type}->{dst}")
    assert refused == []


def test_the_policy_grants_only_declared_types() -> None:
    node_types = set(NODES)
    edge_types = {edge.type for edge in EDGES}
    for rule in POLICY.rules:
        assert set(rule.nodes) <= node_types, f"policy grants unknown node types {set(rule.nodes) - node_types}"
        assert set(rule.edges) <= edge_types, f"policy grants unknown edge types {set(rule.edges) - edge_types}"


def test_an_undeclared_write_is_refused_by_the_policy() -> None:
    assert not POLICY.allowed(Write("human_observer", "node", "robot", "attr", attr="cmd_vx"))
    assert not POLICY.allowed(Write("social_navigation", "node", "clock", "attr", attr="now_s"))


def test_attribute_kinds_are_checked() -> None:
    check_attrs("clock", {"now_s": 1.0, "mode": "idle"})
    with pytest.raises(VocabularyError, match="clock.now_s must be float"):
        check_attrs("clock", {"now_s": "ten"})
    with pytest.raises(VocabularyError, match="no attribute 'now_S'"):
        check_attrs("clock", {"now_S": 1.0})


def test_state_names_and_typed_views() -> None:
    from agents.lib.agenda.model import ActivityState as AgendaState
    from agents.world.vocabulary import (ActivityState, IntentionState, IntentionView, MissionState, MissionView,
                                         activity_id_of, activity_name, intentions, missions)
    from dsr import DSRGraph

    assert {s.value for s in AgendaState} == {ActivityState.SCHEDULED, ActivityState.UPCOMING, ActivityState.RUNNING,
                                              *ActivityState.ENDED}
    assert activity_id_of(activity_name("tv_game")) == "tv_game"
    graph = DSRGraph(agent="test")
    mission = graph.insert_node("mission", "mission/m", {"mission_id": "m", "goal": "room:hall", "time_s": 5.0,
                                                          "state": MissionState.DONE, "finished_s": 9.0})
    graph.insert_node("intention", "intention/m/0.1", {"mission_id": "m", "kind": "navigate", "goal_x": 1.0,
                                                       "goal_y": 2.0, "goal_theta": 0.0, "goal_has_theta": False,
                                                       "rooms": ["a", "b"], "state": IntentionState.ACTIVE})
    (view,) = missions(graph)
    assert view == MissionView.from_node(mission) and view.terminal and view.finished_s == 9.0
    (intention,) = intentions(graph, "m")
    assert isinstance(intention, IntentionView) and intention.active
    assert intention.goal == (1.0, 2.0, None) and intention.rooms == ("a", "b") and intentions(graph, "x") == []
