"""The symbolic planner: plans through doors, no-plan cases, group missions, agenda, determinism,
optimality against uniform-cost search."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from typing import Any

import networkx as nx
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from grammar.errors import PlanningError
from grammar.missions import parse_mission, plan_mission, with_mission_node
from grammar.model import Grammar
from grammar.parser import default_grammar_path, load_grammar, load_target, parse_grammar, parse_target
from grammar.planner import NoPlan, Plan, Planner, plan
from grammar.world import graph_from_mapping
from tests.support import REPO_ROOT


@pytest.fixture(scope="module")
def grammar() -> Grammar:
    return load_grammar(default_grammar_path())


def rooms_in_a_row(n: int, extra_nodes: dict[str, Any] | None = None,
                   extra_edges: list[tuple[Any, ...]] | None = None) -> nx.MultiDiGraph:
    """room0 - room1 - ... - room(n-1), door i between room i and room i+1; robot in room0."""
    nodes: dict[str, Any] = {f"room{i}": {"type": "room"} for i in range(n)}
    nodes.update({f"door{i}": {"type": "door"} for i in range(n - 1)})
    nodes["robot"] = {"type": "omnirobot"}
    nodes.update(extra_nodes or {})
    edges: list[tuple[Any, ...]] = [(f"room{i}", f"room{i + 1}", "connected", {"door": f"door{i}"})
                                    for i in range(n - 1)]
    edges.append(("robot", "room0", "in"))
    edges += extra_edges or []
    return graph_from_mapping(nodes, edges)


def found(result: Plan | NoPlan) -> Plan:
    assert isinstance(result, Plan), getattr(result, "reason", result)
    return result


def test_plan_through_two_doors_with_bindings(grammar: Grammar) -> None:
    result = found(plan_mission(grammar, rooms_in_a_row(4), "room:room2"))
    assert [s.rule for s in result.steps] == ["changeRoom", "changeRoom"]
    assert [dict(s.bindings) for s in result.steps] == [
        {"robot": "robot", "r1": "room0", "r2": "room1", "d": "door0"},
        {"robot": "robot", "r1": "room1", "r2": "room2", "d": "door1"},
    ]
    assert result.cost == 2 and result.target_bindings["robot"] == "robot"
    assert str(result.steps[0]) == "changeRoom(robot=robot, r1=room0, r2=room1, d=door0)"


def test_plan_to_an_object_and_a_person(grammar: Grammar) -> None:
    graph = rooms_in_a_row(3, {"tv": {"type": "object"}, "ann": {"type": "person"}},
                           [("tv", "room2", "in"), ("ann", "room1", "in")])
    obj = found(plan_mission(grammar, graph, "object:tv"))
    assert [s.rule for s in obj.steps] == ["changeRoom", "changeRoom", "goToObject"]
    person = found(plan_mission(grammar, graph, "person:ann"))
    assert [s.rule for s in person.steps] == ["changeRoom", "approachPerson"]
    assert person.steps[-1].bindings["p"] == "ann"


def test_closed_door_makes_the_plan_take_the_other_way(grammar: Grammar) -> None:
    # a ring of four rooms: 0-1-2-3-0; closing door 0 (0-1) forces 0-3-2-1
    graph = rooms_in_a_row(4, {"door3": {"type": "door"}}, [("room3", "room0", "connected", {"door": "door3"})])
    assert [s.bindings["r2"] for s in found(plan_mission(grammar, graph, "room:room1")).steps] == ["room1"]
    graph.nodes["door0"]["open"] = False
    assert [s.bindings["r2"] for s in found(plan_mission(grammar, graph, "room:room1")).steps] == \
        ["room3", "room2", "room1"]


def test_unreachable_room_gives_no_plan_at_once(grammar: Grammar) -> None:
    graph = rooms_in_a_row(3, {"island": {"type": "room"}})
    result = plan_mission(grammar, graph, "room:island")
    assert isinstance(result, NoPlan) and "unreachable" in result.reason and result.expanded == 0


def test_unreachable_target_without_heuristic_exhausts_or_hits_the_limit(grammar: Grammar) -> None:
    graph = with_mission_node(rooms_in_a_row(6, {"island": {"type": "room"}}), parse_mission("room:island"))
    target = parse_mission("room:island").target
    planner = Planner(grammar, graph)
    exhausted = planner.plan(target, heuristic="zero")
    assert isinstance(exhausted, NoPlan) and "all 6 reachable states" in exhausted.reason
    limited = planner.plan(target, heuristic="zero", max_expansions=3)
    assert isinstance(limited, NoPlan) and "expansion limit of 3" in limited.reason and limited.expanded == 3


def test_unknown_names_and_wrong_types_are_reported(grammar: Grammar) -> None:
    graph = rooms_in_a_row(2, {"tv": {"type": "object"}})
    assert "no node named 'kitchen'" in plan_mission(grammar, graph, "room:kitchen").reason  # type: ignore[union-attr]
    assert "is a object, not a room" in plan_mission(grammar, graph, "room:tv").reason  # type: ignore[union-attr]
    with pytest.raises(PlanningError):
        Planner(grammar, graph).plan(parse_mission("room:room1").target, max_expansions=0)


def test_group_mission_needs_take_the_attention(grammar: Grammar) -> None:
    graph = rooms_in_a_row(3, {"ann": {"type": "person"}, "ben": {"type": "person"}, "cid": {"type": "person"}},
                           [("ann", "room2", "in"), ("ben", "room2", "in"), ("cid", "room2", "in"),
                            ("ann", "ben", "interacting"), ("ben", "cid", "interacting")])
    result = found(plan_mission(grammar, graph, "group:ann+cid"))
    assert [s.rule for s in result.steps] == ["changeRoom", "changeRoom", "takeTheAttention"]
    assert set(result.steps[-1].bindings.values()) >= {"ben"}
    final = result.final_state
    assert final is not None
    for person in ("ann", "ben", "cid"):
        assert final.has_edge(final.node_by_name("robot"), final.node_by_name(person), "facing")
    # people who are not a group cannot be faced together: no plan
    graph.remove_edge("ann", "ben", key="interacting")
    graph.remove_edge("ben", "cid", key="interacting")
    assert isinstance(plan_mission(grammar, graph, "group:ann+cid"), NoPlan)


def test_agenda_detour_wait_or_enter(grammar: Grammar) -> None:
    """A group therapy runs in room1. The robot detours when a detour exists and is cheaper than
    waiting, waits when it must pass, and enters directly when the mission is about room1."""
    therapy = ({"therapy": {"type": "activity", "state": "running"}, "bike": {"type": "object"},
                "p1": {"type": "person"}, "p2": {"type": "person"}},
               [("bike", "room1", "in"), ("therapy", "bike", "has"), ("p1", "therapy", "participant"),
                ("p2", "therapy", "participant")])
    line = rooms_in_a_row(3, *therapy)
    waited = found(plan_mission(grammar, line, "room:room2"))
    assert [s.rule for s in waited.steps] == ["waitForPassage", "changeRoom", "changeRoom"]
    assert waited.cost == 12
    entered = found(plan_mission(grammar, line, "room:room1"))
    assert [s.rule for s in entered.steps] == ["changeRoom"]
    ring = rooms_in_a_row(4, {**therapy[0], "door3": {"type": "door"}},
                          [*therapy[1], ("room3", "room0", "connected", {"door": "door3"})])
    detour = found(plan_mission(grammar, ring, "room:room2"))
    assert [s.bindings["r2"] for s in detour.steps] == ["room3", "room2"]


@pytest.mark.parametrize("detour_rooms,expected_cost,first_rule", [(9, 10, "changeRoom"), (13, 12, "waitForPassage")])
def test_cheapest_of_waiting_and_a_long_detour(grammar: Grammar, detour_rooms: int, expected_cost: float,
                                               first_rule: str) -> None:
    """room0-room1-room2 with a therapy in room1 (waiting costs 10), or a detour of
    ``detour_rooms`` rooms from room0 to room2: the plan must be the cheaper one, exactly."""
    nodes: dict[str, Any] = {"therapy": {"type": "activity", "state": "running"}, "bike": {"type": "object"},
                             "p1": {"type": "person"}, "p2": {"type": "person"}}
    edges: list[tuple[Any, ...]] = [("bike", "room1", "in"), ("therapy", "bike", "has"),
                                    ("p1", "therapy", "participant"), ("p2", "therapy", "participant")]
    chain = ["room0", *[f"x{i}" for i in range(detour_rooms)], "room2"]
    for i, (a, b) in enumerate(zip(chain, chain[1:])):
        nodes[f"xd{i}"] = {"type": "door"}
        edges.append((a, b, "connected", {"door": f"xd{i}"}))
    nodes.update({f"x{i}": {"type": "room"} for i in range(detour_rooms)})
    result = found(plan_mission(grammar, rooms_in_a_row(3, nodes, edges), "room:room2"))
    assert result.cost == expected_cost and result.steps[0].rule == first_rule


def test_plan_is_deterministic_in_process_and_across_hash_seeds(grammar: Grammar) -> None:
    graph = rooms_in_a_row(2, {f"r{i}": {"type": "room"} for i in range(4)} |
                           {f"d{i}": {"type": "door"} for i in range(6)},
                           [("room1", "r0", "connected", {"door": "d0"}), ("room1", "r1", "connected", {"door": "d1"}),
                            ("r0", "r2", "connected", {"door": "d2"}), ("r1", "r2", "connected", {"door": "d3"}),
                            ("r2", "r3", "connected", {"door": "d4"}), ("room0", "r3", "connected", {"door": "d5"})])
    first = found(plan_mission(grammar, graph, "room:r2"))
    second = found(plan_mission(grammar, graph, "room:r2"))
    assert first.steps == second.steps
    code = (
        "import json, networkx as nx; from networkx.readwrite import json_graph;"
        "from grammar.parser import load_grammar, default_grammar_path; from grammar.missions import plan_mission;"
        "import sys; g = json_graph.node_link_graph(json.loads(sys.stdin.read()), edges='links');"
        "r = plan_mission(load_grammar(default_grammar_path()), g, 'room:r2');"
        "print(json.dumps([[s.rule, dict(s.bindings)] for s in r.steps]))"
    )
    data = json.dumps(nx.node_link_data(graph, edges="links"))
    outputs = []
    for seed in ("1", "2"):
        env = dict(os.environ, PYTHONHASHSEED=seed)
        out = subprocess.run([sys.executable, "-c", code], input=data, capture_output=True, text=True,
                             cwd=REPO_ROOT, env=env, timeout=60, check=True)
        outputs.append(json.loads(out.stdout))
    expected = [[s.rule, dict(s.bindings)] for s in first.steps]
    assert outputs == [expected, expected]


def test_agm_corpus_grammar_plans_the_agm_target() -> None:
    corpus = REPO_ROOT.parent / "shared" / "corpus" / "aggl"
    if not corpus.is_dir():
        pytest.skip(f"AGM corpus not found at {corpus}")
    agm = load_grammar(corpus / "change_roomViriato2.aggl")
    target = load_target(corpus / "targetGoToKitchen_Viriato.aggt")
    graph = nx.MultiDiGraph()  # DSR-style: integer ids as keys
    graph.add_node(200, type="omnirobot", name="robot")
    for i, name in ((58, "hall"), (59, "corridor"), (60, "kitchen")):
        graph.add_node(i, type="room", name=name)
    graph.add_node(70, type="person", name="ann")
    for a, b in ((58, 59), (59, 60)):
        graph.add_edge(a, b, key="accessible", type="accessible")
        graph.add_edge(b, a, key="accessible", type="accessible")
    graph.add_edge(200, 58, key="in", type="in")
    result = found(plan(agm, graph, target))
    assert [(s.rule, s.bindings["room2"]) for s in result.steps] == [("changeRoom", "corridor"),
                                                                     ("changeRoom", "kitchen")]
    # a person blocking the robot: changeRoom's (forall p:person (not (is_blocking p robot))) fails
    # until the robot has asked for permission (goToPerson, takeTheAttention, askFor...)
    graph.add_edge(70, 200, key="is_blocking", type="is_blocking")
    asked = found(plan(agm, graph, target))
    assert [s.rule for s in asked.steps] == ["goToPerson", "takeTheAttention", "askForIndividualPermission",
                                             "changeRoom", "changeRoom"]
    assert asked.steps[0].bindings == {"p": "ann", "robot": "robot"}


def test_dormant_rules_need_activation_and_passive_rules_are_skipped() -> None:
    g = parse_grammar('''
        rule unlock activates open { lhs { d:door [locked] } rhs { d:door } set d.locked = false }
        rule open dormant { lhs { d:door } rhs { d:door  d->d(opened) } }
        rule magic passive cost 0 { lhs { d:door } rhs { d:door  d->d(opened) } }
    ''', "dormant.aggl")
    graph = graph_from_mapping({"door": {"type": "door", "locked": True}}, [])
    target = parse_target('target { "door":door  door->door(opened) }', "t.aggt")
    result = found(plan(g, graph, target))
    assert [s.rule for s in result.steps] == ["unlock", "open"]
    assert [s.rule for s in found(plan(g, graph, target, include_passive=True)).steps] == ["magic"]


# ----------------------------------------------------------------------------- optimality (property)
@st.composite
def random_centres(draw: st.DrawFn) -> tuple[nx.MultiDiGraph, str]:
    n = draw(st.integers(3, 7))
    nodes: dict[str, Any] = {f"room{i}": {"type": "room"} for i in range(n)}
    edges: list[tuple[Any, ...]] = []
    pairs = draw(st.lists(st.tuples(st.integers(0, n - 1), st.integers(0, n - 1)), min_size=2, max_size=12))
    for k, (a, b) in enumerate(dict.fromkeys(p for p in pairs if p[0] != p[1])):
        nodes[f"door{k}"] = {"type": "door", "open": draw(st.booleans()) or draw(st.booleans())}
        edges.append((f"room{a}", f"room{b}", "connected", {"door": f"door{k}"}))
    nodes["robot"] = {"type": "robot"}
    edges.append(("robot", "room0", "in"))
    for i in range(n):
        if draw(st.booleans()):
            nodes[f"obj{i}"] = {"type": "object"}
            edges.append((f"obj{i}", f"room{i}", "in"))
        if i and draw(st.integers(0, 3)) == 0:
            nodes |= {f"act{i}": {"type": "activity", "state": "running"}, f"pa{i}": {"type": "person"},
                      f"pb{i}": {"type": "person"}}
            edges += [(f"act{i}", f"room{i}", "in"), (f"pa{i}", f"act{i}", "participant"),
                      (f"pb{i}", f"act{i}", "participant")]
    goal = draw(st.sampled_from([f"room:room{n - 1}", f"room:room{n // 2}"] +
                                [f"object:obj{i}" for i in range(n) if f"obj{i}" in nodes]))
    return graph_from_mapping(nodes, edges), goal


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(random_centres())
def test_astar_with_heuristic_and_pruning_finds_the_uniform_cost_optimum(case: tuple[nx.MultiDiGraph, str]) -> None:
    graph, mission = case
    g = load_grammar(default_grammar_path())
    parsed = parse_mission(mission)
    planner = Planner(g, with_mission_node(graph, parsed))
    fast = planner.plan(parsed.target)
    slow = planner.plan(parsed.target, heuristic="zero", prune=False)
    assert fast.found == slow.found, (getattr(fast, "reason", ""), getattr(slow, "reason", ""))
    if isinstance(fast, Plan) and isinstance(slow, Plan):
        assert fast.cost == slow.cost


@st.composite
def random_centres_with_people(draw: st.DrawFn) -> tuple[nx.MultiDiGraph, str]:
    """Rooms in a row or a ring, objects and people in them, some people interacting with one
    another or with an object, a running group activity: every mission kind is drawn."""
    n = draw(st.integers(2, 5))
    nodes: dict[str, Any] = {f"room{i}": {"type": "room"} for i in range(n)}
    edges: list[tuple[Any, ...]] = []
    for i in range(n - 1 + draw(st.integers(0, 1))):
        nodes[f"door{i}"] = {"type": "door", "open": draw(st.integers(0, 5)) > 0}
        edges.append((f"room{i}", f"room{(i + 1) % n}", "connected", {"door": f"door{i}"}))
    nodes["robot"] = {"type": "omnirobot"}
    edges.append(("robot", f"room{draw(st.integers(0, n - 1))}", "in"))
    people = [f"p{i}" for i in range(draw(st.integers(1, 4)))]
    objects = [f"o{i}" for i in range(draw(st.integers(1, 3)))]
    for name in people + objects:
        nodes[name] = {"type": "person" if name in people else "object"}
        edges.append((name, f"room{draw(st.integers(0, n - 1))}", "in"))
    for a, b in draw(st.lists(st.tuples(st.sampled_from(people), st.sampled_from(people + objects)), max_size=3)):
        if a != b:
            edges.append((a, b, "interacting"))
    if len(people) >= 2 and draw(st.booleans()):
        nodes["game"] = {"type": "activity", "state": "running"}
        edges += [("game", objects[0], "has"), (people[0], "game", "participant"), (people[1], "game", "participant")]
    kinds = [f"room:room{draw(st.integers(0, n - 1))}", f"object:{draw(st.sampled_from(objects))}",
             f"person:{draw(st.sampled_from(people))}"]
    if len(people) >= 2:
        kinds.append(f"group:{people[0]}+{people[1]}")
    return graph_from_mapping(nodes, edges), draw(st.sampled_from(kinds))


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(random_centres_with_people())
def test_pruning_keeps_the_optimum_for_every_mission_kind(case: tuple[nx.MultiDiGraph, str]) -> None:
    """Relevance (typed, and without rules that only remove links nobody needs absent) never
    changes whether a plan exists or its cost."""
    graph, mission = case
    g = load_grammar(default_grammar_path())
    parsed = parse_mission(mission)
    planner = Planner(g, with_mission_node(graph, parsed))
    fast = planner.plan(parsed.target, max_expansions=50_000)
    slow = planner.plan(parsed.target, heuristic="zero", prune=False, max_expansions=50_000)
    assert fast.found == slow.found, (mission, getattr(fast, "reason", ""), getattr(slow, "reason", ""))
    if isinstance(fast, Plan) and isinstance(slow, Plan):
        assert fast.cost == slow.cost, (mission, fast.steps, slow.steps)
