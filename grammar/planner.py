"""Lowest-cost sequence of rule applications that makes a target pattern match (A*).

Why A* over whole world states: rules are data (grammar files), so the planner cannot know a
domain's structure; it searches states of the symbolic graph, each a small overlay of the initial
world (see world.py), with an admissible heuristic derived from the grammar when one can be proved
(see heuristics.py) and uniform cost otherwise. The first plan popped is therefore a cheapest one.

Determinism: candidates are enumerated in world insertion order, rules in file order, and the
queue breaks ties on (f, h, insertion counter): the same world, grammar and target always give
the same plan, in any process.

Which rules are used: active rules (passive ones model changes of the world that the robot does
not cause; pass ``include_passive=True`` to use them too), dormant rules only after a rule that
activates them, and hierarchical rules as AGM uses them (``agglplanner2.py``): a hierarchical rule
is an ordinary action of the search (its LHS => RHS rewrite, at its cost); once a plan is found,
each hierarchical step is *expanded* by planning, from the state before it, the step's right-hand
side as a sub-target (its left-hand nodes fixed to the step's bindings), without that rule
(nor the rules being expanded around it). AGM expands the first step (its executive re-plans after
every step, so a later step is expanded when it comes first): if the first step cannot be
expanded there is no plan; a later step that cannot be expanded yet keeps ``expansion_error``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field, replace
from typing import TypeGuard, cast

import networkx as nx

from grammar.canonical import canonical_key
from grammar.diagnosis import MAX_STATES, Diagnosis, explain, type_problem
from grammar.errors import PlanningError
from grammar.formulas import FormulaEvaluator
from grammar.heuristics import Heuristic, RoomDistanceHeuristic, zero_heuristic
from grammar.matcher import Bindings, CompiledPattern, MatchBudgetExceeded, Matcher, Reader
from grammar.model import FCreate, Grammar, Pattern, PatternNode, Rule, Target, effect_atoms
from grammar.relevance import condition_reads, drop_useless_removers, relevant_rules
from grammar.rewrite import apply_rule
from grammar.search import SearchResult, astar
from grammar.world import State, World

DEFAULT_MAX_EXPANSIONS = 20_000
# Candidate nodes matching may try per allowed expansion (docs/limits.md). Measured: 30-50 per
# expansion on the shipped grammar (bench_planner_symbolic, 10-200 rooms), so 250 leaves a 5x
# margin; the floor lets the first expansions of a small bound match a large world.
MATCH_TRIES_PER_EXPANSION = 250
MIN_MATCH_BUDGET = 100_000
MAX_STATE_SIZE = 1_000_000
AGM_MAX_WORLD_INCREMENT = 5
"""AGM's planner (``agglplanner2.py``, ``maxWorldIncrement``) never searches a world with more than
5 symbols beyond the start: with rules that create symbols each time they apply, that is what
makes its search space finite. ``plan_growing`` starts there."""
GROWTH_STEPS: tuple[int | None, ...] = (AGM_MAX_WORLD_INCREMENT, 10, None)
"""Bound on the facts (a state's links, nodes and attributes that differ from the world, plus one
per state) that one search keeps: about 250 MB (measured: 242 MB peak for the whole process).
Without it a rule that creates a node every time it applies made the kept states grow with the
square of the expansions (3.8 GB at the default 20,000). For scale, the object mission on 200 rooms
(tools/bench/bench_planner_symbolic.py) keeps 2,660 facts, about 6 per expansion."""


@dataclass(frozen=True)
class PlanStep:
    """One rule application; ``bindings`` maps each rule variable to a world node name
    (created nodes get a fresh name ``var#id``). ``agm_bindings`` maps them to world graph keys
    (AGM symbol ids; created nodes get the ids AGM's planner gives them, see ``_AgmIds``). A
    hierarchical step carries its ``expansion`` (the sub-plan that realises it) or, when none
    was found, ``expansion_error``."""

    rule: str
    bindings: Mapping[str, str]
    cost: float
    hierarchical: bool = False
    expansion: Plan | None = field(default=None, compare=False, repr=False)
    expansion_error: str | None = field(default=None, compare=False)
    agm_bindings: Mapping[str, str] = field(default_factory=dict, compare=False, repr=False)
    state_after: State | None = field(default=None, compare=False, repr=False)  # the world after this step

    def __str__(self) -> str:
        args = ", ".join(f"{var}={name}" for var, name in self.bindings.items())
        return f"{self.rule}({args})"

    def agm_line(self) -> str:
        """The step as a line of an AGM plan file: ``[*]rule@{'var': 'id', ...}``."""
        return f"{'*' if self.hierarchical else ''}{self.rule}@{dict(self.agm_bindings or self.bindings)!r}"


@dataclass(frozen=True)
class Plan:
    steps: tuple[PlanStep, ...]
    cost: float
    expanded: int
    generated: int
    target_bindings: Mapping[str, str]
    final_state: State | None = field(default=None, compare=False, repr=False)
    created_ids: Mapping[int, str] = field(default_factory=dict, compare=False, repr=False)  # AGM ids given
    found: bool = field(default=True, init=False)

    def agm_lines(self) -> list[str]:
        """The plan as AGM's planner writes it: a first hierarchical step is replaced by its
        expansion followed by ``#!*rule@{...}`` (AGM's mark of a decomposed step); later steps
        are written as they are (AGM expands them when they become the first step)."""
        lines: list[str] = []
        for i, step in enumerate(self.steps):
            if i == 0 and step.hierarchical and step.expansion is not None:
                lines.extend(step.expansion.agm_lines())
                lines.append("#!" + step.agm_line())
            else:
                lines.append(step.agm_line())
        return lines

    def flat_steps(self) -> list[PlanStep]:
        """The steps to execute: every hierarchical step replaced by its expansion (recursively)."""
        out: list[PlanStep] = []
        for step in self.steps:
            if step.hierarchical and step.expansion is not None:
                out.extend(step.expansion.flat_steps())
            else:
                out.append(step)
        return out


@dataclass(frozen=True)
class NoPlan:
    """No plan: ``reason`` says why (target unreachable, expansion limit, unknown names...);
    ``diagnosis`` (when the search ran out of states) names the rules whose conditions block
    the target and the facts that block them (grammar/diagnosis.py)."""

    reason: str
    expanded: int = 0
    generated: int = 0
    diagnosis: Diagnosis | None = field(default=None, compare=False)
    found: bool = field(default=False, init=False)


PlanResult = Plan | NoPlan


@dataclass
class _Compiled:
    rule: Rule
    lhs: CompiledPattern
    reader: Reader  # what decides its matches (relevance.condition_reads)


def state_size(state: State) -> int:
    """The facts a search state holds beyond the world it overlays (plus one for the state): what
    its memory grows with (its overlay and the indexes built on it)."""
    ov = state.overlay
    return (1 + len(ov.added) + len(ov.removed) + len(ov.created) + len(ov.deleted) + len(ov.retyped)
            + len(ov.attrs) + len(ov.activated))


def node_count(state: State) -> int:
    """How many symbols the state's world holds (AGM's ``len(graph.nodes)``)."""
    ov = state.overlay
    return state.world.size - len(ov.deleted) + len(ov.created)


class _PlanTask:
    """The planning problem as search.py sees it: states of the symbolic graph, one action per
    (rule, bindings) application, the target's match as the goal's witness."""

    def __init__(self, planner: Planner, target: Target, rules: list[_Compiled], start: State,
                 max_new_symbols: int | None = None) -> None:
        self.planner, self.target, self.rules, self.start = planner, target, rules, start
        self.goal_pattern = planner.matcher.compile(target.pattern)
        self.max_nodes = None if max_new_symbols is None else node_count(start) + max_new_symbols
        self.over_growth = 0  # successors left out by the bound

    def initial(self) -> State:
        return self.start

    def goal(self, state: State) -> Bindings | None:
        return self.planner.target_match(self.target, self.goal_pattern, state)

    def successors(self, state: State) -> Iterator[tuple[tuple[Rule, Bindings], State, float]]:
        for rule, b, nxt in self.planner.applications(state, self.rules):
            if self.max_nodes is not None and node_count(nxt) > self.max_nodes and self.goal(nxt) is None:
                self.over_growth += 1
                continue
            yield (rule, b), nxt, rule.cost

    size = staticmethod(state_size)


def _size_limit_reason(limit: int, expanded: int, rules: list[Rule],
                       kept: tuple[tuple[tuple[Rule, Bindings], int], ...] = ()) -> str:
    """Why a search that filled its memory bound stopped, in the grammar's words: which rules
    produced the worlds it kept (states and facts per rule, largest first)."""
    growing = [r.name for r in rules if r.created_nodes or any(isinstance(a, FCreate) for a in effect_atoms(r.effect))]
    why = (f"rules {', '.join(growing[:5])} create nodes each time they apply, so the world keeps growing"
           if growing else "the rules keep producing new, larger worlds")
    filled = ""
    if kept:
        per_rule: dict[str, list[int]] = {}
        for (rule, _), facts in kept:
            counts = per_rule.setdefault(rule.name, [0, 0])
            counts[0] += 1
            counts[1] += facts
        ranked = sorted(per_rule.items(), key=lambda kv: (-kv[1][1], kv[0]))
        filled = "; the kept worlds were made by " + ", ".join(
            f"{name} ({states:,} worlds, {facts:,} facts)" for name, (states, facts) in ranked[:8])
    return (f"the search stopped after {expanded} expansions: the worlds it had to remember reached "
            f"{limit:,} facts (the memory bound, docs/limits.md) before the target matched{filled}; {why} "
            f"and the target is probably unreachable: check the target and those rules")


class Planner:
    """Plans on one world with one grammar; reuse it to plan several targets on the same world.
    ``exclude`` names rules not to use (the hierarchical rules being expanded)."""

    def __init__(self, grammar: Grammar, world: nx.MultiDiGraph | World, *,
                 include_passive: bool = False, exclude: frozenset[str] = frozenset(),
                 max_new_symbols: int | None = None) -> None:
        self.grammar = grammar
        # AGM's maxWorldIncrement: worlds with more symbols than the start + this are not searched
        self.max_new_symbols = max_new_symbols
        self.world = world if isinstance(world, World) else World(world)
        self.matcher = Matcher(grammar.types, self.world)
        self.formulas = FormulaEvaluator(self.matcher)
        self.include_passive = include_passive
        self.exclude = frozenset(exclude)
        self.rules: list[_Compiled] = []
        for rule in grammar.rules:
            if rule.name in self.exclude or (not rule.active and not include_passive):
                continue
            lhs = rule.lhs
            extra = tuple(PatternNode(p.name, p.type, pos=p.pos) for p in rule.parameters
                          if lhs.node(p.name) is None)
            if extra:
                lhs = Pattern(lhs.nodes + extra, lhs.links)
            reader = Reader(*condition_reads(rule), self.matcher.type_ok)
            self.rules.append(_Compiled(rule, self.matcher.compile(lhs), reader))
        # matches that pass every condition, by (rule, what the rule can see of the state): states
        # that differ only in links and attributes a rule does not read share its matches
        self._matches: dict[tuple[str, tuple[object, ...]], list[Bindings]] = {}

    # ------------------------------------------------------------------ pieces used by the search
    def applications(self, state: State, rules: list[_Compiled] | None = None
                     ) -> list[tuple[Rule, Bindings, State]]:
        """Every (rule, LHS bindings, next state) applicable in ``state``, in deterministic order."""
        out: list[tuple[Rule, Bindings, State]] = []
        for compiled in self.rules if rules is None else rules:
            rule = compiled.rule
            if rule.dormant and rule.name not in state.overlay.activated:
                continue
            for b in self.applicable(compiled, state):
                application = apply_rule(rule, state, b, self.matcher, self.formulas)
                out.append((rule, application.bindings, application.state))
        return out

    def applicable(self, compiled: _Compiled, state: State) -> list[Bindings]:
        """The left-hand side matches of a rule that pass its conditions (cached, see __init__)."""
        key = (compiled.rule.name, compiled.reader.view(state))
        found = self._matches.get(key)
        if found is not None:
            return found
        rule = compiled.rule
        found = []
        for b in self.matcher.matches(compiled.lhs, state):
            if rule.where and not all(self.matcher.truth(c, state, b) for c in rule.where):
                continue
            if rule.precondition is not None and not self.formulas.holds(rule.precondition, state, b):
                continue
            found.append(b)
        self._matches[key] = found
        return found

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
             heuristic: str | Callable[[State], float] = "auto", prune: bool = True,
             start: State | None = None, expand: bool = True, diagnose: bool = True,
             max_state_size: int = MAX_STATE_SIZE, created_ids: Mapping[int, str] | None = None) -> PlanResult:
        """A* (search.py) from the world (or from ``start``) to ``target``. ``prune`` drops rules
        irrelevant to the target (relevance.py: same reachability and optimal cost, far fewer
        states); ``expand`` expands hierarchical steps; ``diagnose`` explains an exhausted search
        (diagnosis.py); ``max_state_size`` bounds the facts the search keeps (docs/limits.md);
        ``created_ids`` gives the AGM ids of symbols that ``start`` holds but the world does not
        (created by steps already run: grammar/executive.py)."""
        if max_expansions < 1:
            raise PlanningError(f"max_expansions must be >= 1, got {max_expansions}")
        # The expansion bound also bounds matching, which can be exponential within one expansion.
        budget = max(MIN_MATCH_BUDGET, max_expansions * MATCH_TRIES_PER_EXPANSION)
        self.matcher.budget = budget
        try:
            return self._plan(target, max_expansions, heuristic, prune, start, expand, diagnose, max_state_size,
                              dict(created_ids or {}))
        except MatchBudgetExceeded:
            return NoPlan(f"expansion limit of {max_expansions} reached while matching patterns ({budget:,} candidate "
                          "nodes tried, the bound that limit sets on matching); the target or a rule matches the "
                          "world in too many ways")
        finally:
            self.matcher.budget = None

    def _plan(self, target: Target, max_expansions: int, heuristic: str | Callable[[State], float], prune: bool,
              start: State | None, expand: bool, diagnose: bool, max_state_size: int,
              created_ids: dict[int, str]) -> PlanResult:
        start = start if start is not None else self.world.initial_state()
        missing = self._missing_constants(target, start)
        if missing:
            return NoPlan(f"the target names nodes that are not in the world: {', '.join(missing)}")
        problem = type_problem(self, target, start)
        if problem is not None:
            return NoPlan(problem.summary, diagnosis=problem)
        rules = self._relevant(target) if prune else self.rules
        h = self._heuristic(heuristic, target, start, rules)
        if h(start) == math.inf:
            return NoPlan("the target is unreachable: no chain of adjacency links leads the robot "
                          "to the room the target needs")
        task = _PlanTask(self, target, rules, start, self.max_new_symbols)
        result = astar(task, h, max_expansions=max_expansions, max_size=max_state_size,
                       record=MAX_STATES if diagnose else 0, key=canonical_key)
        expanded, generated = result.expanded, result.generated
        if result.found:
            return self._reconstruct(result, target, expand, created_ids)
        if result.outcome == "expansion_limit":
            return NoPlan(f"expansion limit of {max_expansions} reached before the target matched",
                          expanded, generated)
        if result.outcome == "size_limit":
            return NoPlan(_size_limit_reason(max_state_size, expanded, [c.rule for c in rules], result.kept),
                          expanded, generated)
        reason = f"no sequence of rules reaches the target (all {expanded} reachable states searched)"
        diagnosis = explain(self, target, list(result.closed), [c.rule for c in rules]) if diagnose else None
        if diagnosis is not None and diagnosis.blockers:
            reason += f"; blocked: {diagnosis.blockers[0]}"
        return NoPlan(reason, expanded, generated, diagnosis)

    def _relevant(self, target: Target) -> list[_Compiled]:
        """The rules that can matter for ``target`` (relevance.py), in file order."""
        relevant = relevant_rules([c.rule for c in self.rules], target, self.grammar.types)
        keep = {rule.name for rule in drop_useless_removers(relevant, target, self.grammar.types)}
        return [c for c in self.rules if c.rule.name in keep]

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

    def _reconstruct(self, result: SearchResult[State, tuple[Rule, Bindings]], target: Target,
                     expand: bool, created_ids: Mapping[int, str]) -> PlanResult:
        expanded, generated = result.expanded, result.generated
        final = cast(State, result.goal)  # set when the search found the target
        match = cast(Bindings, result.witness)  # what _PlanTask.goal returns
        ids = _AgmIds(self.world, created_ids)
        steps: list[PlanStep] = []
        for index, found in enumerate(result.path):
            before, (rule, b), after = found.before, found.action, found.after
            names = {var: (before.name_of(n) if before.exists(n) else after.name_of(n)) for var, n in b.items()}
            agm = ids.step(rule, b, before, after)
            step = PlanStep(rule.name, names, rule.cost, hierarchical=rule.hierarchical, agm_bindings=agm,
                            state_after=after)
            if rule.hierarchical and expand:
                sub = self._expand(rule, b, before, {n: i for n, i in ids.created.items() if before.exists(n)})
                if isinstance(sub, NoPlan):
                    if index == 0:  # AGM: the first step must be expandable, or there is no plan
                        return NoPlan(f"the plan starts with hierarchical step {step} but its expansion "
                                      f"failed: {sub.reason}", expanded, generated, sub.diagnosis)
                    step = replace(step, expansion_error=sub.reason)
                else:
                    step = replace(step, expansion=sub)
            steps.append(step)
        target_names = {var: final.name_of(n) for var, n in match.items()}
        return Plan(tuple(steps), result.cost, expanded, generated, target_names, final, dict(ids.created))

    def _expand(self, rule: Rule, bindings: Bindings, before: State, created_ids: Mapping[int, str]) -> PlanResult:
        """Plan the right-hand side of hierarchical ``rule`` from ``before``, its left-hand nodes
        fixed to ``bindings``, without the rules being expanded (AGM's ``excludeList``)."""
        nodes = []
        for node in rule.rhs.nodes:
            if rule.lhs.node(node.name) is not None and node.name in bindings:
                nodes.append(PatternNode(node.name, node.type, constant=before.name_of(bindings[node.name]),
                                         pos=node.pos))
            else:
                nodes.append(PatternNode(node.name, node.type, pos=node.pos))
        target = Target(Pattern(tuple(nodes), rule.rhs.links), file=f"<expansion of {rule.name}>")
        sub = Planner(self.grammar, self.world, include_passive=self.include_passive,
                      exclude=self.exclude | {rule.name}, max_new_symbols=self.max_new_symbols)
        return sub.plan(target, start=before, created_ids=created_ids)


class _AgmIds:
    """AGM symbol ids for plan files, as AGM's planner assigns them (``getNewIdForSymbol``): a
    world node keeps its graph key; the nodes one step creates get the largest integer id in
    the graph + 1, + 2, ... in the order AGM creates them: first the rule's right-hand-side
    nodes in AGM's order (``Rule.agm_creation_order``, grammar/agm_order.py), then, after the
    rule's deletions, the nodes its ``effect`` creates. The largest id is that of the graph the
    step applies to (a deleted node's id may be given again, as AGM does)."""

    def __init__(self, world: World, prior: Mapping[int, str] | None = None) -> None:
        self.world = world
        self.created: dict[int, str] = dict(prior or {})  # created node -> its AGM id
        # integer world keys, largest first: the largest id of a state is the first that exists
        self.world_ids = sorted(((int(k), i) for i, k in enumerate(world.keys) if _is_int(k)), reverse=True)

    def _largest(self, state: State, gone: frozenset[int] | set[int], extra: Mapping[int, str]) -> int:
        top = 0
        for value, node in self.world_ids:
            if state.exists(node) and node not in gone:
                top = value
                break
        for node, agm_id in extra.items():
            if node not in gone and int(agm_id) > top:
                top = int(agm_id)
        return top

    def _of(self, node: int) -> str:
        if node < self.world.size:
            return str(self.world.keys[node])
        return self.created.get(node, str(node))

    def step(self, rule: Rule, b: Bindings, before: State, after: State) -> dict[str, str]:
        """The AGM ids of one step's bindings (numbering the nodes it creates)."""
        new = {n for n in b.values() if not before.exists(n)}
        new.update(n for n, _, _ in after.overlay.created if not before.exists(n))
        if new:
            live = {n: i for n, i in self.created.items() if before.exists(n)}
            top = self._largest(before, frozenset(), live)
            ordered = [b[name] for name in rule.agm_creation_order if name in b and b[name] in new]
            for node in ordered:
                top = max(top, 0) + 1
                live[node] = self.created[node] = str(top)
            rest = sorted(new - set(ordered))
            if rest:  # effect creations come after the rule's deletions
                gone = {b[name] for name in rule.deleted_nodes if name in b}
                top = self._largest(before, gone, live)
                for node in rest:
                    top = max(top, 0) + 1
                    live[node] = self.created[node] = str(top)
        return {var: self._of(n) for var, n in b.items()}


def _is_int(key: object) -> TypeGuard[int | str]:
    return isinstance(key, int) and not isinstance(key, bool) or (isinstance(key, str) and key.isdigit())


def plan(grammar: Grammar, world: nx.MultiDiGraph | World, target: Target, *,
         max_expansions: int = DEFAULT_MAX_EXPANSIONS, heuristic: str | Callable[[State], float] = "auto",
         include_passive: bool = False, prune: bool = True) -> PlanResult:
    """Cheapest plan from ``world`` to ``target`` with ``grammar``'s rules, or ``NoPlan``."""
    planner = Planner(grammar, world, include_passive=include_passive)
    return planner.plan(target, max_expansions=max_expansions, heuristic=heuristic, prune=prune)


def plan_growing(grammar: Grammar, world: nx.MultiDiGraph | World, target: Target, *,
                 max_expansions: int = DEFAULT_MAX_EXPANSIONS,
                 steps: tuple[int | None, ...] = GROWTH_STEPS, start: State | None = None,
                 created_ids: Mapping[int, str] | None = None) -> tuple[PlanResult, int | None]:
    """Plan as AGM does with node-creating rules: first among worlds at most
    ``AGM_MAX_WORLD_INCREMENT`` symbols larger than the start (AGM's bound), then, if that finds no
    plan, with the larger bounds of ``steps`` (``None``: unbounded). Returns the result and the bound
    it was found with; the plan is a cheapest one among plans that stay within that bound. The
    expansions of the failed attempts are added to the result's count. A grammar whose rules create
    nothing is planned once, unbounded (the bound cannot matter)."""
    creates = any(r.created_nodes or any(isinstance(a, FCreate) for a in effect_atoms(r.effect))
                  for r in grammar.rules)
    bounds = steps if creates else (None,)
    world = world if isinstance(world, World) else World(world)
    spent_expanded = spent_generated = 0
    result: PlanResult = NoPlan("no bound tried")
    bound: int | None = None
    for bound in bounds:
        result = Planner(grammar, world, max_new_symbols=bound).plan(target, max_expansions=max_expansions,
                                                                     start=start, created_ids=created_ids)
        if result.found:
            break
        spent_expanded += result.expanded
        spent_generated += result.generated
        if not result.found and bound is not None and isinstance(result, NoPlan):
            result = replace(result, reason=f"{result.reason} (worlds at most {bound} symbols larger than the start)")
    if result.found:
        result = replace(result, expanded=result.expanded + spent_expanded,
                         generated=result.generated + spent_generated)
    return result, bound
