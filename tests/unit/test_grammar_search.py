"""The A* search alone (grammar/search.py) on toy tasks, as pyperplan tests its searches: cheapest
paths against networkx's Dijkstra, dead ends, both bounds; and the planner's memory bound on a
grammar whose only rule creates a node every time it applies (a regression: 3.8 GB before)."""

from __future__ import annotations

import math
import random
from collections.abc import Iterable

import networkx as nx
import pytest

from grammar.parser import parse_grammar, parse_target
from grammar.planner import NoPlan, Planner
from grammar.search import SearchResult, astar, zero
from grammar.world import graph_from_mapping


class GraphTask:
    """Shortest path on a weighted directed graph: states are node names."""

    def __init__(self, graph: nx.DiGraph, start: str, goal: str) -> None:
        self.graph, self.start, self.target = graph, start, goal

    def initial(self) -> str:
        return self.start

    def goal(self, state: str) -> object | None:
        return "reached" if state == self.target else None

    def successors(self, state: str) -> Iterable[tuple[str, str, float]]:
        for nxt in sorted(self.graph.successors(state)):
            yield f"{state}->{nxt}", nxt, self.graph[state][nxt]["weight"]

    def size(self, state: str) -> int:
        return 1


class CounterTask:
    """States are tuples that grow by one item per step and never reach the goal: the kept
    states' total size grows with the square of the expansions (like a node-creating rule)."""

    def initial(self) -> tuple[int, ...]:
        return ()

    def goal(self, state: tuple[int, ...]) -> object | None:
        return None

    def successors(self, state: tuple[int, ...]) -> Iterable[tuple[str, tuple[int, ...], float]]:
        yield "grow", state + (len(state),), 1.0

    def size(self, state: tuple[int, ...]) -> int:
        return 1 + len(state)


def random_graph(seed: int) -> nx.DiGraph:
    rng = random.Random(seed)
    graph = nx.DiGraph()
    names = [f"n{i}" for i in range(12)]
    graph.add_nodes_from(names)
    for _ in range(30):
        a, b = rng.sample(names, 2)
        graph.add_edge(a, b, weight=rng.choice([0.5, 1.0, 2.0, 3.0]))
    return graph


@pytest.mark.parametrize("seed", range(8))
def test_astar_finds_a_cheapest_path_like_dijkstra(seed: int) -> None:
    graph = random_graph(seed)
    task = GraphTask(graph, "n0", "n11")
    result: SearchResult[str, str] = astar(task)
    if not nx.has_path(graph, "n0", "n11"):
        assert result.outcome == "exhausted" and not result.found and result.path == ()
        return
    assert result.found and result.witness == "reached" and result.goal == "n11"
    assert result.cost == pytest.approx(nx.dijkstra_path_length(graph, "n0", "n11"))
    # the path is connected and its costs add up to the reported cost
    assert result.path[0].before == "n0" and result.path[-1].after == "n11"
    assert all(a.after == b.before for a, b in zip(result.path, result.path[1:]))
    assert sum(graph[s.before][s.after]["weight"] for s in result.path) == pytest.approx(result.cost)
    assert astar(task) == result  # deterministic


def test_an_admissible_heuristic_expands_fewer_states_for_the_same_cost() -> None:
    line = nx.DiGraph()
    for i in range(20):  # a line n0..n20 and a fan of dead branches at every node
        line.add_edge(f"n{i}", f"n{i + 1}", weight=1.0)
        line.add_edge(f"n{i}", f"x{i}", weight=1.0)
    task = GraphTask(line, "n0", "n20")
    remaining = {f"n{i}": 20 - i for i in range(21)}
    informed = astar(task, lambda s: remaining.get(s, math.inf))
    blind = astar(task, zero)
    assert informed.cost == blind.cost == 20
    assert informed.expanded == 20 < blind.expanded


def test_dead_ends_are_not_queued_and_an_infinite_start_is_exhausted_at_once() -> None:
    graph = random_graph(1)
    task = GraphTask(graph, "n0", "n11")
    assert astar(task, lambda s: math.inf) == SearchResult("exhausted", 0, 0, 1)


def test_the_expansion_bound_stops_the_search() -> None:
    result = astar(CounterTask(), max_expansions=50, record=10)
    assert result.outcome == "expansion_limit" and result.expanded == 50 and len(result.closed) == 10
    assert result.size == sum(1 + k for k in range(51))  # quadratic in the expansions


def test_the_size_bound_stops_a_growing_search_long_before_the_expansion_bound() -> None:
    result = astar(CounterTask(), max_expansions=20_000, max_size=5_000)
    assert result.outcome == "size_limit"
    assert result.size > 5_000 and result.size - 5_000 <= result.expanded + 1  # stopped at the first excess
    assert result.expanded < 100  # sum(1..k) > 5000 at k ~ 100, not 20,000 expansions


GROWING_GRAMMAR = "rule grow { lhs { r:room } rhs { r:room  b:box  b->r(in) } }"
UNREACHABLE = "target { r:room  b:box  b->r(in)  b->b(shiny) }"  # no rule makes anything shiny


def test_a_node_creating_rule_with_an_unreachable_target_hits_the_memory_bound() -> None:
    """Regression: each state holds one more node than its parent, so the states kept grew with
    the square of the expansions (a one-rule grammar reached 3.8 GB at 20,000 expansions)."""
    grammar = parse_grammar(GROWING_GRAMMAR, "grow.aggl")
    target = parse_target(UNREACHABLE, "t.aggt")
    world = graph_from_mapping({"hall": {"type": "room"}}, [])
    result = Planner(grammar, world).plan(target, max_state_size=20_000)
    assert isinstance(result, NoPlan)
    assert "20,000 facts" in result.reason and "memory bound" in result.reason
    assert "rules grow create nodes" in result.reason and "docs/limits.md" in result.reason
    # each state keeps one more node and link than its parent: sum(2k + 1) > 20,000 at k = 141
    assert result.expanded == 141 and result.diagnosis is None
