"""Admissible heuristics for the symbolic planner, derived from the grammar itself.

Why derive instead of hand-code: users write their own rules; a heuristic that silently
overestimates would make the planner return a costlier plan than the best one. So the "rooms to
go" heuristic below is only used when an analysis of every rule proves it a lower bound:

- the only way a rule changes where a mover is (its location link, ``in``) is a *unit move*: the
  LHS has ``x->r1(in)`` and a positive adjacency link between ``r1`` and ``r2`` (``connected``,
  directed or ``--``), the RHS replaces ``x->r1(in)`` with ``x->r2(in)``;
- no rule adds or removes adjacency links, no effect formula touches location or adjacency links,
  no rule creates or retypes nodes through effects.

Then each unit move crosses one adjacency edge of the *initial* world (deleting nodes can only
remove edges), so ``hops(room of mover, goal room) * cheapest unit move`` never overestimates.
The goal room comes from the target: ``M->R(in)`` with ``R`` a constant, or ``R`` the room of a
constant node ``X`` (``X->R(in)``) that no rule can move. Otherwise no heuristic (h = 0).
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable, Iterable
from dataclasses import dataclass

from grammar.matcher import Matcher
from grammar.model import (
    FCreate,
    FLink,
    Formula,
    FRetype,
    Pattern,
    PatternLink,
    PatternNode,
    Rule,
    Target,
    effect_atoms,
)
from grammar.world import State

Heuristic = Callable[[State], float]

LOCATION_LABEL = "in"


def zero_heuristic(state: State) -> float:
    """Uniform-cost search (Dijkstra); always admissible."""
    return 0.0


@dataclass(frozen=True)
class _UnitMove:
    mover_var_type: str
    adjacency: str
    direction: str  # "fwd" (r1->r2), "bwd" (r2->r1) or "both"
    cost: float


def _unit_moves(rules: Iterable[Rule]) -> list[_UnitMove] | None:
    """The rules' unit moves, or None when the heuristic cannot be proved admissible: no rule
    moves, a rule edits nodes or moves otherwise, or an effect touches locations or adjacency."""
    moves: list[_UnitMove] = []
    adjacency_touched: set[str] = set()
    effect_labels: set[str] = set()
    for rule in rules:
        labels, edits = _formula_labels(rule.effect)
        if edits:
            return None
        effect_labels |= labels
        adjacency_touched |= {l.label for l in (*rule.added_links, *rule.removed_links)}
        move = _unit_move(rule, LOCATION_LABEL)
        if move is False:
            return None
        if isinstance(move, _UnitMove):
            moves.append(move)
    if not moves:
        return None
    adjacency = {m.adjacency for m in moves}
    if LOCATION_LABEL in effect_labels or adjacency & effect_labels or adjacency & adjacency_touched:
        return None
    return moves


def _goal_rooms(pattern: Pattern, link: PatternLink, room_node: PatternNode, state: State,
                movable: Callable[[int], bool]) -> set[int]:
    """The rooms the target's location ``link`` asks for: a named room, or the room of a named
    thing that does not move (``o->r(in)`` with ``o`` a constant object)."""
    if room_node.constant is not None:
        found = state.node_by_constant(room_node.constant)
        return {found} if found is not None else set()
    for anchor in pattern.links:
        if anchor is link or anchor.negated or anchor.label != LOCATION_LABEL or anchor.dst != room_node.name:
            continue
        thing = pattern.node(anchor.src)
        if thing is None or thing.constant is None:
            continue
        found = state.node_by_constant(thing.constant)
        if found is None or movable(found):
            continue
        return set(state.out(found, LOCATION_LABEL))
    return set()


def _formula_labels(formula: Formula | None) -> tuple[set[str], bool]:
    """Link labels an effect formula touches (outside when-conditions) and whether it edits nodes."""
    labels: set[str] = set()
    edits = False
    for atom in effect_atoms(formula):
        match atom:
            case FLink():
                labels.add(atom.label)
            case FCreate() | FRetype():
                edits = True
    return labels, edits


def _unit_move(rule: Rule, label: str) -> _UnitMove | None | bool:
    """A unit move, ``None`` if the rule does not change locations, ``False`` if it does otherwise."""
    added = [l for l in rule.added_links if l.label == label]
    removed = [l for l in rule.removed_links if l.label == label]
    if not added and not removed:
        return None
    if len(added) != 1 or len(removed) != 1 or added[0].src != removed[0].src:
        return False if added else None  # removing a location only makes h smaller: harmless
    mover, r1, r2 = added[0].src, removed[0].dst, added[0].dst
    if rule.lhs.node(mover) is None or rule.lhs.node(r2) is None:
        return False
    for link in rule.lhs.links:
        if link.negated:
            continue
        ends = (link.src, link.dst)
        if ends == (r1, r2) or (link.undirected and ends == (r2, r1)):
            direction = "both" if link.undirected else "fwd"
        elif ends == (r2, r1):
            direction = "bwd"
        else:
            continue
        return _UnitMove(rule.lhs.by_name[mover].type, link.label, direction, rule.cost)
    return False


class RoomDistanceHeuristic:
    """h(state) = cheapest unit-move cost x fewest adjacency hops from the mover's room to the goal."""

    def __init__(self, matcher: Matcher, movers: list[int], goal_rooms: set[int], adjacency: set[str],
                 undirected: bool, forward: bool, move_cost: float) -> None:
        self.movers = movers
        self.move_cost = move_cost
        self.goal_rooms = goal_rooms
        world = matcher.world
        self.distance: dict[int, int] = {}
        queue: deque[int] = deque()
        for room in sorted(goal_rooms):
            self.distance[room] = 0
            queue.append(room)
        while queue:  # BFS backwards from the goal rooms
            room = queue.popleft()
            nexts: list[int] = []
            for label in adjacency:
                if undirected or forward:  # a move r1->r2 uses r1->r2: predecessors are sources
                    nexts.extend(world.inn.get((room, label), ()))
                if undirected or not forward:
                    nexts.extend(world.out.get((room, label), ()))
            for other in nexts:
                if other not in self.distance:
                    self.distance[other] = self.distance[room] + 1
                    queue.append(other)

    def __call__(self, state: State) -> float:
        best = math.inf
        for mover in self.movers:
            if not state.exists(mover):
                continue
            rooms = list(state.out(mover, LOCATION_LABEL))
            if not rooms:
                return 0.0
            for room in rooms:
                best = min(best, self.distance.get(room, math.inf))
        if best == math.inf:
            return math.inf
        return best * self.move_cost

    @classmethod
    def derive(cls, rules: Iterable[Rule], target: Target, matcher: Matcher, state: State
               ) -> RoomDistanceHeuristic | None:
        moves = _unit_moves(rules)
        if moves is None:
            return None
        directions = {m.direction for m in moves}
        undirected = "both" in directions or directions == {"fwd", "bwd"}
        forward = directions == {"fwd"}
        move_cost = min(m.cost for m in moves)
        adjacency = {m.adjacency for m in moves}

        def movable(node: int) -> bool:
            return any(matcher.type_ok(state.type_of(node), m.mover_var_type) for m in moves)

        pattern = target.pattern
        for link in pattern.links:
            if link.negated or link.undirected or link.label != LOCATION_LABEL:
                continue
            mover_node = pattern.node(link.src)
            room_node = pattern.node(link.dst)
            if mover_node is None or room_node is None:
                continue
            if mover_node.constant is not None:
                found = state.node_by_constant(mover_node.constant)
                movers = [found] if found is not None and movable(found) else []
            else:
                movers = [n for n in matcher.candidates_of_type(state, mover_node.type) if movable(n)]
            if not movers:
                continue
            goal_rooms = _goal_rooms(pattern, link, room_node, state, movable)
            if goal_rooms:
                return cls(matcher, movers, goal_rooms, adjacency, undirected, forward, move_cost)
        return None
