"""The symbolic world the planner searches: an indexed base graph plus small immutable overlays.

Why overlays: a plan changes a handful of edges (where the robot is, whom it faces) in a graph of
hundreds of nodes. Copying the graph for every search state would dominate planning time; instead
each state stores only its difference from the base (edges added/removed, nodes created/deleted/
retyped, attributes set) in canonical form, so equal worlds reached by different plans are equal
states, and queries merge the base indexes with the (tiny) overlay.

Input is a ``networkx.MultiDiGraph`` whose nodes carry ``type`` and ``name`` attributes and whose
edges carry their type as attribute ``type`` (or as the edge key), as produced by
``DSRGraph.to_networkx()`` and ``agents.world.symbolic.symbolic_graph``.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Iterable, Iterator, Mapping
from dataclasses import dataclass
from typing import Any

import networkx as nx

from grammar.errors import PlanningError
from grammar.model import Value

Edge = tuple[int, int, str]
_EMPTY: dict[int, None] = {}


def freeze_value(value: Any) -> Value:
    """Attribute values must be hashable to be part of a state: lists become tuples."""
    if isinstance(value, list):
        return tuple(freeze_value(v) for v in value)
    if isinstance(value, dict):
        return tuple(sorted((str(k), freeze_value(v)) for k, v in value.items()))
    return value


class World:
    """Read-only indexed copy of a typed graph. Node ids are dense ints in graph insertion order,
    which keeps iteration (and hence plans) deterministic across processes."""

    def __init__(self, graph: nx.MultiDiGraph) -> None:
        self.keys: list[Hashable] = []
        self.index: dict[Hashable, int] = {}
        self.types: list[str] = []
        self.names: list[str] = []
        self.attrs: list[dict[str, Value]] = []
        self.by_type: dict[str, dict[int, None]] = {}
        self.by_name: dict[str, int] = {}
        self.out: dict[tuple[int, str], dict[int, None]] = {}
        self.inn: dict[tuple[int, str], dict[int, None]] = {}
        self.out_all: dict[int, list[tuple[int, str]]] = {}
        self.in_all: dict[int, list[tuple[int, str]]] = {}
        self.edge_attrs: dict[Edge, dict[str, Value]] = {}
        for key, data in graph.nodes(data=True):
            node_type = data.get("type")
            if not isinstance(node_type, str) or not node_type:
                raise PlanningError(f"world node {key!r} has no 'type' attribute")
            name = str(data.get("name", key))
            if name in self.by_name:
                raise PlanningError(f"two world nodes are named {name!r}; names must be unique")
            i = len(self.keys)
            self.keys.append(key)
            self.index[key] = i
            self.types.append(node_type)
            self.names.append(name)
            self.attrs.append({str(k): freeze_value(v) for k, v in data.items() if k not in ("type", "name")})
            self.by_type.setdefault(node_type, {})[i] = None
            self.by_name[name] = i
        for src, dst, key, data in graph.edges(keys=True, data=True):
            label = data.get("type", key if isinstance(key, str) else None)
            if not isinstance(label, str):
                raise PlanningError(f"edge {src!r}->{dst!r} has no 'type' (attribute or string key)")
            s, d = self.index[src], self.index[dst]
            if (s, d, label) in self.edge_attrs:
                continue
            self.out.setdefault((s, label), {})[d] = None
            self.inn.setdefault((d, label), {})[s] = None
            self.out_all.setdefault(s, []).append((d, label))
            self.in_all.setdefault(d, []).append((s, label))
            self.edge_attrs[(s, d, label)] = {str(k): freeze_value(v) for k, v in data.items() if k != "type"}
        self.size = len(self.keys)

    def initial_state(self) -> State:
        return State(self)


@dataclass(frozen=True)
class Overlay:
    """A state's canonical difference from the base world (hashable: it is the search key)."""

    added: frozenset[Edge] = frozenset()
    removed: frozenset[Edge] = frozenset()
    created: tuple[tuple[int, str, str], ...] = ()  # (id, type, name), ids ascending
    deleted: frozenset[int] = frozenset()
    retyped: frozenset[tuple[int, str]] = frozenset()
    attrs: frozenset[tuple[int, str, Value]] = frozenset()
    activated: frozenset[str] = frozenset()
    next_id: int = -1  # id of the next created node; -1 = world.size


