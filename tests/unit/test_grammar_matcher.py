"""Typed subgraph matching, formulas and rule application on small hand-built worlds."""

from __future__ import annotations

import networkx as nx
import pytest

from grammar.errors import PlanningError
from grammar.formulas import FormulaEvaluator
from grammar.matcher import Matcher
from grammar.model import TypeTable
from grammar.parser import parse_grammar, parse_target
from grammar.rewrite import apply_rule
from grammar.world import State, World, graph_from_mapping

TYPES = TypeTable({"entity": (), "robot": ("entity",), "omnirobot": ("robot",), "room": ("entity",),
                   "person": ("entity",), "object": ("entity",)})


def world() -> nx.MultiDiGraph:
    return graph_from_mapping(
        {"r1": {"type": "room"}, "r2": {"type": "room"}, "r3": {"type": "room"},
         "bot": {"type": "omnirobot"}, "ann": {"type": "person", "age": 80}, "ben": {"type": "person", "age": 70},
         "tv": {"type": "object", "tags": ["screen", "big"]}},
        [("bot", "r1", "in"), ("ann", "r1", "in"), ("ben", "r2", "in"), ("tv", "r2", "in"),
         ("r1", "r2", "connected", {"door": "d12"}), ("r3", "r2", "connected", {"door": "d23"}),
         ("ann", "ben", "interacting")])


def names(state: State, matches: list[dict[str, int]]) -> list[dict[str, str]]:
    return [{k: state.name_of(v) for k, v in m.items()} for m in matches]


def match(target_text: str, graph: nx.MultiDiGraph | None = None, types: TypeTable = TYPES) -> list[dict[str, str]]:
    target = parse_target(target_text, "t.aggt")
    w = World(graph if graph is not None else world())
    matcher = Matcher(types, w)
    state = w.initial_state()
    return names(state, list(matcher.matches(matcher.compile(target.pattern), state)))


def test_type_inheritance_matches_subtypes_only_downwards() -> None:
    assert match("target { x:robot }") == [{"x": "bot"}]
    assert match("target { x:entity x->r1(in) \"r1\":room }") in ([{"x": "bot", "r1": "r1"}, {"x": "ann", "r1": "r1"}],)
    assert match("target { x:omnirobot }") == [{"x": "bot"}]
    assert match("target { x:room x->y(in) y:room }") == []


def test_injective_and_negated_and_undirected_links() -> None:
    # two distinct people: only (ann, ben) and (ben, ann)
    assert sorted(m["p"] for m in match("target { p:person q:person }")) == ["ann", "ben"]
    assert match("target { p:person q:person p->q(interacting) }") == [{"p": "ann", "q": "ben"}]
    assert match("target { p:person r:room p->r(in) not p->r(in) }") == []
    assert match("target { p:person r:room p->r(in) p->p(asleep)* }") == [{"p": "ann", "r": "r1"},
                                                                        {"p": "ben", "r": "r2"}]
    # directed: r2 has no outgoing connected edge; undirected: both neighbours
    assert match('target { "r2":room x:room r2->x(connected) }') == []
    assert sorted(m["x"] for m in match('target { "r2":room x:room r2--x(connected) }')) == ["r1", "r3"]


def test_attribute_conditions_on_nodes_and_edges_and_name_join() -> None:
    assert match("target { p:person [age > 75] }") == [{"p": "ann"}]
    assert match('target { o:object ["screen" in tags] }') == [{"o": "tv"}]
    assert match("target { p:person [missing > 1] }") == []             # missing attribute: false, no crash
    assert match('target { p:person [age > "old"] }') == []             # mismatched types: false, no crash
    graph = world()
    graph.add_node("d12", type="door", name="d12", open=True)
    graph.add_node("d23", type="door", name="d23", open=False)
    found = match('target { a:room b:room d:door [open] a--b(connected) [door == d.name] }', graph,
                  TypeTable({"door": ()}))
    assert sorted((m["a"], m["b"], m["d"]) for m in found) == [("r1", "r2", "d12"), ("r2", "r1", "d12")]


def test_constant_matches_by_name_or_graph_key_like_agm_ids() -> None:
    graph = nx.MultiDiGraph()
    graph.add_node(200, type="omnirobot", name="viriato")
    graph.add_node(60, type="room", name="kitchen")
    graph.add_edge(200, 60, key="in", type="in")
    target = parse_target("{ 200:omnirobot 60:room 200->60(in) }", "t.aggt")
    w = World(graph)
    matcher = Matcher(TypeTable(), w)
    found = list(matcher.matches(matcher.compile(target.pattern), w.initial_state()))
    assert found == [{"200": 0, "60": 1}]


