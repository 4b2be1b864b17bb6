"""ElementTable: the replicated CRDT states of one kind of element (nodes, or edges).

Why one generic table: a node (key: its id) and an edge (key: (src, dst, type)) are replicated
the same way (crdt.ElementState: add/remove stamps, registers, a removal receipt), so what is
done to their states is written once here: the undo record and the outgoing delta of a
transaction (`Changes`), the set of removed elements that tombstone compaction may forget, and
the per-element JSON cache that state replies are built from.  What differs between them, the
derived view (visible nodes, names and types; adjacency and visible edges), stays in
DSRGraph (dsr/graph.py), which owns one table of each.

Not thread-safe on its own: the graph's lock guards it.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Iterable
from dataclasses import dataclass, field
from typing import Any, Generic, Literal, TypeVar

import orjson

from dsr import crdt
from dsr.crdt import ElementState

K = TypeVar("K", bound=Hashable)
#: (state object, its rev when encoded, its JSON): see ElementTable.encoded_parts
Encoded = tuple[ElementState, int, bytes]


@dataclass
class Changes(Generic[K]):
    """What one transaction did to one table: states before (None: absent) and the delta."""

    undo: dict[K, ElementState | None] = field(default_factory=dict)
    out: dict[K, ElementState] = field(default_factory=dict)


class ElementTable(Generic[K]):
    """CRDT states of one kind of element, keyed by K (node id, or edge key)."""

    def __init__(self, kind: Literal["node", "edge"],
                 entry: Callable[[Any, ElementState], dict[str, object]]) -> None:
        #: "node" or "edge" (the names write policies and wire entries use)
        self.kind = kind
        #: key -> replicated state (visible or not); the graph indexes are derived from it
        self.states: dict[K, ElementState] = {}
        #: keys whose element is not present (removed, or only known from stray registers):
        #: the candidates of tombstone compaction
        self.dead: set[K] = set()
        self._entry = entry
        self._encoded: dict[K, Encoded] = {}

    def __len__(self) -> int:
        return len(self.states)

    # ------------------------------------------------------------------ transactions
    def record(self, changes: Changes[K], key: K) -> None:
        """Keep the state of `key` as it is before the transaction first touches it."""
        if key not in changes.undo:
            before = self.states.get(key)
            changes.undo[key] = before.copy() if before is not None else None

    @staticmethod
    def stage(changes: Changes[K], key: K, delta: dict[str, Any]) -> None:
        """Add a local change to the transaction's outgoing delta."""
        out = changes.out.get(key)
        if out is None:
            out = changes.out[key] = ElementState()
        crdt.merge_into(out, **delta)

    def restore(self, changes: Changes[K]) -> list[K]:
        """Put back the states recorded before the transaction; returns the keys touched
        (whose derived view the graph must bring back in line) and the keys dropped."""
        for key, before in changes.undo.items():
            if before is None:
                self.states.pop(key, None)
            else:
                self.states[key] = before
        return list(changes.undo)

    def entries(self, out: dict[K, ElementState]) -> list[dict[str, object]]:
        """Wire entries of a delta's states (dsr/wire.py node_entry / edge_entry)."""
        entry = self._entry
        return [entry(key, state) for key, state in out.items()]

    # ------------------------------------------------------------------ tombstones
    def settle(self, key: K, present: bool) -> None:
        """Track whether the element of `key` is present (compaction candidates)."""
        if present:
            self.dead.discard(key)
        else:
            self.dead.add(key)

    def compact(self, acked: Callable[[int, int], bool]) -> list[K]:
        """Forget removed elements whose every stamp every member has acknowledged; returns
        their keys (see DSRGraph.compact)."""
        removed: list[K] = []
        for key in list(self.dead):
            state = self.states.get(key)
            if state is None or state.present():
                self.dead.discard(key)
            elif state.cleared and settled(state, acked):
                del self.states[key]
                self.dead.discard(key)
                removed.append(key)
        return removed

    # ------------------------------------------------------------------ state replies
    def encoded_parts(self, keys: Iterable[K], fresh: dict[K, Encoded]) -> list[bytes]:
        """The JSON of each element of `keys` still held, from the cache when the element's
        state is the same object at the same rev (crdt.py bumps `rev` on every change),
        encoded anew otherwise; every one is put in `fresh` (see `keep_encoded`).

        Why a cache: in a live graph a few elements change between two joins (poses, people)
        while encoding all of them cost a 10k-node join most of its time."""
        out: list[bytes] = []
        dumps, entry, states, cache = orjson.dumps, self._entry, self.states, self._encoded
        for key in keys:
            state = states.get(key)
            if state is None:
                continue
            hit = cache.get(key)
            if hit is not None and hit[0] is state and hit[1] == state.rev:
                fresh[key] = hit
                out.append(hit[2])
            else:
                data = dumps(entry(key, state))
                fresh[key] = (state, state.rev, data)
                out.append(data)
        return out

    def keep_encoded(self, fresh: dict[K, Encoded]) -> None:
        """After a full state was encoded: only what it held stays cached (removed and
        compacted elements drop out)."""
        self._encoded = fresh

    def cached(self, key: K) -> Encoded | None:
        """The cached JSON of an element (tests of the cache)."""
        return self._encoded.get(key)


def settled(state: ElementState, acked: Callable[[int, int], bool]) -> bool:
    """Every stamp of `state` (adds, type/name, registers, removal receipt) is acknowledged."""
    for replica, hlc in state.add.items():
        if not acked(replica, hlc):
            return False
    if state.meta is not None and not acked(state.meta[1], state.meta[0]):
        return False
    return all(acked(reg[1], reg[0]) for reg in state.attrs.values())