_NO_CHANGE = Overlay()
_EMPTY_MAP: dict = {}  # shared, never written: the indexes of an overlay without node changes


class State:
    """One world in the search: base + overlay, with the overlay indexed for fast queries."""

    __slots__ = ("world", "overlay", "_added_out", "_added_in", "_types", "_names", "_attrs",
                 "_by_type_new", "_hash", "_views")

    def __init__(self, world: World, overlay: Overlay | None = None) -> None:
        self.world = world
        self.overlay = overlay or _NO_CHANGE
        ov = self.overlay
        self._added_out: dict[tuple[int, str], list[int]] = {}
        self._added_in: dict[tuple[int, str], list[int]] = {}
        if ov.added:
            for s, d, label in sorted(ov.added):  # sorted: iteration order must not depend on hashing
                self._added_out.setdefault((s, label), []).append(d)
                self._added_in.setdefault((d, label), []).append(s)
        if ov.created or ov.retyped:  # (most states only move links: share the empty indexes)
            self._types: dict[int, str] = {i: t for i, t, _ in ov.created}
            self._types.update(dict(ov.retyped))
            self._names: dict[int, str] = {i: n for i, _, n in ov.created}
            self._by_type_new: dict[str, list[int]] = {}
            for i in sorted(self._types):
                self._by_type_new.setdefault(self._types[i], []).append(i)
        else:
            self._types = self._names = _EMPTY_MAP
            self._by_type_new = _EMPTY_MAP
        if ov.attrs:
            self._attrs: dict[int, dict[str, Value]] = {}
            for i, key, value in ov.attrs:
                self._attrs.setdefault(i, {})[key] = value
        else:
            self._attrs = _EMPTY_MAP
        self._hash = hash(ov)
        self._views: dict[Hashable, tuple[object, ...]] | None = None

    def view(self, reader: Hashable, visible: Callable[[State, Edge], bool], attrs: frozenset[str]
             ) -> tuple[object, ...]:
        """The part of this state's difference from the base world that ``reader`` can see: the
        added and removed links ``visible`` accepts, the attributes it reads, every node change.
        States with equal views give a reader the same answers (cached per state and reader)."""
        views = self._views
        if views is None:
            views = self._views = {}
        found = views.get(reader)
        if found is None:
            ov = self.overlay
            found = (frozenset(e for e in ov.added if visible(self, e)),
                     frozenset(e for e in ov.removed if visible(self, e)),
                     frozenset(a for a in ov.attrs if a[1] in attrs) if ov.attrs else frozenset(),
                     ov.created, ov.deleted, ov.retyped)
            views[reader] = found
        return found

    # ------------------------------------------------------------------ identity
    def __hash__(self) -> int:
        return self._hash

    def __eq__(self, other: object) -> bool:
        return isinstance(other, State) and other.world is self.world and other.overlay == self.overlay

    # ------------------------------------------------------------------ nodes
    def exists(self, n: int) -> bool:
        if n in self.overlay.deleted:
            return False
        return n < self.world.size or n in self._names

    def type_of(self, n: int) -> str:
        return self._types.get(n) or self.world.types[n]

    def name_of(self, n: int) -> str:
        return self._names.get(n) or self.world.names[n]

    def attr(self, n: int, key: str) -> Value:
        if key == "name":
            return self.name_of(n)
        if key == "type":
            return self.type_of(n)
        own = self._attrs.get(n)
        if own is not None and key in own:
            return own[key]
        if n < self.world.size:
            return self.world.attrs[n].get(key)
        return None

    def attrs_of(self, n: int) -> dict[str, Value]:
        base = dict(self.world.attrs[n]) if n < self.world.size else {}
        base.update(self._attrs.get(n, {}))
        return base

    def nodes(self) -> Iterator[int]:
        deleted = self.overlay.deleted
        for i in range(self.world.size):
            if i not in deleted:
                yield i
        for i, _, _ in self.overlay.created:
            if i not in deleted:
                yield i

    def nodes_of_type(self, node_type: str) -> Iterator[int]:
        """Nodes whose current type is exactly ``node_type``."""
        deleted = self.overlay.deleted
        retyped = self._types
        for i in self.world.by_type.get(node_type, _EMPTY):
            if i not in deleted and (i not in retyped or retyped[i] == node_type):
                yield i
        for i in self._by_type_new.get(node_type, ()):
            if i not in deleted and i < self.world.size and self.world.types[i] == node_type:
                continue  # retyped back to its base type: already yielded above
            if i not in deleted:
                yield i

    def present_types(self) -> Iterable[str]:
        return (*self.world.by_type.keys(), *self._by_type_new.keys())

    def node_by_name(self, name: str) -> int | None:
        i = self.world.by_name.get(name)
        if i is not None:
            return i if self.exists(i) and self.name_of(i) == name else None
        for j, _, created_name in self.overlay.created:
            if created_name == name and self.exists(j):
                return j
        return None

    def node_by_constant(self, constant: str) -> int | None:
        """A constant in a pattern names a world node by name, or by its graph key (AGM ids)."""
        found = self.node_by_name(constant)
        if found is not None:
            return found
        for key in (constant, int(constant) if constant.lstrip("-").isdigit() else None):
            if key is not None and key in self.world.index:
                i = self.world.index[key]
                return i if self.exists(i) else None
        return None

    # ------------------------------------------------------------------ edges
    def out(self, n: int, label: str) -> Iterable[int]:
        base = self.world.out.get((n, label), _EMPTY)
        added = self._added_out.get((n, label))
        removed = self.overlay.removed
        if not removed and added is None:
            return base
        out = [d for d in base if (n, d, label) not in removed]
        if added:
            out.extend(added)
        return out

    def inn(self, n: int, label: str) -> Iterable[int]:
        base = self.world.inn.get((n, label), _EMPTY)
        added = self._added_in.get((n, label))
        removed = self.overlay.removed
        if not removed and added is None:
            return base
        out = [s for s in base if (s, n, label) not in removed]
        if added:
            out.extend(added)
        return out

    def has_edge(self, s: int, d: int, label: str) -> bool:
        e = (s, d, label)
        if e in self.overlay.added:
            return True
        return e in self.world.edge_attrs and e not in self.overlay.removed

    def edge_attr(self, s: int, d: int, label: str, key: str) -> Value:
        attrs = self.world.edge_attrs.get((s, d, label))
        return attrs.get(key) if attrs else None

    def edges_from(self, n: int) -> list[tuple[int, str]]:
        removed = self.overlay.removed
        out = [(d, l) for d, l in self.world.out_all.get(n, ()) if (n, d, l) not in removed]
        out.extend((d, l) for (s, d, l) in sorted(self.overlay.added) if s == n)
        return out

    def edges_to(self, n: int) -> list[tuple[int, str]]:
        removed = self.overlay.removed
        out = [(s, l) for s, l in self.world.in_all.get(n, ()) if (s, n, l) not in removed]
        out.extend((s, l) for (s, d, l) in sorted(self.overlay.added) if d == n)
        return out

    # ------------------------------------------------------------------ export
    def to_networkx(self) -> nx.MultiDiGraph:
        """The world of this state as a new graph (keys of base nodes kept; created nodes keyed by name)."""
        graph = nx.MultiDiGraph()
        key_of: dict[int, Hashable] = {}
        for n in self.nodes():
            key = self.world.keys[n] if n < self.world.size else self.name_of(n)
            key_of[n] = key
            graph.add_node(key, type=self.type_of(n), name=self.name_of(n), **self.attrs_of(n))
        for n in key_of:
            for d, label in self.edges_from(n):
                attrs = dict(self.world.edge_attrs.get((n, d, label), {}))
                graph.add_edge(key_of[n], key_of[d], key=label, type=label, **attrs)
        return graph


