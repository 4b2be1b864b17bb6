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
from typing import assert_never

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
    Literal,
    Not,
    Or,
    Pattern,
    Rule,
    Target,
    TypeTable,
    VarRef,
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
    match expr:
        case AttrRef():
            out.attrs.add(expr.attr)
        case Compare():
            _expr_reads(expr.left, out, scope)
            _expr_reads(expr.right, out, scope)
        case Not():
            _expr_reads(expr.expr, out, scope)
        case And() | Or() | ListLit():
            for item in expr.items:
                _expr_reads(item, out, scope)
        case Exists():
            _pattern_reads(expr.pattern, out, scope)
        case Literal() | VarRef():
            pass
        case _:
            assert_never(expr)


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
    match formula:
        case None | FSame() | FCreate() | FDelete() | FRetype():
            pass
        case FLink():
            out.links.update(_typed(formula.label, formula.src, formula.dst, scope))
        case FNot():
            _formula_reads(formula.body, out, scope)
        case FAnd() | FOr():
            for item in formula.items:
                _formula_reads(item, out, scope)
        case FExists() | FForall():
            _formula_reads(formula.body, out, {**scope, **{v.name: v.type for v in formula.vars}})
        case FWhen():
            _formula_reads(formula.condition, out, scope)
            _formula_reads(formula.then, out, scope)
        case _:
            assert_never(formula)


def _effect_changes(formula: Formula | None, scope: Mapping[str, str]) -> set[TypedLink]:
    """Links an effect formula adds or removes (outside when-conditions)."""
    match formula:
        case FLink():
            return set(_typed(formula.label, formula.src, formula.dst, scope))
        case FNot():
            return _effect_changes(formula.body, scope)
        case FAnd():
            out: set[TypedLink] = set()
            for item in formula.items:
                out |= _effect_changes(item, scope)
            return out
        case FForall():
            return _effect_changes(formula.body, {**scope, **{v.name: v.type for v in formula.vars}})
        case FWhen():
            return _effect_changes(formula.then, scope)
        case None | FOr() | FExists() | FSame() | FCreate() | FDelete() | FRetype():
            return set()  # no link changes (node edits are handled by _edits_nodes)
        case _:
            assert_never(formula)


def _effect_reads(formula: Formula | None, relevant: _Reads, types: _Types, out: _Reads,
                  scope: Mapping[str, str]) -> None:
    """Links read by the when-conditions of an effect whose branches change relevant links."""
    match formula:
        case FAnd():
            for item in formula.items:
                _effect_reads(item, relevant, types, out, scope)
        case FForall():
            _effect_reads(formula.body, relevant, types, out, {**scope, **{v.name: v.type for v in formula.vars}})
        case FWhen():
            if _touches(_effect_changes(formula.then, scope), relevant.links, types):
                _formula_reads(formula.condition, out, scope)
            _effect_reads(formula.then, relevant, types, out, scope)
        case None | FLink() | FNot() | FOr() | FExists() | FSame() | FCreate() | FDelete() | FRetype():
            pass  # no when-condition below
        case _:
            assert_never(formula)


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


# ----------------------------------------------------------------------------- useless removers
# A second pass drops relevant rules whose only relevant change is to *remove* links that nothing
# needs absent (approachPerson and takeTheAttention clear the robot's `near` link to objects, but
# an object mission needs that link present). Argument (docs/grammar.md, "How planning works"):
# call a typed link class *monotone* when every remaining reader wants it present (positive
# pattern links and formula atoms), clears it unconditionally (an effect `(when (L a x) (not
# (L a x)))` gives the same result whether the link was there or not), or is a *self-guard*
# (`a->b(L)*` on the left of a rule that adds `a->b(L)` and otherwise only removes monotone
# links). A world with more monotone links is then never worse: every plan step either applies
# there too with a result that again has more monotone links, or is a self-guarded step whose
# link is already there and can be skipped. So a step that only removes monotone links can be
# left out of any plan at no loss, and its rule can be dropped.

def _is_clear(formula: FWhen) -> bool:
    """``(when (L a b) (not (L a b)))``: removes the link whether or not it was there."""
    match formula.condition, formula.then:
        case FLink() as c, FNot(body=FLink() as t):
            return (c.label, c.src, c.dst) == (t.label, t.src, t.dst)
    return False


