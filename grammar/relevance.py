"""Which rules can matter for a target: backward relevance over link labels and attributes.

Why: a mission "go to room X" does not care whether the robot stands near an object on the way,
yet rules like goToObject multiply the search states by the objects of every room. A rule is
*relevant* when it changes a link label or an attribute that the target reads, or that another
relevant rule reads to decide whether it applies (its LHS, ``where``, ``precondition``) or what
its relevant effects do. Irrelevant rules only change things nothing relevant ever reads, so
dropping them changes neither which targets are reachable nor the cheapest plan's cost.

Conservative cases: a rule that creates, deletes or retypes nodes is always relevant; a rule that
activates a relevant dormant rule is relevant.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field

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
    Not,
    Or,
    Pattern,
    Rule,
    Target,
    effect_atoms,
)


@dataclass
class _Reads:
    labels: set[str] = field(default_factory=set)
    attrs: set[str] = field(default_factory=set)


def _expr_reads(expr: Expr, out: _Reads) -> None:
    if isinstance(expr, AttrRef):
        out.attrs.add(expr.attr)
    elif isinstance(expr, Compare):
        _expr_reads(expr.left, out)
        _expr_reads(expr.right, out)
    elif isinstance(expr, Not):
        _expr_reads(expr.expr, out)
    elif isinstance(expr, (And, Or, ListLit)):
        for item in expr.items:
            _expr_reads(item, out)
    elif isinstance(expr, Exists):
        _pattern_reads(expr.pattern, out)


def _pattern_reads(pattern: Pattern, out: _Reads) -> None:
    for node in pattern.nodes:
        for cond in node.conditions:
            _expr_reads(cond, out)
    for link in pattern.links:
        out.labels.add(link.label)
        for cond in link.conditions:
            _expr_reads(cond, out)


def _formula_reads(formula: Formula | None, out: _Reads) -> None:
    """Labels read by a formula used as a condition."""
    if formula is None:
        return
    if isinstance(formula, FLink):
        out.labels.add(formula.label)
    elif isinstance(formula, FNot):
        _formula_reads(formula.body, out)
    elif isinstance(formula, (FAnd, FOr)):
        for item in formula.items:
            _formula_reads(item, out)
    elif isinstance(formula, (FExists, FForall)):
        _formula_reads(formula.body, out)
    elif isinstance(formula, FWhen):
        _formula_reads(formula.condition, out)
        _formula_reads(formula.then, out)
    elif isinstance(formula, FSame):
        pass


def _effect_changes(formula: Formula | None) -> set[str]:
    """Labels an effect formula adds or removes (outside when-conditions)."""
    if formula is None:
        return set()
    if isinstance(formula, FLink):
        return {formula.label}
    if isinstance(formula, FNot):
        return _effect_changes(formula.body)
    if isinstance(formula, FAnd):
        out: set[str] = set()
        for item in formula.items:
            out |= _effect_changes(item)
        return out
    if isinstance(formula, FForall):
        return _effect_changes(formula.body)
    if isinstance(formula, FWhen):
        return _effect_changes(formula.then)
    return set()


def _effect_reads(formula: Formula | None, relevant: set[str], out: _Reads) -> None:
    """Labels read by the when-conditions of an effect whose branches change relevant labels."""
    if formula is None:
        return
    if isinstance(formula, FAnd):
        for item in formula.items:
            _effect_reads(item, relevant, out)
    elif isinstance(formula, FForall):
        _effect_reads(formula.body, relevant, out)
    elif isinstance(formula, FWhen):
        if _effect_changes(formula.then) & relevant:
            _formula_reads(formula.condition, out)
        _effect_reads(formula.then, relevant, out)


def _edits_nodes(rule: Rule) -> bool:
    if rule.created_nodes or rule.deleted_nodes or rule.retyped_nodes:
        return True
    return any(isinstance(atom, (FCreate, FDelete, FRetype)) for atom in effect_atoms(rule.effect))


def relevant_rules(rules: Iterable[Rule], target: Target) -> list[Rule]:
    """The rules (in their original order) that can contribute to reaching ``target``."""
    rules = list(rules)
    reads = _Reads()
    _pattern_reads(target.pattern, reads)
    for cond in target.where:
        _expr_reads(cond, reads)
    _formula_reads(target.precondition, reads)
    changes = {
        rule.name: ({l.label for l in (*rule.added_links, *rule.removed_links)} | _effect_changes(rule.effect),
                    {a.attr for a in rule.assignments})
        for rule in rules
    }
    dormant = {rule.name: rule.dormant for rule in rules}
    chosen: set[str] = set()
    grew = True
    while grew:
        grew = False
        for rule in rules:
            if rule.name in chosen:
                continue
            labels, attrs = changes[rule.name]
            enables = any(name in chosen and dormant[name] for name in rule.activates)
            if not (_edits_nodes(rule) or labels & reads.labels or attrs & reads.attrs or enables):
                continue
            chosen.add(rule.name)
            grew = True
            _pattern_reads(rule.lhs, reads)
            for cond in rule.where:
                _expr_reads(cond, reads)
            _formula_reads(rule.precondition, reads)
        # effects of chosen rules: their conditions matter where they change relevant labels
        before = (len(reads.labels), len(reads.attrs))
        for rule in rules:
            if rule.name in chosen:
                _effect_reads(rule.effect, reads.labels, reads)
                for assignment in rule.assignments:
                    if assignment.attr in reads.attrs:
                        _expr_reads(assignment.value, reads)
        if (len(reads.labels), len(reads.attrs)) != before:
            grew = True
    return [rule for rule in rules if rule.name in chosen]


def condition_reads(rule: Rule) -> tuple[frozenset[str], frozenset[str]]:
    """Link labels and attribute keys that decide whether (and where) ``rule`` applies: its
    left-hand side (negated links and ``[...]`` conditions included), ``where`` and
    ``precondition``. Two states that agree on these (and on their nodes) give the same matches,
    which is what lets the planner reuse them (planner.py)."""
    reads = _Reads()
    _pattern_reads(rule.lhs, reads)
    for cond in rule.where:
        _expr_reads(cond, reads)
    _formula_reads(rule.precondition, reads)
    return frozenset(reads.labels), frozenset(reads.attrs)
