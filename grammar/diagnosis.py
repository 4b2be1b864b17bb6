"""Why there is no plan: the rules that could reach the target and the conditions that block them,
with the facts of the world that make those conditions fail.

Why: "all 12 reachable states searched" tells a person nothing they can act on. What they need is
``goToObject(robot=robot, o=ot_table): unless { p:person  p->o(interacting) } fails:
resident_3 -interacting-> ot_table``: the rule, the condition as written in the grammar (with its
file position) and the facts (witness nodes and the attributes the condition reads).

How (only after a search ran out of states, so it costs nothing when a plan exists):
1. the parts of the target (each link, each node with conditions) that no searched state ever
   satisfied are the *unmet* goals;
2. the rules that could make an unmet goal true (they add its link, remove a link that must be
   absent, or set an attribute it reads) are its *achievers*; the rest of the target, matched in
   each searched state, ties the achiever's variables to the nodes the goal is about;
3. in each searched state, the achiever's left-hand side is matched without its conditions
   (types and positive links only), then every condition is tried in the grammar's order: the
   first that fails, explained down to the world's facts, is a *blocker*.

A diagnosis is data (``Diagnosis``, ``Blocker``, ``Witness``) so that the executive can log or
publish it; ``str()`` gives one line, ``lines()`` a few, ``to_dict()`` JSON.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, assert_never

from grammar.errors import SourcePos
from grammar.matcher import Bindings, NodeRef
from grammar.model import (
    And,
    AttrRef,
    Compare,
    Exists,
    Expr,
    FAnd,
    FCreate,
    FDelete,
    FExists,
    FForall,
    FLink,
    FNot,
    FOr,
    Formula,
    FRetype,
    FSame,
    FWhen,
    ListLit,
    Literal,
    Not,
    Or,
    Pattern,
    PatternLink,
    PatternNode,
    Rule,
    Target,
    Value,
    VarRef,
    expr_children,
    formula_children,
    effect_atoms,
)
from grammar.render import expr_text, formula_text, link_text, node_text, pattern_text, value_text
from grammar.world import State

if TYPE_CHECKING:  # the planner imports this module; only its type is needed here
    from grammar.planner import Planner

MAX_STATES = 2000       # searched states examined (the first ones expanded: closest to the start)
MAX_BLOCKERS = 6        # distinct blockers reported
MAX_MATCHES = 8         # left-hand side matches tried per rule and state
MAX_BASE_MATCHES = 4    # matches of the rest of the target per state


@dataclass(frozen=True)
class Witness:
    """A world node that makes a condition fail, with the attributes the condition reads."""

    var: str
    node: str
    type: str
    attrs: Mapping[str, Value] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        return {"var": self.var, "node": self.node, "type": self.type,
                "attrs": {k: _jsonable(v) for k, v in self.attrs.items()}}


@dataclass(frozen=True)
class Blocker:
    """One rule application that would help but cannot happen, and why."""

    rule: str
    bindings: Mapping[str, str]   # every variable bound when the condition failed (node names)
    focus: Mapping[str, str]      # the variables that tie the rule to the target (e.g. o=ot_table)
    condition: str                # the failing condition as written in the grammar
    pos: SourcePos | None
    facts: tuple[str, ...]        # what in the world makes it fail
    witnesses: tuple[Witness, ...] = ()

    def __str__(self) -> str:
        focus = ", ".join(f"{k}={v}" for k, v in (self.focus or self.bindings).items())
        where = f" ({self.pos})" if self.pos is not None else ""
        return f"{self.rule}({focus}): {self.condition}{where} fails: {'; '.join(self.facts)}"

    def to_dict(self) -> dict[str, Any]:
        return {"rule": self.rule, "bindings": dict(self.bindings), "focus": dict(self.focus),
                "condition": self.condition,
                "pos": None if self.pos is None else {"file": self.pos.file, "line": self.pos.line,
                                                      "column": self.pos.column},
                "facts": list(self.facts), "witnesses": [w.to_dict() for w in self.witnesses]}


@dataclass(frozen=True)
class Diagnosis:
    """Why no plan exists: a summary, the target parts never reached, and the blockers."""

    summary: str
    unmet: tuple[str, ...] = ()
    blockers: tuple[Blocker, ...] = ()
    notes: tuple[str, ...] = ()

    def __str__(self) -> str:
        if self.blockers:
            return f"{self.summary}: {self.blockers[0]}"
        return self.summary

    def lines(self) -> list[str]:
        out = [self.summary]
        out += [f"never reached: {u}" for u in self.unmet]
        out += [f"blocked: {b}" for b in self.blockers]
        out += list(self.notes)
        return out

    def to_dict(self) -> dict[str, Any]:
        return {"summary": self.summary, "unmet": list(self.unmet),
                "blockers": [b.to_dict() for b in self.blockers], "notes": list(self.notes)}


def _jsonable(value: Value) -> Any:
    return list(value) if isinstance(value, tuple) else value


# ----------------------------------------------------------------------------- target types
def type_problem(planner: Planner, target: Target, start: State) -> Diagnosis | None:
    """A target that can never match because of types: a constant whose world node has another
    type, or a node type the world does not have, when no rule creates or retypes nodes."""
    rules = [c.rule for c in planner.rules]
    if any(r.created_nodes or r.retyped_nodes or any(isinstance(a, (FCreate, FRetype)) for a in effect_atoms(r.effect))
           for r in rules):
        return None
    matcher = planner.matcher
    world_types = sorted(planner.world.by_type)
    listed = ", ".join(world_types[:15]) + (", ..." if len(world_types) > 15 else "")
    for node in target.pattern.nodes:
        if node.constant is not None:
            found = start.node_by_constant(node.constant)
            if found is None:
                continue
            actual = start.type_of(found)
            if not matcher.type_ok(actual, node.type):
                case = " (the names differ only in case)" if actual.lower() == node.type.lower() else ""
                return Diagnosis(f"the target needs {node.constant!r} to be a {node.type!r}, but that world "
                                 f"node is a {actual!r}{case}; the world's types are: {listed}")
        elif not any(matcher.type_ok(t, node.type) for t in world_types):
            lower = [t for t in world_types if t.lower() == node.type.lower()]
            case = f" (it has {lower[0]!r}: the names differ only in case)" if lower else ""
            return Diagnosis(f"the target needs a node of type {node.type!r}, but the world has none{case}; "
                             f"the world's types are: {listed}")
    return None


# ----------------------------------------------------------------------------- explaining
@dataclass
class _Goal:
    """One part of the target: a link that must exist or be absent, or a node's conditions."""

    kind: str  # "link", "absent" or "node"
    text: str
    pattern: Pattern
    link: PatternLink | None = None
    node: PatternNode | None = None