def _negative_expr(expr: Expr, negative: bool, out: set[TypedLink], scope: Mapping[str, str]) -> None:
    match expr:
        case Not():
            _negative_expr(expr.expr, not negative, out, scope)
        case And() | Or():
            for item in expr.items:
                _negative_expr(item, negative, out, scope)
        case Exists():
            _negative_pattern(expr.pattern, negative, out, scope)
        case Literal() | ListLit() | AttrRef() | VarRef() | Compare():
            pass  # reads no link
        case _:
            assert_never(expr)


def _negative_pattern(pattern: Pattern, negative: bool, out: set[TypedLink], scope: Mapping[str, str],
                      skip: Iterable[tuple[str, str, str]] = ()) -> None:
    """Typed links a pattern (read with polarity ``negative``) needs absent; ``skip`` = self-guards."""
    inner = _pattern_scope(pattern, scope)
    skipped = set(skip)
    for link in pattern.links:
        if link.negated != negative and (link.src, link.dst, link.label) not in skipped:
            out.update(_typed(link.label, link.src, link.dst, inner, link.undirected))
        for cond in link.conditions:
            _negative_expr(cond, negative, out, inner)
    for node in pattern.nodes:
        for cond in node.conditions:
            _negative_expr(cond, negative, out, inner)


def _negative_formula(formula: Formula | None, negative: bool, out: set[TypedLink], scope: Mapping[str, str]) -> None:
    match formula:
        case FLink():
            if negative:
                out.update(_typed(formula.label, formula.src, formula.dst, scope))
        case FNot():
            _negative_formula(formula.body, not negative, out, scope)
        case FAnd() | FOr():
            for item in formula.items:
                _negative_formula(item, negative, out, scope)
        case FExists() | FForall():
            _negative_formula(formula.body, negative, out, {**scope, **{v.name: v.type for v in formula.vars}})
        case FWhen():
            _negative_formula(formula.condition, not negative, out, scope)
            _negative_formula(formula.then, negative, out, scope)
        case None | FSame() | FCreate() | FDelete() | FRetype():
            pass
        case _:
            assert_never(formula)


def _effect_condition_reads(formula: Formula | None, out: set[TypedLink], scope: Mapping[str, str]) -> None:
    """Links read by an effect's when-conditions, unconditional clears excepted (both polarities)."""
    match formula:
        case FAnd():
            for item in formula.items:
                _effect_condition_reads(item, out, scope)
        case FForall():
            _effect_condition_reads(formula.body, out, {**scope, **{v.name: v.type for v in formula.vars}})
        case FWhen():
            if not _is_clear(formula):
                reads = _Reads()
                _formula_reads(formula.condition, reads, scope)
                out.update(reads.links)
            _effect_condition_reads(formula.then, out, scope)
        case None | FLink() | FNot() | FOr() | FExists() | FSame() | FCreate() | FDelete() | FRetype():
            pass  # no when-condition below
        case _:
            assert_never(formula)


def _effect_edits(formula: Formula | None, scope: Mapping[str, str]) -> tuple[set[TypedLink], set[TypedLink]]:
    """(links an effect adds, links it removes), typed."""
    adds: set[TypedLink] = set()
    removes: set[TypedLink] = set()
    stack: list[tuple[Formula, Mapping[str, str]]] = [(formula, scope)] if formula is not None else []
    while stack:
        f, sc = stack.pop()
        match f:
            case FLink():
                adds.update(_typed(f.label, f.src, f.dst, sc))
            case FNot(body=FLink() as link):
                removes.update(_typed(link.label, link.src, link.dst, sc))
            case FAnd():
                stack.extend((item, sc) for item in f.items)
            case FForall():
                stack.append((f.body, {**sc, **{v.name: v.type for v in f.vars}}))
            case FWhen():
                stack.append((f.then, sc))
            case FNot() | FOr() | FExists() | FSame() | FCreate() | FDelete() | FRetype():
                adds.add((ANY_TYPE, ANY_TYPE, ANY_TYPE))  # count it as an unknown addition
            case _:
                assert_never(f)
    return adds, removes


@dataclass
class _RuleFacts:
    rule: Rule
    reads: set[TypedLink]          # every typed link its conditions read
    attrs_read: set[str]
    negative: set[TypedLink]       # read as "must be absent" (self-guards excluded)
    guards: set[TypedLink]         # its self-guards
    adds: set[TypedLink]           # added, guarded links excluded
    guarded_adds: set[TypedLink]   # the guarded links it adds
    removes: set[TypedLink]
    edits: bool                    # creates/deletes/retypes nodes, sets attributes or activates rules


