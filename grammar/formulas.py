"""Meaning of AGM's prefix formulas: as conditions (``precondition``) and as effects (``effect``).

Semantics follow AGM's ``generateAGGLPlannerCode.py``:
- condition: a link atom ``(label a b)`` is true if that link exists; ``(= a b)`` if both names are
  bound to the same node; ``forall``/``exists`` range over every world node whose type is valid for
  the declared type (bound nodes included, not injective: write ``(not (= p q))`` to exclude);
  ``(when A B)`` is ``A`` implies ``B``.
- effect: a link atom adds the link, ``(not (label a b))`` removes it, ``and`` applies all,
  ``forall`` applies to every node, ``(when A B)`` applies ``B`` where ``A`` holds,
  ``create``/``delete``/``retype`` edit nodes.
Conditions inside effects are evaluated on the graph *before* the rule; the rule's own rewrite and
its effects are then applied together, every removal before every addition (PDDL semantics).

Why the "guarded forall" shortcut: effects such as ``(forall x:object (when (near robot x) ...))``
only act on nodes linked to a bound one; walking that link (or those links, for a ``when`` on an
``or`` of links) instead of every object keeps rule application cheap in large centres. The
result is the same as the plain loop, except for the order of iteration.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from itertools import product
from typing import assert_never

from grammar.errors import PlanningError
from grammar.matcher import Bindings, Matcher
from grammar.model import (
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
    VarDecl,
)
from grammar.world import Edge, State, StateEditor


@dataclass
class Changes:
    """Changes a rule makes, applied together: removals before additions (as in PDDL), so an
    effect that clears every ``near`` link does not undo the ``near`` link the rule adds."""

    remove_edges: list[Edge] = field(default_factory=list)
    add_edges: list[Edge] = field(default_factory=list)
    delete_nodes: list[int] = field(default_factory=list)
    retype: list[tuple[int, str]] = field(default_factory=list)


Effect = Callable[[State, Bindings, "Changes", StateEditor], None]
"""A compiled effect: records its changes for one application."""


class FormulaEvaluator:
    def __init__(self, matcher: Matcher) -> None:
        self.matcher = matcher
        self._guards: dict[tuple[int, str], tuple[Formula, list[tuple[FLink, bool]] | None]] = {}
        self._effects: dict[int, tuple[Formula, Callable[[State, Bindings, Changes, StateEditor], None]]] = {}

    # ------------------------------------------------------------------ quantifiers
    def _guard(self, body: Formula, var: str) -> list[tuple[FLink, bool]] | None:
        key = (id(body), var)
        found = self._guards.get(key)
        if found is None or found[0] is not body:
            found = self._guards[key] = (body, _guard_links(body, var))
        return found[1]

    def _domain(self, decl: VarDecl, body: Formula, state: State, b: Bindings) -> Iterable[int]:
        guards = self._guard(body, decl.name)
        if guards is not None and all((link.dst if forward else link.src) in b for link, forward in guards):
            if len(guards) == 1:
                link, forward = guards[0]
                linked = state.inn(b[link.dst], link.label) if forward else state.out(b[link.src], link.label)
                if not linked:
                    return ()
                return [n for n in linked if self.matcher.type_ok(state.type_of(n), decl.type)]
            nodes: dict[int, None] = {}
            for link, forward in guards:
                other = b[link.dst if forward else link.src]
                linked = state.inn(other, link.label) if forward else state.out(other, link.label)
                nodes.update((n, None) for n in linked)
            return [n for n in nodes if self.matcher.type_ok(state.type_of(n), decl.type)]
        return list(self.matcher.candidates_of_type(state, decl.type))

    def _assignments(self, decls: tuple[VarDecl, ...], body: Formula, state: State, b: Bindings
                     ) -> Iterator[Bindings]:
        if len(decls) == 1:
            for n in self._domain(decls[0], body, state, b):
                yield {**b, decls[0].name: n}
            return
        domains = [list(self.matcher.candidates_of_type(state, d.type)) for d in decls]
        for combo in product(*domains):
            inner = dict(b)
            inner.update({d.name: n for d, n in zip(decls, combo)})
            yield inner

    # ------------------------------------------------------------------ conditions
    def holds(self, formula: Formula, state: State, b: Bindings) -> bool:
        match formula:
            case FLink():
                s, d = b.get(formula.src), b.get(formula.dst)
                return s is not None and d is not None and state.has_edge(s, d, formula.label)
            case FSame():
                return b.get(formula.a) is not None and b.get(formula.a) == b.get(formula.b)
            case FNot():
                return not self.holds(formula.body, state, b)
            case FAnd():
                return all(self.holds(f, state, b) for f in formula.items)
            case FOr():
                return any(self.holds(f, state, b) for f in formula.items)
            case FWhen():
                return not self.holds(formula.condition, state, b) or self.holds(formula.then, state, b)
            case FForall():  # the guard shortcut is exact here: unlinked nodes satisfy (when ...)
                return all(self.holds(formula.body, state, inner)
                           for inner in self._assignments(formula.vars, formula.body, state, b))
            case FExists():
                return any(self.holds(formula.body, state, inner)
                           for inner in self._assignments(formula.vars, _NO_GUARD, state, b))
            case FCreate() | FDelete() | FRetype():
                raise PlanningError(f"{type(formula).__name__} cannot be used as a condition")
            case _:
                assert_never(formula)

    # ------------------------------------------------------------------ effects
    def collect(self, formula: Formula, state: State, b: Bindings, changes: Changes,
                editor: StateEditor) -> None:
        """Record an effect's changes; its conditions read ``state`` (the graph before the rule).
        ``create`` allocates the node at once (through ``editor``) so later atoms can use it."""
        match formula:
            case FLink():
                changes.add_edges.append((self._node(b, formula.src), self._node(b, formula.dst), formula.label))
            case FNot(body=FLink() as body):
                changes.remove_edges.append((self._node(b, body.src), self._node(b, body.dst), body.label))
            case FNot():
                raise PlanningError("(not ...) in an effect must wrap a link atom")
            case FAnd():
                for item in formula.items:
                    self.collect(item, state, b, changes, editor)
            case FWhen():
                if self.holds(formula.condition, state, b):
                    self.collect(formula.then, state, b, changes, editor)
            case FForall() if len(formula.vars) == 1:  # the common case, without a generator
                decl = formula.vars[0]
                for n in self._domain(decl, formula.body, state, b):
                    self.collect(formula.body, state, {**b, decl.name: n}, changes, editor)
            case FForall():
                for inner in list(self._assignments(formula.vars, formula.body, state, b)):
                    self.collect(formula.body, state, inner, changes, editor)
            case FCreate():
                b[formula.var] = editor.create_node(formula.type, formula.var)
            case FDelete():
                changes.delete_nodes.append(self._node(b, formula.var))
            case FRetype():
                changes.retype.append((self._node(b, formula.var), formula.type))
            case FOr() | FExists() | FSame():
                raise PlanningError(f"{type(formula).__name__} has no meaning in an effect")
            case _:
                assert_never(formula)

    # ------------------------------------------------------------------ compiled effects
    def apply_effect(self, formula: Formula, state: State, b: Bindings, changes: Changes,
                     editor: StateEditor) -> None:
        """``collect`` through closures built once per formula: the planner applies the same few
        effects thousands of times, and dispatching on the formula's class each time dominated."""
        key = id(formula)
        found = self._effects.get(key)
        if found is None or found[0] is not formula:
            found = self._effects[key] = (formula, self._compile_effect(formula))
        found[1](state, b, changes, editor)

    def _compile_effect(self, f: Formula) -> Effect:
        match f:
            case FLink():
                return self._add_link(f)
            case FNot(body=FLink() as link):
                return self._remove_link(link)
            case FAnd():
                parts = [self._compile_effect(item) for item in f.items]

                def both(state: State, b: Bindings, changes: Changes, editor: StateEditor) -> None:
                    for part in parts:
                        part(state, b, changes, editor)
                return both
            case FWhen():
                condition, then = self._compile_condition(f.condition), self._compile_effect(f.then)

                def when(state: State, b: Bindings, changes: Changes, editor: StateEditor) -> None:
                    if condition(state, b):
                        then(state, b, changes, editor)
                return when
            case FForall() if len(f.vars) == 1:
                return self._forall_one(f)
            case FNot() | FOr() | FForall() | FExists() | FSame() | FCreate() | FDelete() | FRetype():
                def generic(state: State, b: Bindings, changes: Changes, editor: StateEditor) -> None:
                    self.collect(f, state, b, changes, editor)  # interpreted (and its errors raised) as written
                return generic
            case _:
                assert_never(f)

    def _add_link(self, f: FLink) -> Effect:
        node, label, src, dst = self._node, f.label, f.src, f.dst

        def add(state: State, b: Bindings, changes: Changes, editor: StateEditor) -> None:
            changes.add_edges.append((node(b, src), node(b, dst), label))
        return add

    def _remove_link(self, f: FLink) -> Effect:
        node, label, src, dst = self._node, f.label, f.src, f.dst

        def remove(state: State, b: Bindings, changes: Changes, editor: StateEditor) -> None:
            changes.remove_edges.append((node(b, src), node(b, dst), label))
        return remove

    def _forall_one(self, f: FForall) -> Effect:
        """``(forall x:T body)``; with a guard ``(when (label a x) ...)`` it walks a's links."""
        decl, body = f.vars[0], f.body
        name, inner = decl.name, self._compile_effect(body)
        domain = self._domain
        guards = self._guard(body, name)
        if guards is not None and len(guards) == 1:
            link, forward = guards[0]
            anchor, label, wanted, type_ok = (link.dst if forward else link.src), link.label, decl.type, \
                self.matcher.type_ok

            def guarded(state: State, b: Bindings, changes: Changes, editor: StateEditor) -> None:
                a = b.get(anchor)
                if a is None:
                    for n in domain(decl, body, state, b):
                        inner(state, {**b, name: n}, changes, editor)
                    return
                linked = state.inn(a, label) if forward else state.out(a, label)
                for n in list(linked):
                    if type_ok(state.type_of(n), wanted):
                        inner(state, {**b, name: n}, changes, editor)
            return guarded

        def forall(state: State, b: Bindings, changes: Changes, editor: StateEditor) -> None:
            for n in domain(decl, body, state, b):
                inner(state, {**b, name: n}, changes, editor)
        return forall

    def _compile_condition(self, f: Formula) -> Callable[[State, Bindings], bool]:
        match f:
            case FLink():
                label, src, dst = f.label, f.src, f.dst

                def link(state: State, b: Bindings) -> bool:
                    s, d = b.get(src), b.get(dst)
                    return s is not None and d is not None and state.has_edge(s, d, label)
                return link
            case FNot():
                inner = self._compile_condition(f.body)
                return lambda state, b: not inner(state, b)
            case FAnd():
                parts = [self._compile_condition(item) for item in f.items]
                return lambda state, b: all(part(state, b) for part in parts)
            case FOr():
                parts = [self._compile_condition(item) for item in f.items]
                return lambda state, b: any(part(state, b) for part in parts)
            case FSame() | FWhen() | FForall() | FExists() | FCreate() | FDelete() | FRetype():
                return lambda state, b: self.holds(f, state, b)
            case _:
                assert_never(f)

    @staticmethod
    def _node(b: Bindings, name: str) -> int:
        try:
            return b[name]
        except KeyError:
            raise PlanningError(f"effect uses unbound variable {name!r}") from None


_NO_GUARD: Formula = FAnd(())  # a body that never enables the guard shortcut (exists needs every node)


def _link_of(atom: Formula, var: str) -> tuple[FLink, bool] | None:
    if isinstance(atom, FLink) and (atom.src == var) != (atom.dst == var):
        return atom, atom.src == var
    return None


def _guard_links(body: Formula, var: str) -> list[tuple[FLink, bool]] | None:
    """If ``body`` only does something where a link between ``var`` and another variable exists,
    those links (any one suffices): ``(when (label a var) ...)``, ``(when (and (label a var) ...)
    ...)``, ``(when (or (l1 a var) (l2 var b)) ...)``. Each item is (link, var is its source)."""
    if not isinstance(body, FWhen):
        return None
    condition = body.condition
    if isinstance(condition, FOr):
        found = [_link_of(atom, var) for atom in condition.items]
        links = [link for link in found if link is not None]
        return links if len(links) == len(found) else None
    atoms = condition.items if isinstance(condition, FAnd) else (condition,)
    for atom in atoms:
        link = _link_of(atom, var)
        if link is not None:
            return [link]
    return None
