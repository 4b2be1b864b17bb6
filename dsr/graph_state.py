"""GraphState: the replicated element states of one replica and the view derived from them.

Why its own class: the replicated truth is the CRDT state of each node and edge (one
ElementTable of each, dsr/table.py); everything a query needs (visible nodes, names, types,
adjacency, visible edges) is an index derived from it and kept in sync element by element, so
queries are O(1)/O(degree) and signals are computed exactly where the state changed.  Merging
a delta into an element and bringing the indexes in line is this class's one job, the same for
local writes and remote messages; DSRGraph (dsr/graph.py) adds the API around it: locking,
transactions, write checks, publishing, signals delivery.

Not thread-safe on its own: DSRGraph's lock guards every call.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

from dsr import crdt, wire
from dsr.crdt import ElementState
from dsr.model import Edge, Node, make_node
from dsr.names import NameIndex
from dsr.signals import Event, SignalHub
from dsr.table import ElementTable

EdgeKey = tuple[int, int, str]


@dataclass(slots=True)
class NodeView:
    """What the indexes keep of a visible node."""

    type: str
    name: str
    created: int


class GraphState:
    """Node and edge tables plus the indexes derived from them; merges queue signal events."""

    def __init__(self, signals: SignalHub) -> None:
        self.signals = signals
        self.node_table: ElementTable[int] = ElementTable("node", wire.node_entry)
        self.edge_table: ElementTable[EdgeKey] = ElementTable("edge", wire.edge_entry)
        #: the tables' state dicts (same objects)
        self.nodes = self.node_table.states
        self.edges = self.edge_table.states
        #: adjacency of every edge held (visible or not), by source and by destination
        self.outgoing: dict[int, set[EdgeKey]] = {}
        self.incoming: dict[int, set[EdgeKey]] = {}
        #: visible nodes, and the indexes over them
        self.view: dict[int, NodeView] = {}
        self.types: dict[str, set[int]] = {}
        self.names = NameIndex()
        #: visible edges (present, both ends visible), by type too
        self.visible_edges: set[EdgeKey] = set()
        self.edge_types: dict[str, set[EdgeKey]] = {}

    def node(self, node_id: int) -> Node:
        """Snapshot of a visible node (its shown name, its visible attributes)."""
        view = self.view[node_id]
        return make_node(node_id, view.type, self.names.shown(view.name, node_id),
                         self.nodes[node_id].visible_attrs())

    def edge(self, key: EdgeKey) -> Edge:
        """Snapshot of a held edge with its visible attributes."""
        return Edge(src=key[0], dst=key[1], type=key[2], attrs=self.edges[key].visible_attrs())

    def merge_node(self, node_id: int, delta: dict[str, Any], events: list[Event] | None) -> bool:
        """Merge a delta into one node's state (creating it) and sync the view; True if the
        state changed."""
        state = self.nodes.get(node_id)
        if state is None:
            state = self.nodes[node_id] = ElementState()
            self.node_table.dead.add(node_id)
        if len(delta) == 1 and "attrs" in delta:   # attribute-only: visibility cannot change
            changed, keys = crdt.merge_attrs(state, delta["attrs"])
            if keys and events is not None and node_id in self.view \
                    and self.signals.wants("node_updated"):
                events.append(("node_updated", (self.node(node_id), keys)))
            return changed
        changed, keys = crdt.merge_into(state, **delta)
        if changed:
            self.sync_node(node_id, keys, events)
        return changed

    def merge_edge(self, key: EdgeKey, delta: dict[str, Any], events: list[Event] | None) -> bool:
        """Merge a delta into one edge's state (creating it) and sync its view."""
        state = self.edges.get(key)
        if state is None:
            state = self.edges[key] = ElementState()
            self.index_edge(key)
        changed, keys = crdt.merge_into(state, **delta)
        if changed:
            self.sync_edge(key, keys, events)
        return changed

    def index_edge(self, key: EdgeKey) -> None:
        """Add an edge held (visible or not) to the adjacency indexes."""
        for index, end in ((self.outgoing, key[0]), (self.incoming, key[1])):
            ends = index.get(end)
            if ends is None:
                index[end] = {key}
            else:
                ends.add(key)

    def unlink_edge(self, key: EdgeKey) -> None:
        """An edge no longer held (undone): out of the indexes and of the view."""
        self.unindex_edge(key)
        self.sync_edge(key, [], None)

    def unindex_edge(self, key: EdgeKey) -> None:
        """Drop a forgotten edge from the adjacency indexes."""
        for index, end in ((self.outgoing, key[0]), (self.incoming, key[1])):
            keys = index.get(end)
            if keys is not None:
                keys.discard(key)
                if not keys:
                    del index[end]

    def sync_node(self, node_id: int, keys: list[str], events: list[Event] | None) -> None:
        """Bring the derived view of one node in line with its state; queue signals."""
        state = self.nodes.get(node_id)
        old = self.view.get(node_id)
        new = None
        if state is not None:
            present = state.present()
            self.node_table.settle(node_id, present)
            if present and state.meta is not None:
                hlc, _, (type_, name) = state.meta
                new = NodeView(type_, name, hlc)
        renamed: list[int] = []
        if old is not None and (new is None or new != old):
            self.types[old.type].discard(node_id)
            if not self.types[old.type]:
                del self.types[old.type]
            renamed += self.names.remove(old.name, node_id)
            del self.view[node_id]
        if new is not None and (old is None or new != old):
            self.types.setdefault(new.type, set()).add(node_id)
            renamed += self.names.add(new.name, node_id, new.created)
            self.view[node_id] = new
        signals = self.signals
        if old is None and new is not None:
            if events is not None and signals.wants("node_added"):
                events.append(("node_added", (self.node(node_id),)))
            self.sync_incident(node_id, events)
        elif old is not None and new is None:
            self.sync_incident(node_id, events)
            if events is not None and signals.wants("node_deleted"):
                events.append(("node_deleted", (node_id,)))
        elif old is not None and new is not None and events is not None \
                and signals.wants("node_updated"):
            changed = list(keys)
            if old.type != new.type:
                changed.append("type")
            if old.name != new.name:
                changed.append("name")
            if changed:
                events.append(("node_updated", (self.node(node_id), changed)))
        if renamed and events is not None and signals.wants("node_updated"):
            for other in dict.fromkeys(renamed):
                if other in self.view:
                    events.append(("node_updated", (self.node(other), ["name"])))

    def sync_incident(self, node_id: int, events: list[Event] | None) -> None:
        """Re-sync every edge from or to a node whose visibility changed."""
        for key in sorted(self.outgoing.get(node_id, set()) | self.incoming.get(node_id, set())):
            self.sync_edge(key, [], events)

    def sync_edge(self, key: EdgeKey, keys: list[str], events: list[Event] | None) -> None:
        """Bring the view of one edge in line with its state and its ends; queue signals."""
        state = self.edges.get(key)
        was = key in self.visible_edges
        present = state is not None and state.present()
        if state is not None:
            self.edge_table.settle(key, present)
        now = present and key[0] in self.view and key[1] in self.view
        if was and not now:
            self.visible_edges.discard(key)
            self.edge_types[key[2]].discard(key)
            if not self.edge_types[key[2]]:
                del self.edge_types[key[2]]
            if events is not None and self.signals.wants("edge_deleted"):
                events.append(("edge_deleted", key))
        elif now and not was:
            self.visible_edges.add(key)
            self.edge_types.setdefault(key[2], set()).add(key)
            if events is not None and self.signals.wants("edge_added"):
                events.append(("edge_added", (self.edge(key),)))
        elif now and keys and events is not None and self.signals.wants("edge_updated"):
            events.append(("edge_updated", (self.edge(key), list(keys))))

    def apply_nodes(self, entries: Iterable[tuple[int, ElementState]],
                     events: list[Event]) -> int:
        """Merge received node states: an unknown node's state is installed as decoded, an
        attribute update (the hot path) merges its registers, anything else goes through
        the general merge."""
        changed = 0
        nodes, view = self.nodes, self.view
        merge_attrs = crdt.merge_attrs
        want_updated = self.signals.wants("node_updated")
        for node_id, state in entries:
            current = nodes.get(node_id)
            if current is None:
                self.install_node(node_id, state, events)
                changed += 1
            elif state.meta is None and not state.add and not state.rem and not state.cleared:
                was_changed, keys = merge_attrs(current, state.attrs)   # inlined: hot path
                if was_changed:
                    changed += 1
                    if keys and want_updated and node_id in view:
                        events.append(("node_updated", (self.node(node_id), keys)))
            else:
                changed += self.merge_node(node_id, _as_delta(state), events)
        return changed

    def install_node(self, node_id: int, state: ElementState, events: list[Event]) -> None:
        """A node this replica did not hold: its decoded state becomes the replica's (a join
        does this 10^4 times, so the derived view is built directly, not through merge)."""
        if state.cleared:
            state.prune()
        self.nodes[node_id] = state
        meta = state.meta
        if meta is None or not state.present():
            self.node_table.dead.add(node_id)
            return
        hlc, _, (type_, name) = meta
        self.view[node_id] = NodeView(type_, name, hlc)
        of_type = self.types.get(type_)
        if of_type is None:
            self.types[type_] = {node_id}
        else:
            of_type.add(node_id)
        renamed = self.names.add(name, node_id, hlc)
        signals = self.signals
        if signals.wants("node_added"):
            events.append(("node_added", (self.node(node_id),)))
        if node_id in self.outgoing or node_id in self.incoming:
            self.sync_incident(node_id, events)
        if renamed and signals.wants("node_updated"):
            for other in dict.fromkeys(renamed):
                if other in self.view:
                    events.append(("node_updated", (self.node(other), ["name"])))

    def apply_edges(self, entries: Iterable[tuple[EdgeKey, ElementState]],
                     events: list[Event]) -> int:
        changed = 0
        edges = self.edges
        for key, state in entries:
            if key not in edges:
                self.install_edge(key, state, events)
                changed += 1
            else:
                changed += self.merge_edge(key, _as_delta(state, meta=False), events)
        return changed

    def install_edge(self, key: EdgeKey, state: ElementState, events: list[Event]) -> None:
        """An edge this replica did not hold: its decoded state becomes the replica's."""
        if state.cleared:
            state.prune()
        self.edges[key] = state
        self.index_edge(key)
        self.sync_edge(key, [], events)


    def compact(self, acked: Callable[[int, int], bool]) -> int:
        """Forget removed elements whose every stamp is acknowledged (DSRGraph.compact);
        returns how many."""
        removed = len(self.node_table.compact(acked))
        for key in self.edge_table.compact(acked):
            self.unindex_edge(key)
            removed += 1
        return removed

def _as_delta(state: ElementState, meta: bool = True) -> dict[str, Any]:
    """A received element state as the keyword arguments of a merge (crdt.merge_into)."""
    delta: dict[str, Any] = {"add": state.add.items(), "rem": state.rem.items(),
                             "cleared": state.cleared, "attrs": state.attrs}
    if meta:
        delta["meta"] = state.meta
    return delta
