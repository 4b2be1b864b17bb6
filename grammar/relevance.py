"""Which rules can matter for a target: backward relevance over typed links and attributes.

Why: a mission "go to object X" does not care whether the robot faces a person on the way, yet
rules like approachPerson multiply the search states by the people of every room. A rule is
*relevant* when it changes a link or an attribute that the target reads, or that another
relevant rule reads to decide whether it applies (its LHS, ``where``, ``precondition``) or what
its relevant effects do. Irrelevant rules only change things nothing relevant ever reads, so
dropping them changes neither which targets are reachable nor the cheapest plan's cost.

Links are compared with their end types: ``robot->p(near)`` with ``p:person`` does not feed a
reader of ``robot->o(near)`` with ``o:object`` unless some type is both a person and an object
(the grammar's ``types`` section decides; an undeclared type is only itself, ``auto`` is any).

Conservative cases: a rule that creates, deletes or retypes nodes is always relevant; a rule that
activates a relevant dormant rule is relevant; a variable whose type is unknown reads or changes
links of any type.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field

from grammar.model import (
    ANY_TYPE,
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
    Not,
    Or,
    Pattern,
    Rule,
    Target,
    TypeTable,
    effect_atoms,
)

TypedLink = tuple[str, str, str]  # (label, source type, destination type)


class _Types:
    """Whether two pattern types can match one world node (some type inherits from both)."""

    def __init__(self, table: TypeTable | None) -> None:
        self.table = table or TypeTable()
        self._cache: dict[tuple[str, str], bool] = {}

    def overlap(self, a: str, b: str) -> bool:
        if a == b or a == ANY_TYPE or b == ANY_TYPE:
            return True
        key = (a, b) if a < b else (b, a)
        found = self._cache.get(key)
        if found is None:
            found = any(a in self.table.ancestors(t) and b in self.table.ancestors(t) for t in self.table.parents)
            self._cache[key] = found
        return found

    def link_overlap(self, x: TypedLink, y: TypedLink) -> bool:
        return x[0] == y[0] and self.overlap(x[1], y[1]) and self.overlap(x[2], y[2])


@dataclass
class _Reads:
    links: set[TypedLink] = field(default_factory=set)
    attrs: set[str] = field(default_factory=set)

    @property
    def labels(self) -> set[str]:
        return {link[0] for link in self.links}


def _typed(label: str, src: str, dst: str, scope: Mapping[str, str], undirected: bool = False
           ) -> list[TypedLink]:
    a, b = scope.get(src, ANY_TYPE), scope.get(dst, ANY_TYPE)
    return [(label, a, b), (label, b, a)] if undirected else [(label, a, b)]


def _pattern_scope(pattern: Pattern, scope: Mapping[str, str]) -> dict[str, str]:
    inner = dict(scope)
    inner.update({node.name: node.type for node in pattern.nodes})
    return inner


def _expr_reads(expr: Expr, out: _Reads, scope: Mapping[str, str]) -> None:
    if isinstance(expr, AttrRef):
        out.attrs.add(expr.attr)
    elif isinstance(expr, Compare):
        _expr_reads(expr.left, out, scope)
        _expr_reads(expr.right, out, scope)
    elif isinstance(expr, Not):
        _expr_reads(expr.expr, out, scope)
    elif isinstance(expr, (And, Or, ListLit)):
        for item in expr.items:
            _expr_reads(item, out, scope)
    elif isinstance(expr, Exists):
        _pattern_reads(expr.pattern, out, scope)


def _pattern_reads(pattern: Pattern, out: _Reads, scope: Mapping[str, str]) -> None:
    inner = _pattern_scope(pattern, scope)
    for node in pattern.nodes:
        for cond in node.conditions:
            _expr_reads(cond, out, inner)
    for link in pattern.links:
        out.links.update(_typed(link.label, link.src, link.dst, inner, link.undirected))
        for cond in link.conditions:
            _expr_reads(cond, out, inner)


def _formula_reads(formula: Formula | None, out: _Reads, scope: Mapping[str, str]) -> None:
    """Links read by a formula used as a condition."""
    if formula is None:
        return
    if isinstance(formula, FLink):
        out.links.update(_typed(formula.label, formula.src, formula.dst, scope))
    elif isinstance(formula, FNot):
        _formula_reads(formula.body, out, scope)
    elif isinstance(formula, (FAnd, FOr)):
        for item in formula.items:
            _formula_reads(item, out, scope)
    elif isinstance(formula, (FExists, FForall)):
        _formula_reads(formula.body, out, {**scope, **{v.name: v.type for v in formula.vars}})
    elif isinstance(formula, FWhen):
        _formula_reads(formula.condition, out, scope)
        _formula_reads(formula.then, out, scope)
    elif isinstance(formula, FSame):
        pass


def _effect_changes(formula: Formula | None, scope: Mapping[str, str]) -> set[TypedLink]:
    """Links an effect formula adds or removes (outside when-conditions)."""
    if formula is None:
        return set()
    if isinstance(formula, FLink):
        return set(_typed(formula.label, formula.src, formula.dst, scope))
    if isinstance(formula, FNot):
        return _effect_changes(formula.body, scope)
    if isinstance(formula, FAnd):
        out: set[TypedLink] = set()
        for item in formula.items:
            out |= _effect_changes(item, scope)
        return out
    if isinstance(formula, FForall):
        return _effect_changes(formula.body, {**scope, **{v.name: v.type for v in formula.vars}})
    if isinstance(formula, FWhen):
        return _effect_changes(formula.then, scope)
    return set()


def _effect_reads(formula: Formula | None, relevant: _Reads, types: _Types, out: _Reads,
                  scope: Mapping[str, str]) -> None:
    """Links read by the when-conditions of an effect whose branches change relevant links."""
    if formula is None:
        return
    if isinstance(formula, FAnd):
        for item in formula.items:
            _effect_reads(item, relevant, types, out, scope)
    elif isinstance(formula, FForall):
        _effect_reads(formula.body, relevant, types, out, {**scope, **{v.name: v.type for v in formula.vars}})
    elif isinstance(formula, FWhen):
        if _touches(_effect_changes(formula.then, scope), relevant.links, types):
            _formula_reads(formula.condition, out, scope)
        _effect_reads(formula.then, relevant, types, out, scope)


def _touches(changes: Iterable[TypedLink], reads: Iterable[TypedLink], types: _Types) -> bool:
    reads = list(reads)
    return any(types.link_overlap(c, r) for c in changes for r in reads)


def _edits_nodes(rule: Rule) -> bool:
    if rule.created_nodes or rule.deleted_nodes or rule.retyped_nodes:
        return True
    return any(isinstance(atom, (FCreate, FDelete, FRetype)) for atom in effect_atoms(rule.effect))


def rule_scope(rule: Rule) -> dict[str, str]:
    """Type of each variable of a rule (``auto`` when its two sides disagree: it is retyped)."""
    scope: dict[str, str] = {p.name: p.type for p in rule.parameters}
    for node in rule.lhs.nodes:
        scope[node.name] = node.type
    for node in rule.rhs.nodes:
        if scope.get(node.name, node.type) != node.type:
            scope[node.name] = ANY_TYPE
        else:
            scope[node.name] = node.type
    return scope


def _condition_reads_typed(rule: Rule, out: _Reads) -> None:
    scope = rule_scope(rule)
    _pattern_reads(rule.lhs, out, scope)
    for cond in rule.where:
        _expr_reads(cond, out, scope)
    _formula_reads(rule.precondition, out, scope)


def relevant_rules(rules: Iterable[Rule], target: Target, types: TypeTable | None = None) -> list[Rule]:
    """The rules (in their original order) that can contribute to reaching ``target``;
    ``types`` is the grammar's type table (without it, types overlap only when equal)."""
    rules = list(rules)
    typing = _Types(types)
    reads = _Reads()
    target_scope = {node.name: node.type for node in target.pattern.nodes}
    _pattern_reads(target.pattern, reads, {})
    for cond in target.where:
        _expr_reads(cond, reads, target_scope)
    _formula_reads(target.precondition, reads, target_scope)
    changes: dict[str, tuple[set[TypedLink], set[str]]] = {}
    for rule in rules:
        scope = rule_scope(rule)
        links: set[TypedLink] = set()
        for link in (*rule.added_links, *rule.removed_links):
            links.update(_typed(link.label, link.src, link.dst, scope, link.undirected))
        changes[rule.name] = (links | _effect_changes(rule.effect, scope), {a.attr for a in rule.assignments})
    dormant = {rule.name: rule.dormant for rule in rules}
    chosen: set[str] = set()
    grew = True
    while grew:
        grew = False
        for rule in rules:
            if rule.name in chosen:
                continue
            links, attrs = changes[rule.name]
            enables = any(name in chosen and dormant[name] for name in rule.activates)
            if not (_edits_nodes(rule) or _touches(links, reads.links, typing) or attrs & reads.attrs or enables):
                continue
            chosen.add(rule.name)
            grew = True
            _condition_reads_typed(rule, reads)
        # effects of chosen rules: their conditions matter where they change relevant links
        before = (len(reads.links), len(reads.attrs))
        for rule in rules:
            if rule.name in chosen:
                scope = rule_scope(rule)
                _effect_reads(rule.effect, reads, typing, reads, scope)
                for assignment in rule.assignments:
                    if assignment.attr in reads.attrs:
                        _expr_reads(assignment.value, reads, scope)
        if (len(reads.links), len(reads.attrs)) != before:
            grew = True
    return [rule for rule in rules if rule.name in chosen]


def condition_reads(rule: Rule) -> tuple[frozenset[TypedLink], frozenset[str]]:
    """Typed links and attribute keys that decide whether (and where) ``rule`` applies: its
    left-hand side (negated links and ``[...]`` conditions included), ``where`` and
    ``precondition``. Two states that agree on these (and on their nodes) give the same matches,
    which is what lets the planner reuse them (planner.py)."""
    reads = _Reads()
    _condition_reads_typed(rule, reads)
    return frozenset(reads.links), frozenset(reads.attrs)