def _goals(target: Target) -> list[_Goal]:
    pattern = target.pattern
    goals: list[_Goal] = []
    for link in pattern.links:
        ends = [pattern.by_name[n] for n in dict.fromkeys((link.src, link.dst)) if n in pattern.by_name]
        ends = [PatternNode(n.name, n.type, n.constant, pos=n.pos) for n in ends]
        goals.append(_Goal("absent" if link.negated else "link", _goal_text(link, pattern),
                           Pattern(tuple(ends), (link,)), link=link))
    for node in pattern.nodes:
        if node.conditions:
            goals.append(_Goal("node", node_text(node), Pattern((node,)), node=node))
    return goals


def _goal_text(link: PatternLink, pattern: Pattern) -> str:
    def name(var: str) -> str:
        node = pattern.node(var)
        return node.constant if node is not None and node.constant is not None else var
    arrow = "-" if link.undirected else "->"
    text = f"{name(link.src)} -{link.label}{arrow} {name(link.dst)}"
    return ("no " + text) if link.negated else text


def _relaxed(rule: Rule) -> Pattern:
    """A rule's left-hand side with types and positive links only (its parameters included)."""
    nodes = [PatternNode(n.name, n.type, n.constant, pos=n.pos) for n in rule.lhs.nodes]
    nodes += [PatternNode(p.name, p.type, pos=p.pos) for p in rule.parameters if rule.lhs.node(p.name) is None]
    links = [PatternLink(l.src, l.dst, l.label, undirected=l.undirected, pos=l.pos)
             for l in rule.lhs.links if not l.negated]
    return Pattern(tuple(nodes), tuple(links))


