"""One test group per rule of the shipped grammar/social_navigation.aggl."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import networkx as nx
import pytest

from grammar.missions import parse_mission, with_mission_node
from grammar.model import Grammar
from grammar.parser import default_grammar_path, load_grammar
from grammar.planner import Planner
from grammar.world import State, graph_from_mapping


@pytest.fixture(scope="module")
def grammar() -> Grammar:
    return load_grammar(default_grammar_path())


def centre(extra_nodes: Mapping[str, Mapping[str, Any]] | None = None,
           extra_edges: list[tuple[Any, ...]] | None = None, door_open: bool = True) -> nx.MultiDiGraph:
    """hall -(d1)- gym -(d2)- lounge ; the robot in the hall; a TV in the lounge."""
    nodes: dict[str, Mapping[str, Any]] = {
        "hall": {"type": "room"}, "gym": {"type": "room"}, "lounge": {"type": "room"},
        "d1": {"type": "door", "open": door_open}, "d2": {"type": "door"},
        "robot": {"type": "omnirobot"}, "tv": {"type": "object"},
    }
    nodes.update(extra_nodes or {})
    edges: list[tuple[Any, ...]] = [("hall", "gym", "connected", {"door": "d1"}),
                                    ("gym", "lounge", "connected", {"door": "d2"}),
                                    ("robot", "hall", "in"), ("tv", "lounge", "in")]
    edges += extra_edges or []
    return graph_from_mapping(nodes, edges)


def steps(grammar: Grammar, graph: nx.MultiDiGraph, rule: str, mission: str | None = None,
          state: State | None = None) -> list[tuple[dict[str, str], State]]:
    """Every application of ``rule`` in ``graph`` (or ``state``): (bindings by name, next state)."""
    if mission is not None:
        graph = with_mission_node(graph, parse_mission(mission))
    planner = Planner(grammar, graph)
    s = state if state is not None else planner.world.initial_state()
    return [({var: s.name_of(n) if s.exists(n) else nxt.name_of(n) for var, n in b.items()}, nxt)
            for r, b, nxt in planner.applications(s) if r.name == rule]


def edge(state: State, src: str, dst: str, label: str) -> bool:
    s, d = state.node_by_name(src), state.node_by_name(dst)
    return s is not None and d is not None and state.has_edge(s, d, label)


def group_activity(room_object: str, state: str = "running") -> tuple[dict[str, Any], list[tuple[Any, ...]]]:
    nodes = {"therapy": {"type": "activity", "state": state}, "p1": {"type": "person"}, "p2": {"type": "person"}}
    edges = [("therapy", room_object, "has"), ("p1", "therapy", "participant"), ("p2", "therapy", "participant")]
    return nodes, edges


# ----------------------------------------------------------------------------- changeRoom
def test_change_room_goes_through_the_door_named_on_the_connected_edge(grammar: Grammar) -> None:
    found = steps(grammar, centre(), "changeRoom")
    assert [b for b, _ in found] == [{"robot": "robot", "r1": "hall", "r2": "gym", "d": "d1"}]
    after = found[0][1]
    assert edge(after, "robot", "gym", "in") and not edge(after, "robot", "hall", "in")
    # the connected edge is undirected for the rule: from the gym both neighbours are reachable
    from_gym = steps(grammar, centre(), "changeRoom", state=after)
    assert sorted(b["r2"] for b, _ in from_gym) == ["hall", "lounge"]


def test_change_room_needs_an_open_existing_door(grammar: Grammar) -> None:
    assert steps(grammar, centre(door_open=False), "changeRoom") == []
    no_door = centre()
    no_door.remove_node("d1")
    assert steps(grammar, no_door, "changeRoom") == []


def test_change_room_refuses_a_room_with_a_running_group_activity(grammar: Grammar) -> None:
    nodes, edges = group_activity("bike")
    graph = centre({"bike": {"type": "object"}, **nodes}, [("bike", "gym", "in"), *edges])
    assert steps(grammar, graph, "changeRoom") == []
    # ... unless it is not running, or has one participant only
    graph.nodes["therapy"]["state"] = "finished"
    assert len(steps(grammar, graph, "changeRoom")) == 1
    graph.nodes["therapy"]["state"] = "running"
    graph.remove_edge("p2", "therapy", key="participant")
    assert len(steps(grammar, graph, "changeRoom")) == 1


def test_change_room_enters_a_busy_room_when_the_mission_targets_it_or_something_in_it(grammar: Grammar) -> None:
    nodes, edges = group_activity("bike")
    graph = centre({"bike": {"type": "object"}, **nodes}, [("bike", "gym", "in"), *edges])
    assert len(steps(grammar, graph, "changeRoom", mission="room:gym")) == 1
    assert len(steps(grammar, graph, "changeRoom", mission="object:bike")) == 1
    assert steps(grammar, graph, "changeRoom", mission="room:lounge") == []


def test_change_room_forgets_near_and_facing(grammar: Grammar) -> None:
    graph = centre({"ann": {"type": "person"}}, [("ann", "hall", "in"), ("robot", "ann", "near"),
                                                 ("robot", "ann", "facing")])
    (_, after), = steps(grammar, graph, "changeRoom")
    assert not edge(after, "robot", "ann", "near") and not edge(after, "robot", "ann", "facing")


# ----------------------------------------------------------------------------- goToObject
def test_go_to_object_only_in_the_robots_room_and_when_free(grammar: Grammar) -> None:
    graph = centre({"lamp": {"type": "object"}, "sofa": {"type": "object"}},
                   [("lamp", "hall", "in"), ("sofa", "hall", "in"), ("robot", "sofa", "near")])
    found = steps(grammar, graph, "goToObject")
    assert [b["o"] for b, _ in found] == ["lamp"]            # tv is elsewhere, sofa already near
    after = found[0][1]
    assert edge(after, "robot", "lamp", "near") and not edge(after, "robot", "sofa", "near")


def test_go_to_object_refuses_an_interaction_space_in_use(grammar: Grammar) -> None:
    busy = centre({"lamp": {"type": "object"}, "act": {"type": "activity", "state": "running"}},
                  [("lamp", "hall", "in"), ("act", "lamp", "has")])
    assert steps(grammar, busy, "goToObject") == []
    busy.nodes["act"]["state"] = "scheduled"
    assert len(steps(grammar, busy, "goToObject")) == 1
    used = centre({"lamp": {"type": "object"}, "ann": {"type": "person"}},
                  [("lamp", "hall", "in"), ("ann", "hall", "in"), ("ann", "lamp", "interacting")])
    assert steps(grammar, used, "goToObject") == []


# ----------------------------------------------------------------------------- approachPerson
def test_approach_person_ends_near_and_facing(grammar: Grammar) -> None:
    graph = centre({"ann": {"type": "person"}, "ben": {"type": "person"}, "lamp": {"type": "object"}},
                   [("ann", "hall", "in"), ("ben", "gym", "in"), ("lamp", "hall", "in"), ("robot", "lamp", "near")])
    found = steps(grammar, graph, "approachPerson")
    assert [b["p"] for b, _ in found] == ["ann"]
    after = found[0][1]
    assert edge(after, "robot", "ann", "near") and edge(after, "robot", "ann", "facing")
    assert not edge(after, "robot", "lamp", "near")
    assert steps(grammar, graph, "approachPerson", state=after) == []   # already facing: nothing to do


def test_approach_person_leaves_activity_participants_alone_unless_targeted(grammar: Grammar) -> None:
    nodes, edges = group_activity("lamp")
    graph = centre({"lamp": {"type": "object"}, **nodes},
                   [("lamp", "hall", "in"), ("p1", "hall", "in"), ("p2", "hall", "in"), *edges])
    assert steps(grammar, graph, "approachPerson") == []
    assert [b["p"] for b, _ in steps(grammar, graph, "approachPerson", mission="person:p2")] == ["p2"]


# ----------------------------------------------------------------------------- takeTheAttention
def test_take_the_attention_faces_every_member_of_the_group(grammar: Grammar) -> None:
    graph = centre({"ann": {"type": "person"}, "ben": {"type": "person"}, "cid": {"type": "person"},
                    "dan": {"type": "person"}},
                   [("ann", "hall", "in"), ("ben", "hall", "in"), ("cid", "hall", "in"), ("dan", "hall", "in"),
                    ("ann", "ben", "interacting"), ("cid", "ann", "interacting"), ("robot", "dan", "facing")])
    found = steps(grammar, graph, "takeTheAttention")
    assert sorted((b["p"], b["q"]) for b, _ in found) == [("ann", "ben"), ("cid", "ann")]
    after = found[0][1]
    for member in ("ann", "ben", "cid"):
        assert edge(after, "robot", member, "facing"), member
    assert not edge(after, "robot", "dan", "facing")        # the robot turned away from dan


def test_take_the_attention_needs_the_group_in_the_robots_room(grammar: Grammar) -> None:
    graph = centre({"ann": {"type": "person"}, "ben": {"type": "person"}},
                   [("ann", "gym", "in"), ("ben", "gym", "in"), ("ann", "ben", "interacting")])
    assert steps(grammar, graph, "takeTheAttention") == []


# ----------------------------------------------------------------------------- waitFor
def test_wait_for_ends_a_targeted_activity(grammar: Grammar) -> None:
    graph = centre({"act": {"type": "activity", "state": "running"}}, [("act", "tv", "has")])
    assert steps(grammar, graph, "waitFor") == []            # not targeted, not in the way
    (b, after), = steps(grammar, graph, "waitFor", mission="wait:act")
    assert b == {"m": "mission", "a": "act"} and after.attr(after.node_by_name("act"), "state") == "finished"
    graph.nodes["act"]["state"] = "finished"
    assert steps(grammar, graph, "waitFor", mission="wait:act") == []


def test_wait_for_passage_waits_for_an_activity_in_the_next_room(grammar: Grammar) -> None:
    nodes, edges = group_activity("bike")
    graph = centre({"bike": {"type": "object"}, **nodes}, [("bike", "gym", "in"), *edges])
    (b, after), = steps(grammar, graph, "waitForPassage")
    assert b == {"robot": "robot", "r1": "hall", "r2": "gym", "o": "bike", "a": "therapy"}
    assert len(steps(grammar, graph, "changeRoom", state=after)) == 1   # now the gym may be entered
    far = centre({"bike": {"type": "object"}, **nodes}, [("bike", "lounge", "in"), *edges])
    assert steps(grammar, far, "waitForPassage") == []                  # not next to the robot
