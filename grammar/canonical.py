"""A search key for world states that ignores the names of the symbols the plan created.

Why: a rule that creates symbols (AGM's ``estorbo``, ``findObjectVisually``, ``recognizeObj*``)
numbers them in the order the search happened to apply it, so two plans that create the same
things in another order, or in other branches, reach worlds that differ only in the ids of the
new symbols. Searched as different states, they multiply: k interchangeable creations give k!
states, and the memory bound stopped searches AGM finishes (issue 43). Two such worlds are the
same world for every rule and target (rules and targets name world symbols, never a created
one's id), so the search keys states by a *canonical form up to renaming of created symbols*.

How: the world's own nodes keep their ids; the created ones are ordered by a colour that does
not depend on their ids (type, the rule variable that created them, their attributes), refined
by their links (colour refinement, i.e. 1-dimensional Weisfeiler-Leman: a node's colour becomes
its colour plus the multiset of (direction, label, colour or world id) of its links, until the
partition stops splitting). When the colours single every created node out, that order is the
canonical one. When some stay tied (interchangeable copies, or a structure refinement cannot
split), each node of the first smallest tied class is singled out in turn, recursively, and the
smallest encoding wins (individualisation-refinement, as nauty and bliss do); that is exact, and
equal keys then mean isomorphic worlds. The tree is bounded (``MAX_LEAVES``): past it the key is
the smallest encoding seen so far, still the encoding of a renaming of the state (so equal keys
still mean the same world: sound), only no longer guaranteed equal for every isomorphic world
(some duplicates are then searched twice, as before this module).

The encoding of a state under an order: the created symbols get ids ``world.size + position``
and names ``var#id``; every link, attribute and attribute value that names a created symbol is
rewritten accordingly; the parts of the overlay that only touch world symbols are kept as they
are. ``next_id`` (the id the next creation would get) is dropped: it only names future symbols.
"""

from __future__ import annotations

from collections.abc import Hashable
from typing import Any

from grammar.world import State

MAX_LEAVES = 64
"""Orders tried when colour refinement leaves created symbols tied (k interchangeable copies have
k! leaves, all giving the same encoding; 64 covers every tie of up to 4 copies in one class)."""


def _hint(name: str) -> str:
    """The rule variable a created symbol was named after (``o#12`` -> ``o``)."""
    return name.rsplit("#", 1)[0]


def canonical_key(state: State) -> Hashable:
    """The state's overlay, with the symbols it created renamed canonically (see the module doc)."""
    ov = state.overlay
    if not ov.created:
        return (ov.added, ov.removed, ov.deleted, ov.retyped, ov.attrs, ov.activated)
    canon = _Canon(state)
    return (ov.removed, ov.deleted, ov.retyped, ov.activated, frozenset(canon.world_edges), canon.best())


class _Canon:
    """Individualisation-refinement over the created symbols of one state."""

    def __init__(self, state: State) -> None:
        ov = state.overlay
        self.size = state.world.size
        self.created = {i: (t, _hint(n)) for i, t, n in ov.created}
        self.names = {n: i for i, _, n in ov.created}
        # links to world symbols never change colour: they go into the initial colour once; links
        # between created symbols are what refinement re-reads
        self.adj: dict[int, list[tuple[int, str, int]]] = {i: [] for i in self.created}
        self.fixed: dict[int, list[tuple[int, str, int]]] = {i: [] for i in self.created}
        self.world_edges: list[tuple[int, int, str]] = []
        self.created_edges: list[tuple[int, int, str]] = []
        for s, d, label in ov.added:
            s_new, d_new = s in self.created, d in self.created
            if s_new:
                (self.adj[s] if d_new else self.fixed[s]).append((0, label, d))
            if d_new:
                (self.adj[d] if s_new else self.fixed[d]).append((1, label, s))
            (self.created_edges if s_new or d_new else self.world_edges).append((s, d, label))
        self.own_attrs: dict[int, list[tuple[str, Any]]] = {i: [] for i in self.created}
        self.attrs = list(ov.attrs)
        for i, key, value in ov.attrs:
            if i in self.created:
                self.own_attrs[i].append((key, value))
        self.leaves = 0
        self.found: tuple[object, ...] | None = None

    # ------------------------------------------------------------------ colours
    def _value_mark(self, value: Any) -> str:
        """An attribute value as a colour sees it: a created symbol's name is just 'a created name'."""
        if isinstance(value, str) and value in self.names:
            return "<created>"
        if isinstance(value, tuple):
            return "(" + ",".join(self._value_mark(v) for v in value) + ")"
        return repr(value)

    def _initial(self) -> dict[int, int]:
        sigs = {i: repr((t, hint, sorted((k, self._value_mark(v)) for k, v in self.own_attrs[i]),
                         sorted(self.fixed[i])))
                for i, (t, hint) in self.created.items()}
        ranks = {s: r for r, s in enumerate(sorted(set(sigs.values())))}
        return {i: ranks[s] for i, s in sigs.items()}

    def _refine(self, colour: dict[int, int]) -> dict[int, int]:
        classes = len(set(colour.values()))
        while classes < len(colour):  # (every symbol singled out: nothing left to split)
            sigs: dict[int, tuple[object, ...]] = {}
            for i, links in self.adj.items():
                sigs[i] = (colour[i], tuple(sorted([(direction, label, colour[j]) for direction, label, j in links])))
            ranks = {s: r for r, s in enumerate(sorted(set(sigs.values())))}
            new = {i: ranks[s] for i, s in sigs.items()}
            if len(ranks) == classes:
                return new
            colour, classes = new, len(ranks)
        return colour

    # ------------------------------------------------------------------ search
    def best(self) -> tuple[object, ...]:
        self._search(self._initial())
        assert self.found is not None
        return self.found

    def _search(self, colour: dict[int, int]) -> None:
        colour = self._refine(colour)
        cells: dict[int, list[int]] = {}
        for i, c in colour.items():
            cells.setdefault(c, []).append(i)
        tied = [(len(members), c) for c, members in cells.items() if len(members) > 1]
        if not tied:
            self.leaves += 1
            order = sorted(self.created, key=colour.__getitem__)
            encoding = self._encode(order)
            if self.found is None or encoding < self.found:
                self.found = encoding
            return
        _, cell = min(tied)
        for node in sorted(cells[cell]):
            if self.leaves >= MAX_LEAVES and self.found is not None:
                return
            split = {i: 2 * c + 1 for i, c in colour.items()}
            split[node] = 2 * colour[node]  # singled out: just before its former classmates
            self._search(split)

    # ------------------------------------------------------------------ encoding
    def _encode(self, order: list[int]) -> tuple[object, ...]:
        new_id = {old: self.size + pos for pos, old in enumerate(order)}
        new_name = {name: f"{self.created[old][1]}#{new_id[old]}" for name, old in self.names.items()}

        def node(n: int) -> int:
            return new_id.get(n, n)

        def value(v: Any) -> str:
            if isinstance(v, str) and v in new_name:
                return repr(new_name[v])
            if isinstance(v, tuple):
                return "(" + ",".join(value(x) for x in v) + ")"
            return repr(v)

        created = tuple((new_id[i], t, hint) for i, (t, hint) in sorted(self.created.items(), key=lambda kv: new_id[kv[0]]))
        edges = tuple(sorted((node(s), node(d), label) for s, d, label in self.created_edges))
        attrs = tuple(sorted((node(i), key, value(v)) for i, key, v in self.attrs))
        return (created, edges, attrs)
