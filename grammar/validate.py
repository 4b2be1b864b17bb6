"""Checks that need more than one token: names declared before use, sections used where they mean
something, formulas that AGM would silently misread.

Why here and not in the planner: a mistake in a grammar file must be reported when the file is
loaded, with its line and column, not as a wrong plan an hour later.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from typing import assert_never

from grammar.errors import GrammarError, SourcePos, shorten
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
    Grammar,
    ListLit,
    Literal,
    Not,
    Or,
    Pattern,
    Rule,
    Target,
    VarRef,
    expr_children,
    formula_children,
)


def check_pattern(pattern: Pattern, scope: frozenset[str], where: str, *, allow_conditions: bool,
                  fallback: SourcePos | None) -> frozenset[str]:
    """Check one pattern; returns the names it declares plus ``scope`` (enclosing variables)."""
    seen: dict[str, SourcePos | None] = {}
    for node in pattern.nodes:
        if node.name in seen:
            raise GrammarError.at(node.pos or fallback,
                                  f"{where}: node {node.name!r} is declared twice")
        seen[node.name] = node.pos
    names = scope | frozenset(seen)
    for node in pattern.nodes:
        if node.conditions and not allow_conditions:
            raise GrammarError.at(node.pos or fallback,
                                  f"{where}: conditions [...] are only allowed on the left-hand side "
                                  "and in targets; change attributes with 'set'")
        for cond in node.conditions:
            check_expr(cond, names, fallback=node.pos or fallback, own=True)
    for link in pattern.links:
        for end in (link.src, link.dst):
            if end not in names:
                raise GrammarError.at(link.pos or fallback,
                                      f"{where}: link {link.src}->{link.dst}({link.label}) uses "
                                      f"undeclared node {end!r}")
        if link.conditions and not allow_conditions:
            raise GrammarError.at(link.pos or fallback,
                                  f"{where}: conditions [...] are only allowed on the left-hand side")
        for cond in link.conditions:
            check_expr(cond, names, fallback=link.pos or fallback, own=True)
    return names


def check_expr(expr: Expr, scope: frozenset[str], *, fallback: SourcePos | None, own: bool = False) -> None:
    """Every variable an expression reads must be in scope; ``own`` allows bare attribute names."""
    match expr:
        case AttrRef():
            if expr.var is None:
                if not own:
                    raise GrammarError.at(expr.pos or fallback,
                                          f"attribute {expr.attr!r} of what? write VAR.{expr.attr}")
            elif expr.var not in scope:
                raise GrammarError.at(expr.pos or fallback,
                                      f"unknown variable {expr.var!r} in {expr.var}.{expr.attr}")
        case VarRef():
            if expr.var not in scope:
                raise GrammarError.at(expr.pos or fallback, f"unknown variable {expr.var!r}")
        case Compare() | Not() | And() | Or() | ListLit():
            for item in expr_children(expr):
                check_expr(item, scope, fallback=fallback, own=own)
        case Exists():
            check_pattern(expr.pattern, scope, "exists", allow_conditions=True, fallback=expr.pos or fallback)
        case Literal():
            pass
        case _:
            assert_never(expr)


def check_formula(formula: Formula, scope: frozenset[str], *, effect: bool, in_condition: bool,
                  fallback: SourcePos | None) -> None:
    """Variables in scope; connectives used where AGM gives them a meaning."""
    what = "effect" if effect and not in_condition else "condition"

    def names(*items: str) -> None:
        for name in items:
            if name not in scope:
                raise GrammarError.at(getattr(formula, "pos", None) or fallback,
                                      f"unknown variable {name!r} in {what} formula")

    problem = _misplaced(formula, effect_place=effect and not in_condition)
    if problem is not None:
        raise GrammarError.at(formula_pos(formula) or fallback, problem)
    match formula:
        case FLink():
            names(formula.src, formula.dst)
        case FSame():
            names(formula.a, formula.b)
        case FDelete() | FRetype():
            names(formula.var)
        case FCreate():
            pass  # introduces its variable (see _created_in)
        case FExists() | FForall():
            inner = scope | frozenset(v.name for v in formula.vars)
            check_formula(formula.body, inner, effect=effect, in_condition=in_condition, fallback=fallback)
        case FWhen():
            check_formula(formula.condition, scope, effect=effect, in_condition=True, fallback=fallback)
            check_formula(formula.then, scope, effect=effect, in_condition=in_condition, fallback=fallback)
        case FNot() | FAnd() | FOr():
            for item in formula_children(formula):
                check_formula(item, scope, effect=effect, in_condition=in_condition, fallback=fallback)
        case _:
            assert_never(formula)


def _misplaced(formula: Formula, *, effect_place: bool) -> str | None:
    """Why ``formula`` has no meaning where it is written (an effect, or a condition), or None:
    AGM gives tests no meaning in effects and graph edits none in conditions."""
    match formula:
        case FSame() if effect_place:
            return "(= a b) is a test: in an effect it may only appear inside the condition of a (when ...)"
        case FNot(body=body) if effect_place and not isinstance(body, FLink):
            return "(not ...) in an effect removes a link: it must wrap a link atom such as (not (in a b))"
        case FOr() if effect_place:
            return "(or ...) has no meaning in an effect (outside the condition of a (when ...))"
        case FExists() if effect_place:
            return "(exists ...) has no meaning in an effect"
        case FCreate() | FDelete() | FRetype() if not effect_place:
            return f"({type(formula).__name__[1:].lower()} ...) changes the graph: it is only allowed in an effect"
    return None


def formula_pos(formula: Formula) -> SourcePos | None:
    """Where a formula was written: the position of its first atom that has one."""
    pos = getattr(formula, "pos", None)
    if pos is not None:
        return pos
    children = formula_children(formula)
    return formula_pos(children[0]) if children else None


def _created_in(formula: Formula | None) -> set[str]:
    """Variables that ``(create v T)`` introduces, usable elsewhere in the same effect."""
    if formula is None:
        return set()
    if isinstance(formula, FCreate):
        return {formula.var}
    out: set[str] = set()
    for inner in formula_children(formula):
        out |= _created_in(inner)
    return out


def check_rule(rule: Rule) -> None:
    where = f"rule {shorten(rule.name)!r}"
    if not math.isfinite(rule.cost):
        raise GrammarError.at(rule.pos, f"{where}: cost {rule.cost:g} is not a finite number")
    if rule.success is not None and not (0.0 <= rule.success <= 1.0):
        raise GrammarError.at(rule.pos, f"{where}: success {rule.success:g} is not a probability "
                                        "(between 0 and 1)")
    if rule.cost < 0:
        raise GrammarError.at(rule.pos, f"{where}: cost {rule.cost:g} is negative; the planner needs "
                                        "costs >= 0 to find the cheapest plan")
    params = frozenset(p.name for p in rule.parameters)
    lhs_names = check_pattern(rule.lhs, params, f"{where}, left-hand side", allow_conditions=True,
                              fallback=rule.pos)
    rhs_names = check_pattern(rule.rhs, params, f"{where}, right-hand side", allow_conditions=False,
                              fallback=rule.pos)
    lhs_keys = {link.key for link in rule.lhs.links if link.undirected and not link.negated}
    rhs_keys = {link.key for link in rule.rhs.links if link.undirected and not link.negated}
    for link in (*rule.lhs.links, *rule.rhs.links):
        if link.undirected and not link.negated and (link.key in lhs_keys) != (link.key in rhs_keys):
            raise GrammarError.at(link.pos or rule.pos,
                                  f"{where}: undirected link {link.src}--{link.dst}({link.label}) must "
                                  "appear on both sides (it can be tested, not added or removed)")
    for cond in rule.where:
        check_expr(cond, lhs_names, fallback=rule.pos)
    both = lhs_names | rhs_names
    for assignment in rule.assignments:
        if assignment.var not in rhs_names:
            raise GrammarError.at(assignment.pos or rule.pos,
                                  f"{where}: 'set {assignment.var}.{assignment.attr}' needs "
                                  f"{assignment.var!r} on the right-hand side")
        if assignment.attr in ("name", "type"):
            raise GrammarError.at(assignment.pos or rule.pos,
                                  f"{where}: 'set' cannot change a node's {assignment.attr}")
        check_expr(assignment.value, both, fallback=assignment.pos or rule.pos)
    if rule.precondition is not None:
        check_formula(rule.precondition, lhs_names, effect=False, in_condition=False, fallback=rule.pos)
    if rule.effect is not None:
        scope = both | frozenset(_created_in(rule.effect))
        check_formula(rule.effect, scope, effect=True, in_condition=False, fallback=rule.pos)


def check_target(target: Target) -> None:
    names = check_pattern(target.pattern, frozenset(), "target", allow_conditions=True, fallback=None)
    for cond in target.where:
        check_expr(cond, names, fallback=None)
    if target.precondition is not None:
        check_formula(target.precondition, names, effect=False, in_condition=False, fallback=None)


def _types_used(rule: Rule) -> Iterator[tuple[str, SourcePos | None]]:
    """Every type a rule names: pattern nodes (nested ``exists`` included), quantified and
    parameter variables, ``create``/``retype`` in formulas."""
    patterns = [rule.rhs, rule.lhs]  # popped from the end: left-hand side first
    exprs: list[Expr] = list(rule.where) + [a.value for a in rule.assignments]
    formulas: list[Formula] = [f for f in (rule.precondition, rule.effect) if f is not None]
    for decl in rule.parameters:
        yield decl.type, decl.pos
    while patterns or exprs or formulas:
        if patterns:
            pattern = patterns.pop()
            for node in pattern.nodes:
                yield node.type, node.pos
                exprs.extend(node.conditions)
            for link in pattern.links:
                exprs.extend(link.conditions)
        elif exprs:
            expr = exprs.pop()
            if isinstance(expr, Exists):
                patterns.append(expr.pattern)
            exprs.extend(expr_children(expr))
        else:
            formula = formulas.pop()
            match formula:
                case FExists() | FForall():
                    for decl in formula.vars:
                        yield decl.type, decl.pos
                case FCreate() | FRetype():
                    yield formula.type, formula.pos
            formulas.extend(formula_children(formula))


def check_grammar(grammar: Grammar, *, top_level: bool = True) -> None:
    """Whole-grammar checks, after includes are merged: unique rule names, known activations,
    declared types (when the grammar has a ``types`` section), and at least one rule."""
    seen: dict[str, Rule] = {}
    for rule in grammar.rules:
        if rule.name in seen:
            first = seen[rule.name].pos
            raise GrammarError.at(rule.pos, f"rule {shorten(rule.name)!r} is defined twice (first at {first})")
        seen[rule.name] = rule
    for rule in grammar.rules:
        for name in rule.activates:
            if name not in seen and not grammar.skipped_includes:
                raise GrammarError.at(rule.pos, f"rule {shorten(rule.name)!r} activates unknown rule "
                                                f"{shorten(name)!r}")
    if grammar.declared_types:
        declared = set(grammar.types.parents)
        for rule in grammar.rules:
            for type_name, pos in _types_used(rule):
                if type_name not in declared and type_name != ANY_TYPE:
                    known = ", ".join(sorted(declared)[:12]) + (", ..." if len(declared) > 12 else "")
                    raise GrammarError.at(pos or rule.pos,
                                          f"rule {shorten(rule.name)!r} uses type {shorten(type_name)!r}, "
                                          f"which the types section does not declare (declared: {known})")
    if top_level and not grammar.rules and not grammar.combos and not grammar.skipped_includes:
        raise GrammarError("no rules: a grammar needs at least one rule to plan with", grammar.file, 1, 1)