def _achievers(goal: _Goal, rules: Iterable[Rule]) -> list[tuple[Rule, dict[str, str]]]:
    """Rules that can make ``goal`` true, each with its variable -> target variable ties."""
    out: list[tuple[Rule, dict[str, str]]] = []
    for rule in rules:
        if goal.kind in ("link", "absent"):
            assert goal.link is not None
            link = goal.link
            changed = rule.added_links if goal.kind == "link" else rule.removed_links
            ties = [l for l in changed if l.label == link.label]
            if ties:
                tie = {ties[0].src: link.src, ties[0].dst: link.dst}
                out.append((rule, tie if len(tie) == 2 or link.src == link.dst else {}))
                continue
            adds = goal.kind == "link" and link.label in _effect_adds(rule.effect)
            if adds or (goal.kind == "absent" and _effect_removes(rule.effect, link.label)):
                out.append((rule, {}))
        else:
            assert goal.node is not None
            read = _attrs_read(goal.node.conditions)
            setters = [a for a in rule.assignments if a.attr in read]
            if setters:
                out.append((rule, {setters[0].var: goal.node.name}))
    return out


def _effect_adds(formula: Formula | None) -> set[str]:
    """Labels of the links an effect adds (link atoms not under a ``not``)."""
    out: set[str] = set()
    stack = [formula] if formula is not None else []
    while stack:
        f = stack.pop()
        match f:
            case FLink():
                out.add(f.label)
            case FAnd():
                stack.extend(f.items)
            case FForall() | FExists():
                stack.append(f.body)
            case FWhen():
                stack.append(f.then)
            case FNot() | FOr() | FSame() | FCreate() | FDelete() | FRetype():
                pass  # adds no link (a not removes one; or has no meaning in an effect)
            case _:
                assert_never(f)
    return out


def _effect_removes(formula: Formula | None, label: str) -> bool:
    stack = [formula] if formula is not None else []
    while stack:
        f = stack.pop()
        match f:
            case FNot(body=FLink() as link) if link.label == label:
                return True
            case FAnd():
                stack.extend(f.items)
            case FForall() | FExists():
                stack.append(f.body)
            case FWhen():
                stack.append(f.then)
            case FNot() | FLink() | FOr() | FSame() | FCreate() | FDelete() | FRetype():
                pass
            case _:
                assert_never(f)
    return False


def _attrs_read(exprs: Iterable[Expr]) -> set[str]:
    out: set[str] = set()
    stack = list(exprs)
    while stack:
        e = stack.pop()
        if isinstance(e, AttrRef):
            out.add(e.attr)
        stack += expr_children(e)
    return out


def _expr_pos(expr: Expr) -> SourcePos | None:
    """The first position found breadth-first (the outermost expression that knows its place)."""
    stack = [expr]
    while stack:
        e = stack.pop(0)
        pos = getattr(e, "pos", None)
        if pos is not None:
            return pos
        stack += expr_children(e)
    return None


def _formula_pos(formula: Formula) -> SourcePos | None:
    stack = [formula]
    while stack:
        f = stack.pop(0)
        pos = getattr(f, "pos", None)
        if pos is not None:
            return pos
        stack.extend(formula_children(f))
    return None


_NOTHING = "nothing matches "


