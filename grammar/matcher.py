"""Typed subgraph matching of patterns against a world state, with an index-driven search order.

Why not ``networkx.isomorphism``: the planner matches every rule on every search state, and most
pattern variables are reachable from an already bound one through a labelled edge (the room the
robot is ``in``, the rooms ``connected`` to it). Walking those edges through the world's
``(node, label)`` indexes touches a few candidates per variable instead of all nodes of a type.

Semantics (those of AGM's planner):
- distinct pattern variables bind distinct world nodes (injective matching), including the
  variables already bound by an enclosing pattern;
- a pattern node of type T matches a world node whose type is T or a subtype of T (``types``
  section); type ``auto`` matches any type; a *constant* node matches only the world node with
  that name (or graph key);
- a positive link must exist, a negated link (``*`` / ``not``) must not exist (with its ``[...]``
  conditions, if any, no edge may satisfy them); an undirected link (``--``) may exist either way;
- ``[...]`` conditions on nodes and links must hold; they may read other variables' attributes.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
import itertools
from functools import lru_cache
from typing import Any, assert_never

from grammar.model import (
    ANY_TYPE,
    And,
    AttrRef,
    Compare,
    Exists,
    Expr,
    ListLit,
    Literal,
    Not,
    Or,
    Pattern,
    PatternLink,
    TypeTable,
    Value,
    VarRef,
    expr_children,
)
from grammar.world import State, World

Bindings = dict[str, int]


@dataclass(frozen=True)
class NodeRef:
    """Value of a bare variable in an expression: compares equal only to the same world node."""

    node: int


_TOKENS = itertools.count()


class Reader:
    """What a rule or a nested pattern reads: typed links ``(label, source type, destination
    type)`` and attribute keys. States that agree on what a reader can see (``view``) give it the
    same answers, which is what lets the planner reuse matches and ``exists`` results."""

    def __init__(self, links: Iterable[tuple[str, str, str]], attrs: Iterable[str], type_ok: Any) -> None:
        self.links = frozenset(links)
        self.attrs = frozenset(attrs)
        self.labels = frozenset(link[0] for link in self.links)
        self.type_ok = type_ok
        self.token = next(_TOKENS)  # unique in the process: names this reader in State.view caches
        self._seen: dict[tuple[str, str, str], bool] = {}

    def visible(self, state: State, edge: tuple[int, int, str]) -> bool:
        """Can a link of the world be one this reader reads (label and end types)?"""
        label = edge[2]
        if label not in self.labels:
            return False
        key = (label, state.type_of(edge[0]), state.type_of(edge[1]))
        found = self._seen.get(key)
        if found is None:
            type_ok = self.type_ok
            found = self._seen[key] = any(l == label and type_ok(key[1], a) and type_ok(key[2], b)
                                          for l, a, b in self.links)
        return found

    def view(self, state: State) -> tuple[object, ...]:
        return state.view(self.token, self.visible, self.attrs)


# ---------------------------------------------------------------------------- compiled patterns
@dataclass
class _LinkCheck:
    link: PatternLink


@dataclass
class _CondCheck:
    expr: Expr
    link: PatternLink | None  # conditions of a link are evaluated on its edge(s)


@dataclass
class _Step:
    var: str
    type: str
    source: tuple[Any, ...]  # how candidates are found: const / name / out / in / both / scan
    links: list[_LinkCheck] = field(default_factory=list)
    conds: list[_CondCheck] = field(default_factory=list)


@dataclass
class CompiledPattern:
    pattern: Pattern
    prebound: frozenset[str]
    pre_checks: _Step | None  # checks among prebound variables (types, links, conditions)
    steps: list[_Step]
    prebound_types: list[tuple[str, str]]


def _expr_refs(expr: Expr, own: str | None, link: PatternLink | None) -> set[str]:
    """Variables an expression reads (``own`` = the node a ``[...]`` block is written on)."""
    match expr:
        case AttrRef():
            if expr.var is not None:
                return {expr.var}
            if link is not None:
                return {link.src, link.dst}
            return {own} if own else set()
        case VarRef():
            return {expr.var}
        case Compare() | Not() | And() | Or() | ListLit():
            out: set[str] = set()
            for item in expr_children(expr):
                out |= _expr_refs(item, own, link)
            return out
        case Exists():
            return pattern_free_vars(expr.pattern)
        case Literal():
            return set()
        case _:
            assert_never(expr)


def pattern_free_vars(pattern: Pattern) -> set[str]:
    """Names a nested pattern uses without declaring them (they come from the enclosing scope)."""
    declared = {n.name for n in pattern.nodes}
    used: set[str] = set()
    for link in pattern.links:
        used |= {link.src, link.dst}
        for cond in link.conditions:
            used |= _expr_refs(cond, None, link)
    for node in pattern.nodes:
        for cond in node.conditions:
            used |= _expr_refs(cond, node.name, None)
    return used - declared


def _own_to_var(expr: Expr, var: str) -> Expr:
    match expr:
        case AttrRef(var=None):
            return AttrRef(var, expr.attr, expr.pos)
        case Compare():
            return Compare(expr.op, _own_to_var(expr.left, var), _own_to_var(expr.right, var))
        case Not():
            return Not(_own_to_var(expr.expr, var))
        case And():
            return And(tuple(_own_to_var(e, var) for e in expr.items))
        case Or():
            return Or(tuple(_own_to_var(e, var) for e in expr.items))
        case ListLit():
            return ListLit(tuple(_own_to_var(e, var) for e in expr.items))
        case AttrRef() | Literal() | VarRef() | Exists():
            return expr  # nothing of its own to rename (an exists declares its own nodes)
        case _:
            assert_never(expr)


class MatchBudgetExceeded(Exception):
    """Matching tried more candidate nodes than the planner's budget allows (see ``Matcher.budget``)."""