def test_world_rejects_nodes_without_type_and_duplicate_names() -> None:
    graph = nx.MultiDiGraph()
    graph.add_node(1, name="x")
    with pytest.raises(PlanningError, match="no 'type'"):
        World(graph)
    graph = nx.MultiDiGraph()
    graph.add_node(1, type="room", name="x")
    graph.add_node(2, type="room", name="x")
    with pytest.raises(PlanningError, match="named 'x'"):
        World(graph)


RULES = '''
types { entity  room, person, object, robot, note : entity  omnirobot : robot }
rule move {
    lhs { r:robot a:room b:room r->a(in) a--b(connected) }
    rhs { r:robot a:room b:room r->b(in) a--b(connected) }
    effect { (forall x:person (when (near r x) (not (near r x)))) }
}
rule greet {
    lhs { r:robot a:room p:person r->a(in) p->a(in) }
    rhs { r:robot a:room p:person r->a(in) p->a(in) r->p(near) n:note n->p(about) }
    effect { (forall x:person (when (near r x) (not (near r x)))) }
    set n.text = p.name
    set p.greeted = true
}
rule forget {
    lhs { n:note p:person n->p(about) }
    rhs { p:person }
}
rule promote {
    lhs { p:person }
    rhs { p:object }
    precondition { (forall q:person (when (near q p) (= q p))) }
}
'''


def setup() -> tuple[Matcher, FormulaEvaluator, State, object]:
    g = parse_grammar(RULES, "rules.aggl")
    w = World(world())
    m = Matcher(g.types, w)
    return m, FormulaEvaluator(m), w.initial_state(), g


def apply(name: str, state: State, m: Matcher, f: FormulaEvaluator, g: object, **pins: str) -> State:
    rule = g.rule(name)  # type: ignore[attr-defined]
    for b in m.matches(m.compile(rule.lhs), state):
        if all(state.name_of(b[k]) == v for k, v in pins.items()):
            if rule.precondition is None or f.holds(rule.precondition, state, b):
                return apply_rule(rule, state, b, m, f).state
    raise AssertionError(f"{name} not applicable with {pins}")


def test_rewrite_moves_creates_sets_and_deletes() -> None:
    m, f, s0, g = setup()
    s1 = apply("greet", s0, m, f, g, p="ann")
    ann, bot = s1.node_by_name("ann"), s1.node_by_name("bot")
    assert ann is not None and bot is not None
    assert s1.has_edge(bot, ann, "near")                      # added by the RHS, not undone by the effect
    notes = list(s1.nodes_of_type("note"))
    assert len(notes) == 1 and s1.attr(notes[0], "text") == "ann"
    assert s1.attr(ann, "greeted") is True and s0.attr(ann, "greeted") is None   # s0 untouched
    s2 = apply("move", s1, m, f, g, b="r2")
    assert not s2.has_edge(bot, ann, "near")                  # effect cleared it
    assert s2.has_edge(bot, s2.node_by_name("r2"), "in") and not s2.has_edge(bot, s2.node_by_name("r1"), "in")
    s3 = apply("forget", s2, m, f, g)
    assert list(s3.nodes_of_type("note")) == []
    # moving back and forth gives the very same state (canonical overlay)
    back = apply("move", apply("move", s0, m, f, g, b="r2"), m, f, g, b="r1")
    assert back == s0 and hash(back) == hash(s0)


def test_retype_and_precondition_forall() -> None:
    m, f, s0, g = setup()
    s1 = apply("promote", s0, m, f, g, p="ben")
    ben = s1.node_by_name("ben")
    assert ben is not None and s1.type_of(ben) == "object"
    assert [s1.name_of(n) for n in s1.nodes_of_type("person")] == ["ann"]
    assert sorted(s1.name_of(n) for n in s1.nodes_of_type("object")) == ["ben", "tv"]
    graph = s1.to_networkx()
    assert graph.nodes["ben"]["type"] == "object"


def test_state_to_networkx_round_trip_keeps_edges() -> None:
    m, f, s0, g = setup()
    s1 = apply("greet", s0, m, f, g, p="ann")
    graph = s1.to_networkx()
    assert graph.has_edge("bot", "ann", key="near")
    again = World(graph).initial_state()
    assert again.has_edge(again.node_by_name("bot"), again.node_by_name("ann"), "near")