class _Explainer:
    """Explains failing conditions on one state with one binding, down to the world's facts."""

    def __init__(self, planner: Planner, state: State, b: Bindings) -> None:
        self.matcher = planner.matcher
        self.formulas = planner.formulas
        self.state = state
        self.b = b
        self.witnesses: dict[tuple[str, int], set[str]] = {}

    # ------------------------------------------------------------------ facts
    def name(self, n: int) -> str:
        return self.state.name_of(n)

    def witness(self, var: str, node: int, attrs: Iterable[str] = ()) -> None:
        self.witnesses.setdefault((var, node), set()).update(a for a in attrs if a not in ("name", "type"))

    def link_fact(self, s: int, d: int, label: str) -> str:
        attrs = self.state.world.edge_attrs.get((s, d, label)) or {}
        shown = ", ".join(f"{k}={value_text(v)}" for k, v in sorted(attrs.items())[:4])
        return f"{self.name(s)} -{label}-> {self.name(d)}" + (f" [{shown}]" if shown else "")

    def operand_facts(self, expr: Expr, b: Bindings, edge: tuple[int, int, str] | None) -> list[str]:
        facts: list[str] = []
        stack = [expr]
        while stack:
            e = stack.pop(0)
            match e:
                case AttrRef(var=str(var)):
                    node = b.get(var)
                    if node is not None:
                        facts.append(f"{self.name(node)}.{e.attr} = {value_text(self.state.attr(node, e.attr))}")
                        self.witness(var, node, [e.attr])
                case AttrRef():  # the link the condition is written on
                    if edge is not None:
                        value = self.matcher.eval(e, self.state, b, edge)
                        facts.append(f"{self.link_fact(*edge)}: {e.attr} = {value_text(value)}")
                case VarRef():
                    if e.var in b:
                        self.witness(e.var, b[e.var])
                case Compare() | Not() | And() | Or() | ListLit():
                    stack.extend(expr_children(e))
                case Literal() | Exists():
                    pass
                case _:
                    assert_never(e)
        return list(dict.fromkeys(facts))

    def match_facts(self, pattern: Pattern, match: Bindings) -> list[str]:
        """The facts a match of a nested pattern consists of (its links and node attributes)."""
        facts: list[str] = []
        for link in pattern.links:
            if link.negated or link.src not in match or link.dst not in match:
                continue
            s, d = match[link.src], match[link.dst]
            if not self.state.has_edge(s, d, link.label) and link.undirected:
                s, d = d, s
            facts.append(self.link_fact(s, d, link.label))
        for node in pattern.nodes:
            if node.name not in match:
                continue
            read = _attrs_read(node.conditions)
            for attr in sorted(read):
                facts.append(f"{self.name(match[node.name])}.{attr} = "
                             f"{value_text(self.state.attr(match[node.name], attr))}")
            if node.name not in self.b:
                self.witness(node.name, match[node.name], read)
        return facts

    # ------------------------------------------------------------------ expressions
    def why_false(self, expr: Expr, b: Bindings, edge: tuple[int, int, str] | None = None) -> list[str]:
        truth = self.matcher.truth
        match expr:
            case Not():
                return self.why_true(expr.expr, b, edge)
            case And():
                for item in expr.items:
                    if not truth(item, self.state, b, edge):
                        return self.why_false(item, b, edge)
                return []
            case Or():
                facts: list[str] = []
                for item in expr.items:
                    facts += self.why_false(item, b, edge)
                concrete = [f for f in facts if not f.startswith(_NOTHING)]
                return list(dict.fromkeys(concrete or facts))
            case Exists():
                return [f"{_NOTHING}exists {{ {pattern_text(expr.pattern)} }}"]
            case Literal() | ListLit() | AttrRef() | VarRef() | Compare():
                return self.operand_facts(expr, b, edge)
            case _:
                assert_never(expr)

    def why_true(self, expr: Expr, b: Bindings, edge: tuple[int, int, str] | None = None) -> list[str]:
        truth = self.matcher.truth
        match expr:
            case Not():
                return self.why_false(expr.expr, b, edge)
            case Or():
                for item in expr.items:
                    if truth(item, self.state, b, edge):
                        return self.why_true(item, b, edge)
                return []
            case And():
                facts: list[str] = []
                for item in expr.items:
                    facts += self.why_true(item, b, edge)
                return list(dict.fromkeys(facts))
            case Exists():
                compiled = self.matcher._compile_exists(expr.pattern, b)
                found = self.matcher.first_match(compiled, self.state, b)
                return self.match_facts(expr.pattern, found) if found is not None else []
            case Literal() | ListLit() | AttrRef() | VarRef() | Compare():
                return self.operand_facts(expr, b, edge)
            case _:
                assert_never(expr)

    # ------------------------------------------------------------------ formulas
    def f_false(self, f: Formula, b: Bindings) -> list[str]:
        holds = self.formulas.holds
        match f:
            case FLink():
                s, d = b.get(f.src), b.get(f.dst)
                if s is None or d is None:
                    return [f"({f.label} {f.src} {f.dst}): a variable is unbound"]
                return [f"no link {self.name(s)} -{f.label}-> {self.name(d)}"]
            case FNot():
                return self.f_true(f.body, b)
            case FAnd():
                for item in f.items:
                    if not holds(item, self.state, b):
                        return self.f_false(item, b)
                return []
            case FOr():
                facts: list[str] = []
                for item in f.items:
                    facts += self.f_false(item, b)
                return facts
            case FWhen():
                return self.f_true(f.condition, b) + self.f_false(f.then, b)
            case FForall():
                for inner in self.formulas._assignments(f.vars, f.body, self.state, b):
                    if not holds(f.body, self.state, inner):
                        for decl in f.vars:
                            self.witness(decl.name, inner[decl.name])
                        return self.f_false(f.body, inner)
                return []
            case FExists():
                decls = " ".join(f"{v.name}:{v.type}" for v in f.vars)
                return [f"no {decls} satisfies {formula_text(f.body)}"]
            case FSame():
                return [f"{f.a} is {self._bound(f.a, b)} and {f.b} is {self._bound(f.b, b)}"]
            case FCreate() | FDelete() | FRetype():
                return [formula_text(f)]
            case _:
                assert_never(f)

    def f_true(self, f: Formula, b: Bindings) -> list[str]:
        holds = self.formulas.holds
        match f:
            case FLink():
                s, d = b.get(f.src), b.get(f.dst)
                return [self.link_fact(s, d, f.label)] if s is not None and d is not None else []
            case FNot():
                return self.f_false(f.body, b)
            case FOr():
                for item in f.items:
                    if holds(item, self.state, b):
                        return self.f_true(item, b)
                return []
            case FAnd():
                facts: list[str] = []
                for item in f.items:
                    facts += self.f_true(item, b)
                return facts
            case FExists():
                for inner in self.formulas._assignments(f.vars, f.body, self.state, b):
                    if holds(f.body, self.state, inner):
                        for decl in f.vars:
                            self.witness(decl.name, inner[decl.name])
                        return self.f_true(f.body, inner)
                return []
            case FSame():
                return [f"{f.a} and {f.b} are both {self._bound(f.a, b)}"]
            case FWhen() | FForall() | FCreate() | FDelete() | FRetype():
                return [formula_text(f)]
            case _:
                assert_never(f)

    def _bound(self, var: str, b: Bindings) -> str:
        return self.name(b[var]) if var in b else "unbound"

    def witness_list(self) -> tuple[Witness, ...]:
        out = []
        for (var, node), attrs in self.witnesses.items():
            out.append(Witness(var, self.name(node), self.state.type_of(node),
                               {a: self.state.attr(node, a) for a in sorted(attrs)}))
        return tuple(out)


