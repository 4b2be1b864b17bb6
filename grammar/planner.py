"""Lowest-cost sequence of rule applications that makes a target pattern match (A*).

Why A* over whole world states: rules are data (grammar files), so the planner cannot know a
domain's structure; it searches states of the symbolic graph, each a small overlay of the initial
world (see world.py), with an admissible heuristic derived from the grammar when one can be proved
(see heuristics.py) and uniform cost otherwise. The first plan popped is therefore a cheapest one.

Determinism: candidates are enumerated in world insertion order, rules in file order, and the
queue breaks ties on (f, h, insertion counter): the same world, grammar and target always give
the same plan, in any process.

Which rules are used: active rules (passive ones model changes of the world that the robot does
not cause; pass ``include_passive=True`` to use them too), not hierarchical (their right-hand side
is a sub-goal, expanded by the executive), and dormant rules only after a rule that activates them.
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Union

import networkx as nx

from grammar.errors import PlanningError
from grammar.formulas import FormulaEvaluator
from grammar.heuristics import Heuristic, RoomDistanceHeuristic, zero_heuristic
from grammar.matcher import Bindings, CompiledPattern, Matcher
from grammar.model import Grammar, Pattern, PatternNode, Rule, Target
from grammar.relevance import relevant_rules
from grammar.rewrite import apply_rule
from grammar.world import State, World

DEFAULT_MAX_EXPANSIONS = 20_000


@dataclass(frozen=True)
class PlanStep:
    """One rule application; ``bindings`` maps each rule variable to a world node name
    (created nodes get a fresh name ``var#id``)."""

    rule: str
    bindings: Mapping[str, str]
    cost: float

    def __str__(self) -> str:
        args = ", ".join(f"{var}={name}" for var, name in self.bindings.items())
        return f"{self.rule}({args})"


@dataclass(frozen=True)
class Plan:
    steps: tuple[PlanStep, ...]
    cost: float
    expanded: int
    generated: int
    target_bindings: Mapping[str, str]
    final_state: State | None = field(default=None, compare=False, repr=False)
    found: bool = field(default=True, init=False)


@dataclass(frozen=True)
class NoPlan:
    """No plan: ``reason`` says why (target unreachable, expansion limit, unknown names...)."""

    reason: str
    expanded: int = 0
    generated: int = 0
    found: bool = field(default=False, init=False)


PlanResult = Union[Plan, NoPlan]


@dataclass
class _Compiled:
    rule: Rule
    lhs: CompiledPattern


class Planner:
    """Plans on one world with one grammar; reuse it to plan several targets on the same world."""

    def __init__(self, grammar: Grammar, world: nx.MultiDiGraph | World, *,
                 include_passive: bool = False) -> None:
        self.grammar = grammar
        self.world = world if isinstance(world, World) else World(world)
        self.matcher = Matcher(grammar.types, self.world)
        self.formulas = FormulaEvaluator(self.matcher)
        self.rules: list[_Compiled] = []
        for rule in grammar.rules:
            if rule.hierarchical or (not rule.active and not include_passive):
                continue
            lhs = rule.lhs
            extra = tuple(PatternNode(p.name, p.type, pos=p.pos) for p in rule.parameters
                          if lhs.node(p.name) is None)
            if extra:
                lhs = Pattern(lhs.nodes + extra, lhs.links)
            self.rules.append(_Compiled(rule, self.matcher.compile(lhs)))

    # ------------------------------------------------------------------ pieces used by the search
    def applications(self, state: State, rules: list[_Compiled] | None = None
                     ) -> list[tuple[Rule, Bindings, State]]:
        """Every (rule, LHS bindings, next state) applicable in ``state``, in deterministic order."""
        out: list[tuple[Rule, Bindings, State]] = []
        for compiled in self.rules if rules is None else rules:
            rule = compiled.rule
            if rule.dormant and rule.name not in state.overlay.activated:
                continue
            for b in self.matcher.matches(compiled.lhs, state):
                if rule.where and not all(self.matcher.truth(c, state, b) for c in rule.where):
                    continue
                if rule.precondition is not None and not self.formulas.holds(rule.precondition, state, b):
                    continue
                application = apply_rule(rule, state, b, self.matcher, self.formulas)
                out.append((rule, application.bindings, application.state))
        return out

    def target_match(self, target: Target, compiled: CompiledPattern, state: State) -> Bindings | None:
        for b in self.matcher.matches(compiled, state):
            if target.where and not all(self.matcher.truth(c, state, b) for c in target.where):
                continue
            if target.precondition is not None and not self.formulas.holds(target.precondition, state, b):
                continue
            return b
        return None

    def _missing_constants(self, target: Target, state: State) -> list[str]:
        return [n.constant for n in target.pattern.nodes
                if n.constant is not None and state.node_by_constant(n.constant) is None]

    # ------------------------------------------------------------------ search
    def plan(self, target: Target, *, max_expansions: int = DEFAULT_MAX_EXPANSIONS,
             heuristic: str | Callable[[State], float] = "auto", prune: bool = True) -> PlanResult:
        """A* from the world to ``target``. ``prune`` drops rules irrelevant to the target
        (relevance.py: same reachability and optimal cost, far fewer states)."""
        if max_expansions < 1:
            raise PlanningError(f"max_expansions must be >= 1, got {max_expansions}")
        start = self.world.initial_state()
        missing = self._missing_constants(target, start)
        if missing:
            return NoPlan(f"the target names nodes that are not in the world: {', '.join(missing)}")
        goal = self.matcher.compile(target.pattern)
        rules = self.rules
        if prune:
            keep = {rule.name for rule in relevant_rules([c.rule for c in self.rules], target)}
            rules = [c for c in self.rules if c.rule.name in keep]
        h = self._heuristic(heuristic, target, start, rules)

        h0 = h(start)
        if h0 == math.inf:
            return NoPlan("the target is unreachable: no chain of adjacency links leads the robot "
                          "to the room the target needs")
        counter = 0
        queue: list[tuple[float, float, int, State]] = [(h0, h0, counter, start)]
        best_g: dict[State, float] = {start: 0.0}
        parent: dict[State, tuple[State, Rule, Bindings]] = {}
        closed: set[State] = set()
        expanded = generated = 0
        while queue:
            f, h_value, _, state = heapq.heappop(queue)
            if state in closed:
                continue
            g = best_g[state]
            match = self.target_match(target, goal, state)
            if match is not None:
                return self._reconstruct(state, parent, g, match, expanded, generated)
            if expanded >= max_expansions:
                return NoPlan(f"expansion limit of {max_expansions} reached before the target matched",
                              expanded, generated)
            closed.add(state)
            expanded += 1
            for rule, b, nxt in self.applications(state, rules):
                generated += 1
                if nxt in closed:
                    continue
                g2 = g + rule.cost
                if g2 >= best_g.get(nxt, math.inf):
                    continue
                h2 = h(nxt)
                if h2 == math.inf:
                    continue
                best_g[nxt] = g2
                parent[nxt] = (state, rule, b)
                counter += 1
                heapq.heappush(queue, (g2 + h2, h2, counter, nxt))
        return NoPlan(f"no sequence of rules reaches the target (all {expanded} reachable states "
                      "searched)", expanded, generated)

    def _heuristic(self, heuristic: str | Callable[[State], float], target: Target, start: State,
                   rules: list[_Compiled]) -> Heuristic:
        if callable(heuristic):
            return heuristic
        if heuristic == "zero":
            return zero_heuristic
        if heuristic == "auto":
            derived = RoomDistanceHeuristic.derive([c.rule for c in rules], target, self.matcher, start)
            return derived if derived is not None else zero_heuristic
        raise PlanningError(f"unknown heuristic {heuristic!r} (use 'auto', 'zero' or a function)")

    def _reconstruct(self, state: State, parent: dict[State, tuple[State, Rule, Bindings]], cost: float,
                     match: Bindings, expanded: int, generated: int) -> Plan:
        steps: list[PlanStep] = []
        final = state
        while state in parent:
            before, rule, b = parent[state]
            names = {var: (before.name_of(n) if before.exists(n) else state.name_of(n)) for var, n in b.items()}
            steps.append(PlanStep(rule.name, names, rule.cost))
            state = before
        steps.reverse()
        target_names = {var: final.name_of(n) for var, n in match.items()}
        return Plan(tuple(steps), cost, expanded, generated, target_names, final)


def plan(grammar: Grammar, world: nx.MultiDiGraph | World, target: Target, *,
         max_expansions: int = DEFAULT_MAX_EXPANSIONS, heuristic: str | Callable[[State], float] = "auto",
         include_passive: bool = False, prune: bool = True) -> PlanResult:
    """Cheapest plan from ``world`` to ``target`` with ``grammar``'s rules, or ``NoPlan``."""
    planner = Planner(grammar, world, include_passive=include_passive)
    return planner.plan(target, max_expansions=max_expansions, heuristic=heuristic, prune=prune)
