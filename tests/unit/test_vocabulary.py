"""The DSR vocabulary (agents/world/vocabulary.py) and the write policy agree, both ways."""

from __future__ import annotations

import pytest

from agents.world.vocabulary import VocabularyError, check_attrs, check_edge, own_vocabulary
from agents.world.write_policy import DEFAULT_POLICY_FILE, load_policy
from dsr.writes import Write

POLICY = load_policy(DEFAULT_POLICY_FILE)
#: chronav's vocabulary with its own agents (their heartbeats): what the shipped policy holds
NODES, EDGES = own_vocabulary().nodes, own_vocabulary().edges


def test_the_shipped_policy_is_what_the_vocabulary_generates() -> None:
    from agents.world.write_policy import render_policy_yaml, vocabulary_rules

    assert list(POLICY.rules) == vocabulary_rules(), \
        ("write_policy.yaml differs from the vocabulary: "
         "python -m agents.world.write_policy > agents/world/write_policy.yaml")
    assert DEFAULT_POLICY_FILE.read_text() == render_policy_yaml()


def test_no_grant_is_a_wildcard() -> None:
    for rule in POLICY.rules:
        ends = (*rule.from_, *rule.to) if rule.edges else ()    # node rules: from/to unused
        for pattern in (*rule.writers, *rule.nodes, *rule.edges, *ends, *rule.attrs, *(rule.init_attrs or ())):
            assert "*" not in pattern or pattern == "agenda_tool-*", (rule, pattern)
        assert "create" not in rule.ops or rule.init_attrs is not None, f"{rule}: create brings any value"


def test_every_declared_write_is_granted() -> None:
    refused = []
    for spec in NODES.values():
        for creator in spec.creators:
            if not POLICY.allowed(Write(creator.replace("*", "x"), "node", spec.type, "create")):
                refused.append(f"{creator} create {spec.type}")
        for key, attr in spec.attrs.items():
            for writer in attr.writers:
                if not POLICY.allowed(Write(writer.replace("*", "x"), "node", spec.type, "attr", attr=key)):
                    refused.append(f"{writer} set {spec.type}.{key}")
            for writer in (*attr.writers, *attr.init_by):
                value = spec.init_values.get(writer, {}).get(key, (None,))[0]
                if writer in spec.creators and not POLICY.allowed(
                        Write(writer.replace("*", "x"), "node", spec.type, "init", attr=key, value=value)):
                    refused.append(f"{writer} create a {spec.type} with {key}")
    for edge in EDGES:
        for writer in edge.writers:
            for src in edge.src:
                for dst in edge.dst:
                    if not POLICY.allowed(Write(writer, "edge", edge.type, "create", src=src, dst=dst)):
                        refused.append(f"{writer} create {src}-{edge.type}->{dst}")
    assert refused == []


def test_the_policy_refuses_what_the_vocabulary_does_not_declare() -> None:
    # a typo'd attribute, at creation and later (the vocabulary's own example)
    assert not POLICY.allowed(Write("sim_robot", "node", "clock", "attr", attr="now_S"))
    assert not POLICY.allowed(Write("sim_robot", "node", "clock", "init", attr="now_S"))
    # an attribute given only at creation may not be changed later
    assert POLICY.allowed(Write("sim_robot", "node", "robot", "init", attr="radius"))
    assert not POLICY.allowed(Write("sim_robot", "node", "robot", "attr", attr="radius"))
    # the ROS bridge creates missions but never changes them
    assert POLICY.allowed(Write("ros_bridge", "node", "mission", "init", attr="state"))
    assert not POLICY.allowed(Write("ros_bridge", "node", "mission", "attr", attr="state"))
    # a staff tool creates a request pending only
    assert POLICY.allowed(Write("agenda_tool-1", "node", "agenda_request", "init", attr="state", value="pending"))
    assert not POLICY.allowed(Write("agenda_tool-1", "node", "agenda_request", "init", attr="state",
                                    value="accepted"))


def test_the_policy_grants_only_declared_types() -> None:
    node_types = set(NODES)
    edge_types = {edge.type for edge in EDGES}
    for rule in POLICY.rules:
        assert set(rule.nodes) <= node_types, f"policy grants unknown node types {set(rule.nodes) - node_types}"
        assert set(rule.edges) <= edge_types, f"policy grants unknown edge types {set(rule.edges) - edge_types}"


def test_an_undeclared_write_is_refused_by_the_policy() -> None:
    assert not POLICY.allowed(Write("human_observer", "node", "robot", "attr", attr="cmd_vx"))
    assert not POLICY.allowed(Write("social_navigation", "node", "clock", "attr", attr="now_s"))


def test_attribute_kinds_and_states_are_checked() -> None:
    check_attrs("clock", {"now_s": 1.0, "mode": "idle"})
    with pytest.raises(VocabularyError, match="clock.now_s must be float"):
        check_attrs("clock", {"now_s": "ten"})
    with pytest.raises(VocabularyError, match="no attribute 'now_S'"):
        check_attrs("clock", {"now_S": 1.0})
    with pytest.raises(VocabularyError, match="mission.state cannot be 'finished'; it is one of: pending, active"):
        check_attrs("mission", {"state": "finished"})
    with pytest.raises(VocabularyError, match="unknown node type 'robt'"):
        check_attrs("robt", {})
    check_edge("RT", {"x": 1.0, "y": 2, "theta": 0.0})
    with pytest.raises(VocabularyError, match="unknown edge type 'rt'"):
        check_edge("rt", {})
    with pytest.raises(VocabularyError, match="a RT edge has no attribute 'z'"):
        check_edge("RT", {"z": 1.0})


def test_every_state_attribute_names_its_state_set() -> None:
    from agents.world.vocabulary import (ActivityState, ClockMode, IntentionKind, IntentionState, MissionState,
                                         RequestState)

    sets = {(spec.type, key): attr.values for spec in NODES.values() for key, attr in spec.attrs.items()
            if attr.values is not None}
    assert sets == {("clock", "mode"): ClockMode, ("activity", "state"): ActivityState,
                    ("agenda_request", "state"): RequestState, ("mission", "state"): MissionState,
                    ("intention", "kind"): IntentionKind, ("intention", "state"): IntentionState}
    # every attribute key constant is declared on its type, and the other way round
    from agents.world import vocabulary as v
    for spec in NODES.values():
        keys = getattr(v, {"agenda_request": "RequestAttr", "ground_truth": "GroundTruthAttr"}.get(
            spec.type, spec.type.capitalize() + "Attr"), None)
        assert set(spec.attrs) == (set() if keys is None else set(keys)), spec.type


def test_state_names_and_typed_views() -> None:
    from agents.lib.agenda import ActivityState as AgendaState
    from agents.world.vocabulary import (ActivityState, IntentionState, IntentionView, MissionState, MissionView,
                                         activity_id_of, activity_name, intentions, missions)
    from dsr import DSRGraph

    assert AgendaState is ActivityState        # one definition (agents/lib/states.py)
    assert set(ActivityState.ENDED) == {ActivityState.FINISHED, ActivityState.CANCELLED}
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