def _first_failure(planner: Planner, rule: Rule, state: State, b: Bindings, focus: Mapping[str, str]
                   ) -> Blocker | None:
    """The first condition of ``rule`` (in the grammar's order) that fails at the match ``b``."""
    matcher, ex = planner.matcher, _Explainer(planner, state, b)
    names = {var: state.name_of(n) for var, n in b.items()}

    def blocker(condition: str, pos: SourcePos | None, facts: list[str]) -> Blocker:
        return Blocker(rule.name, names, dict(focus), condition, pos or rule.pos,
                       tuple(facts) or ("(no single fact: the condition as a whole is false)",),
                       ex.witness_list())

    if rule.dormant and rule.name not in state.overlay.activated:
        return blocker("dormant", rule.pos, ["no applied rule has activated it"])
    added = {(l.src, l.dst, l.label) for l in rule.added_links}
    for link in rule.lhs.links:
        s, d = b.get(link.src), b.get(link.dst)
        if s is None or d is None:
            continue
        if link.negated and (link.src, link.dst, link.label) in added and state.has_edge(s, d, link.label):
            return None  # a self-guard: what the rule would do is already done, it blocks nothing
        edges = [(s, d, link.label)] if state.has_edge(s, d, link.label) else []
        if link.undirected and state.has_edge(d, s, link.label):
            edges.append((d, s, link.label))
        if link.conditions:
            expr = link.conditions[0] if len(link.conditions) == 1 else And(link.conditions)
            good = [e for e in edges if matcher.truth(expr, state, b, e)]
            if link.negated and good:
                return blocker(link_text(link), link.pos, [ex.link_fact(*good[0])])
            if not link.negated and not good:
                facts = [f for e in edges for f in ex.why_false(expr, b, e)]
                return blocker(link_text(link), link.pos, facts)
        elif link.negated and edges:
            return blocker(link_text(link), link.pos, [ex.link_fact(*edges[0])])
    for node in rule.lhs.nodes:
        for cond in node.conditions:
            expr = _own(cond, node.name)
            if not matcher.truth(expr, state, b):
                return blocker(f"{node.name}:{node.type} [{expr_text(cond)}]", node.pos, ex.why_false(expr, b))
    for cond in rule.where:  # ('unless { P }' is 'where not exists { P }')
        if not matcher.truth(cond, state, b):
            return blocker(f"where {expr_text(cond)}", _expr_pos(cond), ex.why_false(cond, b))
    if rule.precondition is not None and not planner.formulas.holds(rule.precondition, state, b):
        return blocker(f"precondition {formula_text(rule.precondition)}", _formula_pos(rule.precondition),
                       ex.f_false(rule.precondition, b))
    return None


