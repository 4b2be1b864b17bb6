"""Typed model of a parsed grammar: rules as data, independent of the text dialect they came from.

Why plain frozen dataclasses: the planner hashes and compares them, the executive passes them
between threads, and both dialects (chronav-native and RoboComp AGM's AGGL) produce the same model,
so everything after the parser is dialect-free.

Two condition languages live side by side:
- ``Expr``: chronav's infix expressions (``a.state == "running"``, ``exists { ... }``), used in
  ``[...]`` attribute conditions on pattern nodes/links, ``where`` sections and ``set`` values.
- ``Formula``: AGM's prefix formulas (``(forall p:person (not (is_blocking p robot)))``), used in
  ``precondition { }`` and ``effect { }`` sections of both dialects.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from functools import cached_property
from typing import assert_never

from grammar.agm_order import agm_creation_order
from grammar.errors import GrammarWarning, SourcePos

Value = bool | int | float | str | None | tuple

ANY_TYPE = "auto"
"""Pattern type that matches a world node of any type (AGM targets use it on constants)."""


# --------------------------------------------------------------------------- expressions (native)
@dataclass(frozen=True)
class Literal:
    value: Value


@dataclass(frozen=True)
class ListLit:
    items: tuple[Expr, ...]


@dataclass(frozen=True)
class AttrRef:
    """``var.attr``; ``var is None`` means the node or link the ``[...]`` condition is written on.

    ``name`` and ``type`` read the node's name and type.
    """

    var: str | None
    attr: str
    pos: SourcePos | None = field(default=None, compare=False)


@dataclass(frozen=True)
class VarRef:
    """A bare variable in a ``where``: the world node it is bound to (for ``p1 != p2``)."""

    var: str
    pos: SourcePos | None = field(default=None, compare=False)


@dataclass(frozen=True)
class Compare:
    op: str  # == != < <= > >= in
    left: Expr
    right: Expr


@dataclass(frozen=True)
class Not:
    expr: Expr


@dataclass(frozen=True)
class And:
    items: tuple[Expr, ...]


@dataclass(frozen=True)
class Or:
    items: tuple[Expr, ...]


@dataclass(frozen=True)
class Exists:
    """True when ``pattern`` matches with the enclosing variables already bound."""

    pattern: Pattern
    pos: SourcePos | None = field(default=None, compare=False)


Expr = Literal | ListLit | AttrRef | VarRef | Compare | Not | And | Or | Exists
"""In a boolean place any expression counts by Python truthiness (``[open]``, ``where a.busy``)."""


# --------------------------------------------------------------------------- formulas (AGM)
@dataclass(frozen=True)
class VarDecl:
    name: str
    type: str
    pos: SourcePos | None = field(default=None, compare=False)


@dataclass(frozen=True)
class FNot:
    body: Formula


@dataclass(frozen=True)
class FAnd:
    items: tuple[Formula, ...]


@dataclass(frozen=True)
class FOr:
    items: tuple[Formula, ...]


@dataclass(frozen=True)
class FLink:
    """``(label src dst)``: in a condition the link exists; in an effect the link is added."""

    label: str
    src: str
    dst: str
    pos: SourcePos | None = field(default=None, compare=False)


@dataclass(frozen=True)
class FSame:
    a: str
    b: str
    pos: SourcePos | None = field(default=None, compare=False)


@dataclass(frozen=True)
class FExists:
    vars: tuple[VarDecl, ...]
    body: Formula


@dataclass(frozen=True)
class FForall:
    vars: tuple[VarDecl, ...]
    body: Formula


@dataclass(frozen=True)
class FWhen:
    """``(when IF THEN)``: in a condition IF implies THEN; in an effect THEN applies where IF holds."""

    condition: Formula
    then: Formula


@dataclass(frozen=True)
class FCreate:
    var: str
    type: str
    pos: SourcePos | None = field(default=None, compare=False)


@dataclass(frozen=True)
class FDelete:
    var: str
    pos: SourcePos | None = field(default=None, compare=False)


@dataclass(frozen=True)
class FRetype:
    var: str
    type: str
    pos: SourcePos | None = field(default=None, compare=False)


Formula = FNot | FAnd | FOr | FLink | FSame | FExists | FForall | FWhen | FCreate | FDelete | FRetype


def formula_children(f: Formula) -> tuple[Formula, ...]:
    """The formulas directly inside ``f``, in written order (a when: condition, then). One place
    that knows every formula class: a class added to ``Formula`` but not here fails loudly."""
    match f:
        case FNot() | FExists() | FForall():
            return (f.body,)
        case FAnd() | FOr():
            return f.items
        case FWhen():
            return (f.condition, f.then)
        case FLink() | FSame() | FCreate() | FDelete() | FRetype():
            return ()
        case _:
            assert_never(f)


def expr_children(e: Expr) -> tuple[Expr, ...]:
    """The expressions directly inside ``e`` (an ``exists`` holds a pattern, not expressions)."""
    match e:
        case Compare():
            return (e.left, e.right)
        case Not():
            return (e.expr,)
        case And() | Or() | ListLit():
            return e.items
        case Literal() | AttrRef() | VarRef() | Exists():
            return ()
        case _:
            assert_never(e)


def effect_atoms(formula: Formula | None) -> Iterator[Formula]:
    """The atoms an effect formula applies (links, node edits, ...), found through not, and, or,
    forall, exists and the THEN of a when (a when's condition is read, not applied)."""
    stack: list[Formula] = [formula] if formula is not None else []
    while stack:
        f = stack.pop()
        match f:
            case FNot():
                stack.append(f.body)
            case FAnd() | FOr():
                stack.extend(f.items)
            case FForall() | FExists():
                stack.append(f.body)
            case FWhen():
                stack.append(f.then)
            case FLink() | FSame() | FCreate() | FDelete() | FRetype():
                yield f
            case _:
                assert_never(f)


# --------------------------------------------------------------------------- patterns
@dataclass(frozen=True)
class PatternNode:
    """``name:type``; a ``constant`` pattern node matches only the world node with that name/id."""

    name: str
    type: str
    constant: str | None = None
    conditions: tuple[Expr, ...] = ()
    pos: SourcePos | None = field(default=None, compare=False)


@dataclass(frozen=True)
class PatternLink:
    """``src->dst(label)``; ``negated`` (AGM ``*``) = must be absent; ``undirected`` (``--``) = either way."""

    src: str
    dst: str
    label: str
    negated: bool = False
    undirected: bool = False
    conditions: tuple[Expr, ...] = ()
    pos: SourcePos | None = field(default=None, compare=False)

    @property
    def key(self) -> tuple[str, str, str, bool]:
        return (self.src, self.dst, self.label, self.undirected)


@dataclass(frozen=True)
class Pattern:
    nodes: tuple[PatternNode, ...] = ()
    links: tuple[PatternLink, ...] = ()

    @cached_property
    def by_name(self) -> dict[str, PatternNode]:
        return {node.name: node for node in self.nodes}

    def node(self, name: str) -> PatternNode | None:
        return self.by_name.get(name)


@dataclass(frozen=True)
class Assignment:
    """``set var.attr = value``: an effect on an attribute, evaluated on the rewritten graph."""

    var: str
    attr: str
    value: Expr
    pos: SourcePos | None = field(default=None, compare=False)


@dataclass(frozen=True)
class Rule:
    """One rewrite rule: LHS pattern => RHS pattern, plus conditions and effects.

    Semantics (as AGM): LHS nodes absent from the RHS are deleted, RHS nodes absent from the LHS are
    created, a node whose type differs is retyped; positive links only in the LHS are removed, only
    in the RHS are added. ``where`` conditions and the ``precondition`` formula must hold on the
    current graph; the ``effect`` formula and ``set`` assignments apply after the rewrite.
    """

    name: str
    lhs: Pattern
    rhs: Pattern
    cost: float = 1.0
    active: bool = True
    where: tuple[Expr, ...] = ()
    precondition: Formula | None = None
    effect: Formula | None = None
    assignments: tuple[Assignment, ...] = ()
    parameters: tuple[VarDecl, ...] = ()
    hierarchical: bool = False
    dormant: bool = False
    activates: tuple[str, ...] = ()
    success: float | None = None
    pos: SourcePos | None = field(default=None, compare=False)

    @cached_property
    def deleted_nodes(self) -> tuple[str, ...]:
        return tuple(n.name for n in self.lhs.nodes if self.rhs.node(n.name) is None)

    @cached_property
    def created_nodes(self) -> tuple[PatternNode, ...]:
        return tuple(n for n in self.rhs.nodes if self.lhs.node(n.name) is None)

    @cached_property
    def agm_creation_order(self) -> tuple[str, ...]:
        """The created nodes' names in the order AGM's planner creates (and numbers) them: the
        iteration order of a Python 2 dict of the RHS names (grammar/agm_order.py), which a plan
        file must follow for AGM's plan checker to accept its ids."""
        return agm_creation_order([n.name for n in self.rhs.nodes], [n.name for n in self.lhs.nodes],
                                  [p.name for p in self.parameters])

    @cached_property
    def retyped_nodes(self) -> tuple[PatternNode, ...]:
        out = []
        for node in self.rhs.nodes:
            before = self.lhs.node(node.name)
            if before is not None and before.type != node.type:
                out.append(node)
        return tuple(out)

    @cached_property
    def removed_links(self) -> tuple[PatternLink, ...]:
        after = {link.key for link in self.rhs.links if not link.negated}
        return tuple(link for link in self.lhs.links if not link.negated and link.key not in after)

    @cached_property
    def added_links(self) -> tuple[PatternLink, ...]:
        before = {link.key for link in self.lhs.links if not link.negated}
        return tuple(link for link in self.rhs.links if not link.negated and link.key not in before)


@dataclass(frozen=True)
class ComboAtom:
    rule: str
    alias: str
    optional: bool = False


@dataclass(frozen=True)
class ComboRule:
    """AGM combo rule (``where:``). Parsed so that old files load; the planner does not apply them
    (AGM itself removed their implementation in 2017)."""

    name: str
    cost: float
    atoms: tuple[ComboAtom, ...]
    equivalences: tuple[tuple[tuple[str, str], ...], ...]
    active: bool = True
    pos: SourcePos | None = field(default=None, compare=False)


@dataclass(frozen=True)
class TypeTable:
    """Type hierarchy from a ``types`` section: each type's direct parents.

    A pattern node of type T matches world nodes of type T or of any subtype of T. Types not
    declared anywhere are roots (AGM files without a ``types`` section use them freely).
    """

    parents: Mapping[str, tuple[str, ...]] = field(default_factory=dict)

    def ancestors(self, type_name: str) -> frozenset[str]:
        """``type_name`` and every type it inherits from (transitively)."""
        seen = {type_name}
        stack = [type_name]
        while stack:
            for parent in self.parents.get(stack.pop(), ()):
                if parent not in seen:
                    seen.add(parent)
                    stack.append(parent)
        return frozenset(seen)

    def is_subtype(self, type_name: str, of: str) -> bool:
        return of == ANY_TYPE or of in self.ancestors(type_name)

    def matching_types(self, pattern_type: str, world_types: Iterable[str]) -> frozenset[str] | None:
        """World types a pattern node of ``pattern_type`` accepts; ``None`` means every type."""
        if pattern_type == ANY_TYPE:
            return None
        return frozenset(t for t in world_types if pattern_type in self.ancestors(t))


@dataclass(frozen=True)
class Grammar:
    name: str
    rules: tuple[Rule, ...]
    types: TypeTable = field(default_factory=TypeTable)
    file: str = "<string>"
    dialect: str = "native"  # "native" or "agm"
    properties: Mapping[str, str] = field(default_factory=dict)
    combos: tuple[ComboRule, ...] = ()
    includes: tuple[str, ...] = ()
    skipped_includes: tuple[str, ...] = ()  # include paths not read (``includes=False``)
    declared_types: bool = False  # a ``types`` section exists (then every type used must be declared)
    warnings: tuple[GrammarWarning, ...] = ()

    def rule(self, name: str) -> Rule:
        for rule in self.rules:
            if rule.name == name:
                return rule
        raise KeyError(f"grammar {self.name!r} has no rule {name!r}")


@dataclass(frozen=True)
class Target:
    """What the planner must make true: a pattern (constants name world nodes) plus conditions."""

    pattern: Pattern
    where: tuple[Expr, ...] = ()
    precondition: Formula | None = None
    file: str = "<string>"
    warnings: tuple[GrammarWarning, ...] = field(default=(), compare=False)