class Matcher:
    """Matches patterns of one grammar (its type table) on states of one world.

    ``budget`` (None: unbounded) is how many more candidate nodes matching may try before it
    raises :class:`MatchBudgetExceeded`; the planner sets it from its expansion bound, because one
    match can be exponential on its own (a 9-room ring sought in a 40-room clique tries billions of
    bindings inside the first expansion, so ``--max-expansions 1`` did not stop it)."""

    def __init__(self, types: TypeTable, world: World) -> None:
        self.types = types
        self.world = world
        self.budget: int | None = None
        self.tried = 0   # candidate nodes tried, in all (for the budget's message and measurements)
        self._compiled: dict[tuple[int, frozenset[str]], CompiledPattern] = {}
        self._ancestors = lru_cache(maxsize=None)(types.ancestors)
        self._free: dict[int, tuple[Pattern, frozenset[str], tuple[str, ...]]] = {}
        # results of nested `exists` patterns, by (pattern, its bound variables' nodes, what it
        # can see of the state): the agenda conditions of changeRoom ask the same question about
        # a room from every room next to it
        self._exists: dict[tuple[object, ...], bool] = {}
        self._readers: dict[int, tuple[Pattern, Reader]] = {}

    # ------------------------------------------------------------------ typing
    def type_ok(self, world_type: str, pattern_type: str) -> bool:
        return pattern_type == ANY_TYPE or pattern_type == world_type or \
            pattern_type in self._ancestors(world_type)

    def _type_count(self, pattern_type: str) -> int:
        return sum(len(ids) for t, ids in self.world.by_type.items() if self.type_ok(t, pattern_type))

    def candidates_of_type(self, state: State, pattern_type: str) -> Iterator[int]:
        if pattern_type == ANY_TYPE:
            yield from state.nodes()
            return
        seen: set[str] = set()
        for t in state.present_types():
            if t not in seen and self.type_ok(t, pattern_type):
                seen.add(t)
                yield from state.nodes_of_type(t)

    # ------------------------------------------------------------------ compilation
    def compile(self, pattern: Pattern, prebound: Iterable[str] = ()) -> CompiledPattern:
        pre = frozenset(prebound)
        key = (id(pattern), pre)
        found = self._compiled.get(key)
        if found is not None and found.pattern is pattern:
            return found
        compiled = self._compile(pattern, pre)
        self._compiled[key] = compiled
        return compiled

    def _compile(self, pattern: Pattern, prebound: frozenset[str]) -> CompiledPattern:
        decl = [n for n in pattern.nodes if n.name not in prebound]
        # conditions: (expr, link-or-None, vars it needs)
        conds: list[tuple[Expr, PatternLink | None, frozenset[str]]] = []
        for node in pattern.nodes:
            for cond in node.conditions:
                expr = _own_to_var(cond, node.name)
                conds.append((expr, None, frozenset(_expr_refs(expr, None, None) | {node.name})))
        for link in pattern.links:
            if link.conditions:  # all of them must hold on one and the same edge
                expr = link.conditions[0] if len(link.conditions) == 1 else And(link.conditions)
                conds.append((expr, link, frozenset(_expr_refs(expr, None, link))))
        bound: set[str] = set(prebound)
        order: list[str] = []
        remaining = list(decl)
        while remaining:
            best_key: tuple[int, int, int] | None = None
            best = None
            for index, node in enumerate(remaining):
                if node.constant is not None:
                    key = (0, 0, index)
                elif self._name_join(node.name, conds, bound) is not None:
                    key = (1, 0, index)
                else:
                    via = self._link_source(node.name, pattern.links, bound)
                    if via is not None:
                        key = (2, 0 if via[0] == "out" else 1, index)
                    else:
                        key = (3, self._type_count(node.type), index)
                if best_key is None or key < best_key:
                    best_key, best = key, node
            assert best is not None
            remaining.remove(best)
            order.append(best.name)
            bound.add(best.name)

        steps: list[_Step] = []
        done: set[str] = set(prebound)
        placed_links: set[int] = set()
        placed_conds: set[int] = set()
        pre_step = _Step("", ANY_TYPE, ("pre",))
        self._attach_checks(pre_step, pattern, conds, done, placed_links, placed_conds)
        for var in order:
            node = pattern.by_name[var]
            if node.constant is not None:
                source: tuple[Any, ...] = ("const", node.constant)
            else:
                join = self._name_join(var, conds, done)
                if join is not None:
                    source = ("name",) + join
                else:
                    via = self._link_source(var, pattern.links, done)
                    source = via if via is not None else ("scan",)
            step = _Step(var, node.type, source)
            done.add(var)
            self._attach_checks(step, pattern, conds, done, placed_links, placed_conds)
            steps.append(step)
        prebound_types = [(n.name, n.type) for n in pattern.nodes if n.name in prebound]
        has_pre = bool(pre_step.links or pre_step.conds)
        return CompiledPattern(pattern, prebound, pre_step if has_pre else None, steps, prebound_types)

    @staticmethod
    def _attach_checks(step: _Step, pattern: Pattern,
                       conds: list[tuple[Expr, PatternLink | None, frozenset[str]]],
                       done: set[str], placed_links: set[int], placed_conds: set[int]) -> None:
        """Attach every link and condition whose variables are all bound once ``step`` is done."""
        for i, link in enumerate(pattern.links):
            if i in placed_links or not {link.src, link.dst} <= done:
                continue
            placed_links.add(i)
            if not link.conditions:  # links with conditions are checked with them (see conds)
                step.links.append(_LinkCheck(link))
        for i, (expr, cond_link, needs) in enumerate(conds):
            if i in placed_conds or not needs <= done:
                continue
            placed_conds.add(i)
            step.conds.append(_CondCheck(expr, cond_link))

    @staticmethod
    def _link_source(var: str, links: Iterable[PatternLink], bound: set[str]) -> tuple[Any, ...] | None:
        """The first positive link from a bound variable to ``var``: walk it to get candidates."""
        best: tuple[Any, ...] | None = None
        for link in links:
            if link.negated:
                continue
            if link.undirected:
                if link.src == var and link.dst in bound:
                    cand: tuple[Any, ...] = ("both", link.dst, link.label)
                elif link.dst == var and link.src in bound:
                    cand = ("both", link.src, link.label)
                else:
                    continue
            elif link.dst == var and link.src in bound:
                cand = ("out", link.src, link.label)
            elif link.src == var and link.dst in bound:
                cand = ("in", link.dst, link.label)
            else:
                continue
            if best is None or (cand[0] == "out" and best[0] != "out"):
                best = cand
        return best

    @staticmethod
    def _name_join(var: str, conds: list[tuple[Expr, PatternLink | None, frozenset[str]]],
                   bound: set[str]) -> tuple[Expr, PatternLink | None] | None:
        """A condition that names ``var`` through values computable from bound variables: look
        ``var`` up by name instead of scanning its type (e.g. the door named by a ``connected``
        edge: ``[d.name in doors or door == d.name]``). See ``_name_source``."""
        for expr, link, _needs in conds:
            if link is not None and link.negated:
                continue
            if _name_source(expr, var, bound, link):
                return (expr, link)
        return None

    # ------------------------------------------------------------------ matching
    def matches(self, compiled: CompiledPattern, state: State, bindings: Bindings | None = None
                ) -> Iterator[Bindings]:
        """Every injective binding of the pattern's variables extending ``bindings``."""
        b: Bindings = dict(bindings or {})
        for var, ptype in compiled.prebound_types:
            if var not in b or not self.type_ok(state.type_of(b[var]), ptype):
                return
        if compiled.pre_checks is not None and not self._checks_pass(compiled.pre_checks, state, b):
            return
        used = set(b.values())
        yield from self._search(compiled.steps, 0, state, b, used)

    def _compile_exists(self, pattern: Pattern, b: Bindings) -> CompiledPattern:
        """A nested pattern's enclosing variables are bound; names it redeclares refer to them."""
        key = id(pattern)
        cached = self._free.get(key)
        if cached is None or cached[0] is not pattern:
            cached = (pattern, frozenset(pattern_free_vars(pattern)), tuple(n.name for n in pattern.nodes))
            self._free[key] = cached
        prebound = cached[1] | {name for name in cached[2] if name in b}
        return self.compile(pattern, prebound)

    def _exists_holds(self, pattern: Pattern, state: State, b: Bindings) -> bool:
        compiled = self._compile_exists(pattern, b)
        found = self._readers.get(id(pattern))
        if found is None or found[0] is not pattern:
            from grammar.relevance import pattern_reads  # (relevance imports no matcher)

            found = self._readers[id(pattern)] = (pattern, Reader(*pattern_reads(pattern), self.type_ok))
        reader = found[1]
        key = (reader.token, tuple(sorted((v, b[v]) for v in compiled.prebound if v in b)), reader.view(state))
        holds = self._exists.get(key)
        if holds is None:
            holds = self._exists[key] = self.first_match(compiled, state, b) is not None
        return holds

    def first_match(self, compiled: CompiledPattern, state: State, bindings: Bindings | None = None
                    ) -> Bindings | None:
        return next(self.matches(compiled, state, bindings), None)

    def _search(self, steps: list[_Step], depth: int, state: State, b: Bindings, used: set[int]
                ) -> Iterator[Bindings]:
        if depth == len(steps):
            yield dict(b)
            return
        step = steps[depth]
        for cand in self._candidates(step, state, b):
            self.tried += 1
            if self.budget is not None:
                self.budget -= 1
                if self.budget < 0:
                    raise MatchBudgetExceeded
            if cand in used or not self.type_ok(state.type_of(cand), step.type):
                continue
            b[step.var] = cand
            if self._checks_pass(step, state, b):
                used.add(cand)
                yield from self._search(steps, depth + 1, state, b, used)
                used.discard(cand)
            del b[step.var]

    def _candidates(self, step: _Step, state: State, b: Bindings) -> Iterable[int]:
        kind = step.source[0]
        if kind == "out":
            return state.out(b[step.source[1]], step.source[2])
        if kind == "in":
            return state.inn(b[step.source[1]], step.source[2])
        if kind == "both":
            anchor, label = b[step.source[1]], step.source[2]
            out = list(state.out(anchor, label))
            seen = set(out)
            out.extend(n for n in state.inn(anchor, label) if n not in seen)
            return out
        if kind == "const":
            found = state.node_by_constant(step.source[1])
            return () if found is None else (found,)
        if kind == "name":
            expr, link = step.source[1], step.source[2]
            names: set[Value] = set()
            edges = [None] if link is None else self._edges_of(link, state, b)
            for edge in edges:
                found_names = self._names_from(expr, step.var, state, b, edge)
                if found_names is None:  # a value that cannot be enumerated: scan the type
                    return self.candidates_of_type(state, step.type)
                names |= found_names
            out_ids: list[int] = []
            for name in sorted(n for n in names if isinstance(n, str)):
                found = state.node_by_name(name)
                if found is not None:
                    out_ids.append(found)
            return out_ids
        return self.candidates_of_type(state, step.type)

    def _names_from(self, expr: Expr, var: str, state: State, b: Bindings,
                    edge: tuple[int, int, str] | None) -> set[Value] | None:
        """Every name ``var`` may have for ``expr`` to hold (a superset), or ``None`` if unknown."""
        match expr:
            case Or():
                out: set[Value] = set()
                for item in expr.items:
                    part = self._names_from(item, var, state, b, edge)
                    if part is None:
                        return None
                    out |= part
                return out
            case And():
                for item in expr.items:
                    if _is_name_atom(item, var):
                        return self._names_from(item, var, state, b, edge)
                return None
            case Compare() if _is_name_atom(expr, var):
                mine_left = _is_name_ref(expr.left, var)
                other = expr.right if mine_left else expr.left
                value = self.eval(other, state, b, edge)
                if expr.op == "==":
                    return {value} if isinstance(value, str) else set()
                if isinstance(value, tuple):
                    return set(value)
                return None if isinstance(value, str) else set()  # 'in' a string: substrings, unknown
            case Compare() | Literal() | ListLit() | AttrRef() | VarRef() | Not() | Exists():
                return None
            case _:
                assert_never(expr)

    @staticmethod
    def _edges_of(link: PatternLink, state: State, b: Bindings) -> list[tuple[int, int, str]]:
        s, d = b[link.src], b[link.dst]
        edges = []
        if state.has_edge(s, d, link.label):
            edges.append((s, d, link.label))
        if link.undirected and state.has_edge(d, s, link.label):
            edges.append((d, s, link.label))
        return edges

    def _checks_pass(self, step: _Step, state: State, b: Bindings) -> bool:
        for check in step.links:
            link = check.link
            s, d = b[link.src], b[link.dst]
            present = state.has_edge(s, d, link.label) or \
                (link.undirected and state.has_edge(d, s, link.label))
            if present == link.negated:
                return False
        for cond in step.conds:
            if cond.link is None:
                if not self.truth(cond.expr, state, b):
                    return False
                continue
            link = cond.link
            ok = any(self.truth(cond.expr, state, b, edge) for edge in self._edges_of(link, state, b))
            if ok == link.negated:
                return False
        return True

    # ------------------------------------------------------------------ expressions
    def truth(self, expr: Expr, state: State, b: Bindings, edge: tuple[int, int, str] | None = None) -> bool:
        match expr:
            case And():
                return all(self.truth(e, state, b, edge) for e in expr.items)
            case Or():
                return any(self.truth(e, state, b, edge) for e in expr.items)
            case Not():
                return not self.truth(expr.expr, state, b, edge)
            case Exists():
                return self._exists_holds(expr.pattern, state, b)
            case Compare():
                return _compare(expr.op, self.eval(expr.left, state, b, edge), self.eval(expr.right, state, b, edge))
            case Literal() | AttrRef() | VarRef() | ListLit():
                return bool(self.eval(expr, state, b, edge))
            case _:
                assert_never(expr)

    def eval(self, expr: Expr, state: State, b: Bindings, edge: tuple[int, int, str] | None = None) -> Any:
        match expr:
            case Literal():
                return expr.value
            case AttrRef():
                if expr.var is not None:
                    node = b.get(expr.var)
                    return None if node is None else state.attr(node, expr.attr)
                if edge is None:
                    return None
                if expr.attr == "type":
                    return edge[2]
                return state.edge_attr(edge[0], edge[1], edge[2], expr.attr)
            case VarRef():
                node = b.get(expr.var)
                return None if node is None else NodeRef(node)
            case ListLit():
                return tuple(self.eval(e, state, b, edge) for e in expr.items)
            case And() | Or() | Not() | Exists() | Compare():
                return self.truth(expr, state, b, edge)
            case _:
                assert_never(expr)