def _own(expr: Expr, var: str) -> Expr:
    from grammar.matcher import _own_to_var
    return _own_to_var(expr, var)


def explain(planner: Planner, target: Target, states: list[State], rules: list[Rule]) -> Diagnosis:
    """Why none of ``states`` (the searched states, in the order they were expanded) matches."""
    matcher = planner.matcher
    states = states[:MAX_STATES]
    goals = _goals(target)
    unmet: list[_Goal] = []
    for goal in goals:
        compiled = matcher.compile(goal.pattern)
        if not any(matcher.first_match(compiled, s) is not None for s in states):
            unmet.append(goal)
    count = f"{len(states)} reachable state(s) searched"
    if not unmet:
        return Diagnosis(f"every part of the target holds in some searched state, but never all at once "
                         f"({count})")
    unmet_links = {id(g.link) for g in unmet if g.link is not None}
    unmet_nodes = {g.node.name for g in unmet if g.node is not None}
    base_nodes = tuple(PatternNode(n.name, n.type, n.constant, () if n.name in unmet_nodes else n.conditions, n.pos)
                       for n in target.pattern.nodes)
    base = matcher.compile(Pattern(base_nodes, tuple(l for l in target.pattern.links if id(l) not in unmet_links)))
    relaxed = {rule.name: _relaxed(rule) for rule in rules}
    achievers = [(goal, [(r, tie) for r, tie in _achievers(goal, rules) if _tie_possible(planner, r, tie, target)])
                 for goal in unmet]
    notes = [f"no rule can make '{goal.text}' true" for goal, found in achievers if not found]

    blockers: dict[tuple[str, str, tuple[str, ...]], Blocker] = {}
    matched_rules: set[str] = set()
    _collect(planner, states, base, achievers, relaxed, blockers, matched_rules, tied=True)
    if not blockers:  # the achievers never got close to the goal: what stopped the search on its way?
        _collect(planner, states, base, achievers, relaxed, blockers, matched_rules, tied=False)
        if blockers:
            notes.append("no rule that could reach the target ever matched near it; these are the "
                         "applications that were blocked on the way")
    for goal, found in achievers:
        for rule, _tie in found:
            if rule.name not in matched_rules:
                notes.append(f"'{goal.text}': the left-hand side of {rule.name} never matched in a searched "
                             "state")
    summary = f"no plan: the target needs {', '.join(repr(g.text) for g in unmet)}, never reached ({count})"
    ordered = sorted(blockers.values(), key=lambda b: (not b.witnesses, ))[:MAX_BLOCKERS]
    return Diagnosis(summary, tuple(g.text for g in unmet), tuple(ordered), tuple(dict.fromkeys(notes)))