class StateEditor:
    """Mutable copy of an overlay; ``freeze()`` gives the canonical next state."""

    def __init__(self, state: State) -> None:
        self.state = state
        ov = state.overlay
        self.world = state.world
        # links are copied on first change (most rule applications change two or three)
        self.added: set[Edge] | frozenset[Edge] = ov.added
        self.removed: set[Edge] | frozenset[Edge] = ov.removed
        self.created = {i: (t, n) for i, t, n in ov.created}
        self.deleted = set(ov.deleted)
        self.retyped = dict(ov.retyped)
        self.attrs = {(i, k): v for i, k, v in ov.attrs}
        self.activated = set(ov.activated)
        self.next_id = ov.next_id if ov.next_id >= 0 else self.world.size

    def _own_links(self) -> None:
        if isinstance(self.added, frozenset):
            self.added = set(self.added)
        if isinstance(self.removed, frozenset):
            self.removed = set(self.removed)

    def _base_has(self, e: Edge) -> bool:
        return e in self.world.edge_attrs

    def add_edge(self, s: int, d: int, label: str) -> None:
        e = (s, d, label)
        if e in self.removed:
            self._own_links()
            self.removed.discard(e)  # type: ignore[union-attr]  # _own_links() made it a set
        elif e not in self.added and not self._base_has(e):
            self._own_links()
            self.added.add(e)  # type: ignore[union-attr]  # _own_links() made it a set

    def remove_edge(self, s: int, d: int, label: str) -> None:
        e = (s, d, label)
        if e in self.added:
            self._own_links()
            self.added.discard(e)  # type: ignore[union-attr]  # _own_links() made it a set
        elif e not in self.removed and self._base_has(e):
            self._own_links()
            self.removed.add(e)  # type: ignore[union-attr]  # _own_links() made it a set

    def create_node(self, node_type: str, name_hint: str) -> int:
        i = self.next_id
        self.next_id += 1
        self.created[i] = (node_type, f"{name_hint}#{i}")
        return i

    def delete_node(self, n: int, view: State) -> None:
        for d, label in view.edges_from(n):
            self.remove_edge(n, d, label)
        for s, label in view.edges_to(n):
            self.remove_edge(s, n, label)
        self.added = {e for e in self.added if e[0] != n and e[1] != n}
        self.removed = set(self.removed)
        if n in self.created:
            del self.created[n]
        else:
            self.deleted.add(n)
        self.retyped.pop(n, None)
        self.attrs = {k: v for k, v in self.attrs.items() if k[0] != n}

    def retype(self, n: int, node_type: str) -> None:
        if n in self.created:
            self.created[n] = (node_type, self.created[n][1])
        elif self.world.types[n] == node_type:
            self.retyped.pop(n, None)
        else:
            self.retyped[n] = node_type

    def set_attr(self, n: int, key: str, value: Value) -> None:
        value = freeze_value(value)
        if n < self.world.size and n not in self.created and key in self.world.attrs[n] \
                and self.world.attrs[n][key] == value and type(self.world.attrs[n][key]) is type(value):
            self.attrs.pop((n, key), None)
        else:
            self.attrs[(n, key)] = value

    def activate(self, rule_names: Iterable[str]) -> None:
        self.activated.update(rule_names)

    def freeze(self) -> State:
        ov = self.state.overlay
        overlay = Overlay(
            added=self.added if isinstance(self.added, frozenset) else frozenset(self.added),
            removed=self.removed if isinstance(self.removed, frozenset) else frozenset(self.removed),
            created=tuple((i, t, n) for i, (t, n) in sorted(self.created.items())) if self.created else (),
            deleted=ov.deleted if self.deleted == ov.deleted else frozenset(self.deleted),
            retyped=frozenset(self.retyped.items()) if self.retyped else frozenset(),
            attrs=frozenset((i, k, v) for (i, k), v in self.attrs.items()) if self.attrs else frozenset(),
            activated=ov.activated if self.activated == ov.activated else frozenset(self.activated),
            next_id=self.next_id if self.created or self.next_id != self.world.size else -1,
        )
        return State(self.world, overlay)


def graph_from_mapping(nodes: Mapping[str, Mapping[str, Any]],
                       edges: Iterable[tuple[str, str, str] | tuple[str, str, str, Mapping[str, Any]]]
                       ) -> nx.MultiDiGraph:
    """Build a symbolic graph keyed by node name: ``nodes = {name: {"type": t, ...attrs}}``,
    ``edges = [(src, dst, type[, attrs])]``. Handy for tests, examples and generated centres."""
    graph = nx.MultiDiGraph()
    for name, data in nodes.items():
        graph.add_node(name, name=name, **dict(data))
    for edge in edges:
        src, dst, label = edge[0], edge[1], edge[2]
        attrs = dict(edge[3]) if len(edge) > 3 else {}
        for end in (src, dst):
            if end not in graph:
                raise PlanningError(f"edge {src}->{dst}({label}) uses unknown node {end!r}")
        graph.add_edge(src, dst, key=label, type=label, **attrs)
    return graph