def _is_name_ref(expr: Expr, var: str) -> bool:
    return isinstance(expr, AttrRef) and expr.var == var and expr.attr == "name"


def _is_name_atom(expr: Expr, var: str) -> bool:
    """``X == var.name``, ``var.name == X`` or ``var.name in X``."""
    if not isinstance(expr, Compare):
        return False
    if expr.op == "==":
        return _is_name_ref(expr.left, var) != _is_name_ref(expr.right, var)
    return expr.op == "in" and _is_name_ref(expr.left, var) and not _is_name_ref(expr.right, var)


def _name_source(expr: Expr, var: str, bound: set[str], link: PatternLink | None) -> bool:
    """Does ``expr`` (if true) name ``var`` through values computable from ``bound`` variables?
    An ``or`` qualifies if every branch does, an ``and`` if one of its items does."""
    match expr:
        case Or():
            return bool(expr.items) and all(_name_source(item, var, bound, link) for item in expr.items)
        case And():
            return any(_is_name_atom(item, var) and _name_source(item, var, bound, link) for item in expr.items)
        case Compare() if _is_name_atom(expr, var):
            other = expr.right if _is_name_ref(expr.left, var) else expr.left
            return not isinstance(other, Exists) and _expr_refs(other, None, link) <= bound
        case Compare() | Literal() | ListLit() | AttrRef() | VarRef() | Not() | Exists():
            return False
        case _:
            assert_never(expr)


def _compare(op: str, left: Any, right: Any) -> bool:
    """Comparisons never raise: a missing attribute (None) or mismatched types compare false
    (except ``!=``), so that bad data in the world makes a rule inapplicable, not the agent crash."""
    try:
        if op == "==":
            return bool(left == right)
        if op == "!=":
            return bool(left != right)
        if op == "in":
            return right is not None and left in right
        if left is None or right is None:
            return False
        if op == "<":
            return bool(left < right)
        if op == "<=":
            return bool(left <= right)
        if op == ">":
            return bool(left > right)
        if op == ">=":
            return bool(left >= right)
    except TypeError:
        return False
    raise ValueError(f"unknown comparison {op!r}")