def _collect(planner: Planner, states: list[State], base: Any,
             achievers: list[tuple[_Goal, list[tuple[Rule, dict[str, str]]]]], relaxed: dict[str, Pattern],
             blockers: dict[tuple[str, str, tuple[str, ...]], Blocker], matched_rules: set[str], *,
             tied: bool) -> None:
    """Blockers of the achievers in ``states`` (``tied``: only applications about the target's nodes)."""
    matcher = planner.matcher
    for state in states:
        if len(blockers) >= MAX_BLOCKERS:
            return
        bases = list(_take(matcher.matches(base, state), MAX_BASE_MATCHES)) if tied else [{}]
        for _goal, found in achievers:
            for rule, tie in found:
                for base_match in (bases if tie and tied else [{}]):
                    prebound = {var: base_match[t] for var, t in tie.items() if t in base_match} if tied else {}
                    if len(set(prebound.values())) != len(prebound):
                        continue
                    compiled = matcher.compile(relaxed[rule.name], prebound)
                    for b in _take(matcher.matches(compiled, state, prebound), MAX_MATCHES):
                        matched_rules.add(rule.name)
                        focus = {var: state.name_of(n) for var, n in prebound.items()}
                        found_blocker = _first_failure(planner, rule, state, b, focus)
                        if found_blocker is not None and len(blockers) < MAX_BLOCKERS:
                            key = (found_blocker.rule, found_blocker.condition, found_blocker.facts)
                            blockers.setdefault(key, found_blocker)


def _tie_possible(planner: Planner, rule: Rule, tie: Mapping[str, str], target: Target) -> bool:
    """Can the rule's tied variables be the target's nodes at all (types compatible)?"""
    matcher = planner.matcher
    start = planner.world.initial_state()
    for var, target_var in tie.items():
        mine = rule.lhs.node(var) or rule.rhs.node(var)
        theirs = target.pattern.node(target_var)
        if mine is None or theirs is None:
            continue
        if theirs.constant is not None:
            found = start.node_by_constant(theirs.constant)
            if found is not None and not matcher.type_ok(start.type_of(found), mine.type):
                return False
        elif not (matcher.type_ok(theirs.type, mine.type) or matcher.type_ok(mine.type, theirs.type)):
            return False
    return True


def _take(iterator: Iterator[Bindings], limit: int) -> Iterator[Bindings]:
    for i, item in enumerate(iterator):
        if i >= limit:
            return
        yield item


__all__ = ["Blocker", "Diagnosis", "NodeRef", "Witness", "explain", "type_problem"]