def _facts(rule: Rule) -> _RuleFacts:
    scope = rule_scope(rule)
    added = {(l.src, l.dst, l.label) for l in rule.added_links}
    guard_keys = [(l.src, l.dst, l.label) for l in rule.lhs.links
                  if l.negated and not l.conditions and not l.undirected and (l.src, l.dst, l.label) in added]
    reads = _Reads()
    _condition_reads_typed(rule, reads)
    effect_reads: set[TypedLink] = set()
    _effect_condition_reads(rule.effect, effect_reads, scope)
    negative: set[TypedLink] = set()
    _negative_pattern(rule.lhs, False, negative, scope, skip=guard_keys)
    for cond in rule.where:
        _negative_expr(cond, False, negative, scope)
    _negative_formula(rule.precondition, False, negative, scope)
    negative |= effect_reads
    guards = {t for key in guard_keys for t in _typed(key[2], key[0], key[1], scope)}
    adds: set[TypedLink] = set()
    guarded_adds: set[TypedLink] = set()
    for link in rule.added_links:
        typed = _typed(link.label, link.src, link.dst, scope, link.undirected)
        (guarded_adds if (link.src, link.dst, link.label) in guard_keys else adds).update(typed)
    removes: set[TypedLink] = set()
    for link in rule.removed_links:
        removes.update(_typed(link.label, link.src, link.dst, scope, link.undirected))
    effect_adds, effect_removes = _effect_edits(rule.effect, scope)
    edits = _edits_nodes(rule) or bool(rule.assignments) or bool(rule.activates) or rule.dormant
    return _RuleFacts(rule, reads.links | effect_reads, reads.attrs, negative, guards, adds | effect_adds,
                      guarded_adds, removes | effect_removes, edits)


def drop_useless_removers(rules: list[Rule], target: Target, types: TypeTable | None = None) -> list[Rule]:
    """``rules`` (already relevant) without those whose only relevant changes remove monotone links."""
    typing = _Types(types)
    facts = {rule.name: _facts(rule) for rule in rules}
    target_reads = _Reads()
    _pattern_reads(target.pattern, target_reads, {})
    target_scope = {node.name: node.type for node in target.pattern.nodes}
    for cond in target.where:
        _expr_reads(cond, target_reads, target_scope)
    _formula_reads(target.precondition, target_reads, target_scope)
    target_negative: set[TypedLink] = set()
    _negative_pattern(target.pattern, False, target_negative, {})
    for cond in target.where:
        _negative_expr(cond, False, target_negative, target_scope)
    _negative_formula(target.precondition, False, target_negative, target_scope)

    kept = [rule.name for rule in rules]
    changed = True
    while changed:
        changed = False
        for name in list(kept):
            others = [facts[n] for n in kept if n != name]
            if _prunable(facts[name], others, target_reads, target_negative, typing):
                kept.remove(name)
                changed = True
                break
    return [rule for rule in rules if rule.name in kept]


def _prunable(me: _RuleFacts, others: list[_RuleFacts], target_reads: _Reads, target_negative: set[TypedLink],
              typing: _Types) -> bool:
    if me.edits:
        return False
    reads = set(target_reads.links)
    attrs = set(target_reads.attrs)
    for other in others:
        reads |= other.reads
        attrs |= other.attrs_read
    if _touches(me.adds | me.guarded_adds, reads, typing):  # it adds something someone reads: it may help
        return False
    removed = [link for link in me.removes if any(typing.link_overlap(link, r) for r in reads)]
    if not removed:
        return False  # relevant for some other reason (kept: the first pass chose it)
    # self-guarded rules are skippable when, besides their guarded link, they only remove
    # monotone links: greatest fixpoint over (monotone classes, skippable rules)
    skippable = {id(o) for o in others if o.guards and not o.edits}
    while True:
        negative = set(target_negative)
        for other in others:
            negative |= other.negative
            if id(other) not in skippable:
                negative |= other.guards
        bad = [o for o in others if id(o) in skippable and
               (_touches(o.adds, reads, typing) or _touches(o.removes, negative, typing))]
        if not bad:
            break
        for o in bad:
            skippable.discard(id(o))
    return not _touches(removed, negative, typing)


def pattern_reads(pattern: Pattern) -> tuple[frozenset[TypedLink], frozenset[str]]:
    """Typed links and attribute keys a (nested) pattern reads; variables it does not declare
    (those of the enclosing pattern) may be of any type."""
    reads = _Reads()
    _pattern_reads(pattern, reads, {})
    return frozenset(reads.links), frozenset(reads.attrs)
