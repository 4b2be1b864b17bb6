"""DSRGraph: the local replica of the shared graph and the API agents call.

Why this structure: the replicated truth is the CRDT state (`crdt.ElementState` per node and
edge); everything an agent queries (visible nodes, names, types, adjacency) is an index derived
from it and kept in sync element by element, so queries are O(1)/O(degree) and signals are
computed exactly where the state changed.  Local writes are built as deltas and go through the
same merge code as remote deltas, so a replica cannot diverge from what it publishes.

Threading: one re-entrant lock guards the state.  A transaction holds it for its whole body
(remote merges wait, which gives the transaction isolation and makes rollback safe); signals are
queued and delivered by `dispatch()` on the caller's thread with no lock held.
"""

from __future__ import annotations

import hashlib
import secrets
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import orjson

from dsr import crdt, poses, wire
from dsr.crdt import ElementState
from dsr.errors import (DSRError, EdgeNotFoundError, InvalidAttributeError,
                        InvalidIdentifierError, NameTakenError, NodeNotFoundError, PoseError,
                        ReadOnlyGraphError, TransactionError, WriteRefusedError)
from dsr.limits import LIMITS, node_problem, value_bytes
from dsr.hlc import HybridLogicalClock
from dsr.model import (Attrs, Edge, Node, check_agent_name, check_attrs, check_name,
                       check_node_id, check_type_name, make_node)
from dsr.names import NameIndex
from dsr.outbox import Outbox, Outgoing
from dsr.signals import Event, PollSource, SignalHub, SpinPolicy

if TYPE_CHECKING:
    import networkx

EdgeKey = tuple[int, int, str]
Publisher = Callable[[bytes], None]
RT = "RT"


@dataclass(slots=True)
class _NodeView:
    type: str
    name: str
    created: int


@dataclass
class _Transaction:
    owner: int
    rollback: bool
    undo_nodes: dict[int, ElementState | None] = field(default_factory=dict)
    undo_edges: dict[EdgeKey, ElementState | None] = field(default_factory=dict)
    out_nodes: dict[int, ElementState] = field(default_factory=dict)
    out_edges: dict[EdgeKey, ElementState] = field(default_factory=dict)
    events: list[Event] = field(default_factory=list)


class IdAllocator:
    """64-bit node ids: a random nonzero 31-bit prefix per replica incarnation + a counter.

    Why random per incarnation: a restarted agent (same name) must never reuse the ids of its
    previous life; collisions between replicas are checked against the local state and skipped.
    """

    def __init__(self, prefix: int | None = None) -> None:
        self.prefix = prefix if prefix is not None else secrets.randbelow(2**31 - 1) + 1
        self._counter = 0

    def next(self, taken: Callable[[int], bool]) -> int:
        while True:
            self._counter += 1
            if self._counter >= 2**32:
                self.prefix = secrets.randbelow(2**31 - 1) + 1
                self._counter = 1
            node_id = (self.prefix << 32) | self._counter
            if not taken(node_id):
                return node_id


def _cannot_grow(values: Attrs, held: dict[str, Any]) -> bool:
    """Only scalar values (8 bytes each as the node limits count them) written over keys the
    node already has: they cannot take it over a node limit (dsr/limits.py node_problem)."""
    if len(values) == 1:                 # the common update: one key
        ((key, value),) = values.items()
        kind = type(value)
        return key in held and kind is not str and kind is not list
    if not values.keys() <= held.keys():
        return False
    for value in values.values():
        kind = type(value)
        if kind is str or kind is list:
            return False
    return True


def _settled(state: ElementState, acked: Callable[[int, int], bool]) -> bool:
    for replica, hlc in state.add.items():
        if not acked(replica, hlc):
            return False
    if state.meta is not None and not acked(state.meta[1], state.meta[0]):
        return False
    return all(acked(reg[1], reg[0]) for reg in state.attrs.values())


class DSRGraph:
    """A full replica of a DSR graph.  Offline until a transport (dsr.transport.join) attaches."""

    def __init__(self, agent: str, *, replica_id: int | None = None, read_only: bool = False,
                 graph: str = "chronav", clock: HybridLogicalClock | None = None,
                 spin: SpinPolicy | None = None) -> None:
        self.agent = check_agent_name(agent)
        self.graph_name = check_agent_name(graph, "graph")
        self.replica_id = replica_id if replica_id is not None else secrets.randbits(63) | 1
        self.read_only = read_only
        self.clock = clock or HybridLogicalClock()
        self.ids = IdAllocator()
        #: the transport that replicates this graph (dsr.transport.Replica), if any
        self.replica: Any = None
        self._publish: Publisher | None = None
        self._outbox: Outbox | None = None
        self._lock = threading.RLock()
        self._nodes: dict[int, ElementState] = {}
        self._edges: dict[EdgeKey, ElementState] = {}
        self._out: dict[int, set[EdgeKey]] = {}
        self._in: dict[int, set[EdgeKey]] = {}
        self._view: dict[int, _NodeView] = {}
        self._visible_edges: set[EdgeKey] = set()
        self._types: dict[str, set[int]] = {}
        self._edge_types: dict[str, set[EdgeKey]] = {}
        self._names = NameIndex()
        self._signals = SignalHub(spin)     # spin None: SpinPolicy.from_env()
        self._tx: _Transaction | None = None
        self._tx_depth = 0
        self._version = 0
        self._snapshot_cache: tuple[int, bytes] | None = None
        #: element -> (its state object, that object's rev, its JSON): see state_parts
        self._encoded_nodes: dict[int, tuple[ElementState, int, bytes]] = {}
        self._encoded_edges: dict[EdgeKey, tuple[ElementState, int, bytes]] = {}
        self._writers: dict[int, str] = {self.replica_id: self.agent}
        self._bound: dict[int, str] = {self.replica_id: self.agent}
        self._encoder = wire.DeltaEncoder(self.graph_name, self.agent, self.replica_id)
        #: elements that are not present (removed, or only known from stray registers): the
        #: candidates of tombstone compaction (compact())
        self._dead_nodes: set[int] = set()
        self._dead_edges: set[EdgeKey] = set()
        #: write policy checked on local writes (set by the transport when join() has one;
        #: None: every local write is allowed, as in library use)
        self.local_policy: Any = None
        #: largest HLC published through outboxes this graph has detached (published_hlc())
        self.sent_hlc = 0
        #: type of the node whose delete_node() is removing its edges (local policy checks)
        self._cascade: str | None = None

    # ------------------------------------------------------------------ reads
    def __len__(self) -> int:
        return len(self._view)

    def __contains__(self, node_id: object) -> bool:
        return node_id in self._view

    @property
    def version(self) -> int:
        """Increases on every state change (local or remote)."""
        return self._version

    def _node(self, node_id: int) -> Node:
        view = self._view[node_id]
        return make_node(node_id, view.type, self._names.shown(view.name, node_id),
                         self._nodes[node_id].visible_attrs())

    def _edge(self, key: EdgeKey) -> Edge:
        return Edge(src=key[0], dst=key[1], type=key[2], attrs=self._edges[key].visible_attrs())

    def get_node(self, node_id: int) -> Node | None:
        with self._lock:
            return self._node(node_id) if node_id in self._view else None

    def get_node_by_name(self, name: str) -> Node | None:
        with self._lock:
            node_id = self._names.lookup(name)
            return self._node(node_id) if node_id is not None else None

    def require_node(self, node: int | str) -> Node:
        """Node by id or shown name, or NodeNotFoundError (for agents that expect it)."""
        found = self.get_node(node) if isinstance(node, int) else self.get_node_by_name(node)
        if found is None:
            raise NodeNotFoundError(f"no node {node!r} in graph {self.graph_name!r}")
        return found

    def get_attr(self, node_id: int, key: str, default: Any = None) -> Any:
        """One attribute of a visible node without building a Node snapshot."""
        with self._lock:
            if node_id not in self._view:
                raise NodeNotFoundError(f"no node {node_id}")
            value = self._nodes[node_id].visible_value(key)
            return default if value is crdt._MISSING else value

    def nodes(self) -> list[Node]:
        with self._lock:
            return [self._node(i) for i in sorted(self._view)]

    def nodes_of_type(self, type: str) -> list[Node]:  # noqa: A002 - DSR vocabulary
        with self._lock:
            return [self._node(i) for i in sorted(self._types.get(type, ()))]

    def get_edge(self, src: int, dst: int, type: str) -> Edge | None:  # noqa: A002
        with self._lock:
            key = (src, dst, type)
            return self._edge(key) if key in self._visible_edges else None

    def edges(self) -> list[Edge]:
        with self._lock:
            return [self._edge(k) for k in sorted(self._visible_edges)]

    def edges_from(self, node_id: int, type: str | None = None) -> list[Edge]:  # noqa: A002
        with self._lock:
            return [self._edge(k) for k in sorted(self._out.get(node_id, ()))
                    if k in self._visible_edges and (type is None or k[2] == type)]

    def edges_to(self, node_id: int, type: str | None = None) -> list[Edge]:  # noqa: A002
        with self._lock:
            return [self._edge(k) for k in sorted(self._in.get(node_id, ()))
                    if k in self._visible_edges and (type is None or k[2] == type)]

    def edges_of_type(self, type: str) -> list[Edge]:  # noqa: A002
        with self._lock:
            return [self._edge(k) for k in sorted(self._edge_types.get(type, ()))]

    # ------------------------------------------------------------------ signals
    def connect(self, signal: str, callback: Callable[..., Any]) -> None:
        """Register a callback for one of dsr.signals.SIGNALS; it runs inside dispatch()."""
        self._signals.connect(signal, callback)

    def disconnect(self, signal: str, callback: Callable[..., Any]) -> None:
        self._signals.disconnect(signal, callback)

    def dispatch(self, timeout: float | None = 0.0) -> int:
        """Deliver queued signals on the calling thread (see SignalHub.dispatch)."""
        if self._tx is not None and self._tx.owner == threading.get_ident():
            raise TransactionError("dispatch() called inside a transaction; call it after")
        return self._signals.dispatch(timeout)

    def receive_while_polling(self, source: PollSource | None) -> None:
        """Transport hook: while dispatch() polls, it handles the deltas `source` received
        itself (dsr/signals.py, "Why the polling thread receives"; never inside the polling
        thread's own transaction: dispatch() refuses to run there).  None detaches."""
        self._signals.receive_from(source)

    def dispatch_stats(self) -> dict[str, float]:
        """How dispatch() has waited: polls that found a change, polls that gave up and slept,
        seconds spent polling (dsr.signals.SpinPolicy)."""
        hub = self._signals
        return {"poll_hits": hub.spin_hits, "poll_misses": hub.spin_misses,
                "poll_s": hub.spin_s}

    @property
    def callback_errors(self) -> int:
        return self._signals.callback_errors

    # ------------------------------------------------------------------ transactions
    @contextmanager
    def transaction(self) -> Iterator[DSRGraph]:
        """Group changes into one delta; on exception every change of the block is undone.

        Nested blocks join the outermost one.  The graph lock is held for the whole block, so
        keep it short (remote merges wait meanwhile).
        """
        with self._write(rollback=True):
            yield self

    @contextmanager
    def _write(self, rollback: bool) -> Iterator[_Transaction]:
        if self.read_only:
            raise ReadOnlyGraphError(f"graph replica of agent {self.agent!r} is read-only")
        self._lock.acquire()
        try:
            outer = self._tx is None
            if outer:
                self._tx = _Transaction(owner=threading.get_ident(), rollback=rollback)
            elif rollback and not self._tx.rollback:
                raise TransactionError("transaction opened inside a single write")
            self._tx_depth += 1
            tx = self._tx
            try:
                yield tx
            except BaseException:
                self._tx_depth -= 1
                if outer:
                    self._tx = None
                    self._tx_depth = 0
                    self._undo(tx)
                raise
            self._tx_depth -= 1
            out = None
            if outer:
                self._tx = None
                if tx.out_nodes or tx.out_edges:
                    self._check_size(tx)
                outbox = self._outbox
                out = self._commit(tx, outbox)
        finally:
            self._lock.release()
        if out is not None:
            outbox.send(out)   # type: ignore[union-attr]  # out comes from this outbox

    def _check_size(self, tx: _Transaction) -> None:
        """Refuse (and undo) a write whose delta receivers would drop as too large."""
        limit = LIMITS.max_delta_bytes
        estimate = 0
        for state in (*tx.out_nodes.values(), *tx.out_edges.values()):
            estimate += 200 + sum(value_bytes(reg[2]) + 60 for reg in state.attrs.values())
        if estimate * 2 < limit:
            return
        size = len(self._encoder.encode(
            [wire.node_entry(i, st) for i, st in tx.out_nodes.items()],
            [wire.edge_entry(k, st) for k, st in tx.out_edges.items()]))
        if size > limit:
            self._undo(tx)
            raise InvalidAttributeError(
                f"this write would make a delta of {size} bytes, over the limit of {limit} "
                "bytes per message (CHRONAV_DSR_MAX_DELTA_BYTES): split it into smaller "
                "transactions")

    def _check_node_limits(self, node_id: int, values: Attrs, fresh: bool = False) -> None:
        """Refuse a write that would take a node over max_node_attrs / max_node_bytes
        (dsr/limits.py): every receiver would drop its delta."""
        state = None if fresh else self._nodes.get(node_id)
        problem = node_problem(node_id, state.attrs if state is not None else None, values,
                               registers=False)
        if problem is not None:
            raise InvalidAttributeError(f"{problem[1]}: the other replicas would drop this "
                                        "write; keep large or many values out of one node")

    def _commit(self, tx: _Transaction, outbox: Outbox | None) -> Outgoing | None:
        self._signals.post(tx.events)
        if not tx.out_nodes and not tx.out_edges:
            return None
        self._version += 1
        return outbox.add(tx.out_nodes, tx.out_edges, self.clock.last) \
            if outbox is not None else None

    def _undo(self, tx: _Transaction) -> None:
        for node_id, before in tx.undo_nodes.items():
            if before is None:
                self._nodes.pop(node_id, None)
            else:
                self._nodes[node_id] = before
        for key, before_edge in tx.undo_edges.items():
            if before_edge is None:
                self._edges.pop(key, None)
                self._unlink_edge(key)
            else:
                self._edges[key] = before_edge
        for node_id in tx.undo_nodes:
            self._sync_node(node_id, [], None)
        for key in tx.undo_edges:
            self._sync_edge(key, [], None)
        self._version += 1

    # ------------------------------------------------------------------ local writes
    def insert_node(self, type: str, name: str, attrs: Attrs | None = None,  # noqa: A002
                    *, id: int | None = None) -> Node:  # noqa: A002
        """Create a node; `id` is generated unless given (e.g. by a world file)."""
        check_type_name(type)
        check_name(name)
        values = check_attrs(attrs) if attrs else {}
        if id is not None:
            check_node_id(id)
        with self._write(rollback=False) as tx:
            return self._insert_node(tx, type, name, values, id)

    def _insert_node(self, tx: _Transaction, type_: str, name: str, values: Attrs,
                     node_id: int | None) -> Node:
        holder = self._names.lookup(name)
        if holder is not None and holder != node_id:
            raise NameTakenError(f"node name {name!r} is already taken by node {holder}")
        if node_id is None:
            node_id = self.ids.next(lambda i: i in self._nodes)
        elif node_id in self._view:
            raise InvalidIdentifierError(f"node id {node_id} already exists; use update_node")
        if values:
            self._check_node_limits(node_id, values, fresh=True)
        hlc = self.clock.tick()
        me = self.replica_id
        self._local_node(tx, node_id, add=((me, hlc),), meta=(hlc, me, (type_, name)),
                         attrs={k: (hlc, me, v) for k, v in values.items()})
        return self._node(node_id)

    def update_node(self, node_id: int, attrs: Attrs) -> None:
        """Set attributes of a visible node (last writer wins per attribute).

        Outside a transaction this is the hot path of every agent (poses, sensor values), so
        it bypasses the transaction machinery: merge, encode one small delta, publish."""
        values = check_attrs(attrs)
        if self.read_only:
            raise ReadOnlyGraphError(f"graph replica of agent {self.agent!r} is read-only")
        out = None
        with self._lock:
            if self._tx is None:
                if node_id not in self._view:
                    raise NodeNotFoundError(f"cannot update node {node_id}: not in the graph")
                if self.local_policy is not None:
                    self._check_local("node", node_id, {"attrs": dict.fromkeys(values, (0, 0, 0))})
                if not _cannot_grow(values, self._nodes[node_id].attrs):
                    self._check_node_limits(node_id, values)
                hlc = self.clock.tick()
                me = self.replica_id
                regs = {k: (hlc, me, v) for k, v in values.items()}
                _, keys = crdt.merge_attrs(self._nodes[node_id], regs)
                event = None
                if keys and self._signals.wants("node_updated"):
                    event = ("node_updated", (self._node(node_id), keys))
                self._version += 1
                outbox = self._outbox
                if outbox is not None:
                    out = outbox.add_attrs(node_id, regs, hlc)
            else:
                self._update_node_tx(node_id, values)
                return
        try:
            if event is not None:
                self._signals.post([event])
        finally:
            if out is not None:
                outbox.send(out)   # type: ignore[union-attr]  # out comes from this outbox

    def update_nodes(self, updates: dict[int, Attrs]) -> None:
        """Set attributes of many visible nodes at once: one stamp, one delta, one lock.

        How a writer batches (docs/dsr_wire_format.md): receivers apply the whole batch at
        once, so thousands of updates cost them one message.  All-or-nothing: a missing node or
        a refused write raises before anything changes.  Inside a transaction it joins it."""
        checked = {node_id: check_attrs(attrs) for node_id, attrs in updates.items()}
        if self.read_only:
            raise ReadOnlyGraphError(f"graph replica of agent {self.agent!r} is read-only")
        if self._tx is not None and self._tx.owner == threading.get_ident():
            for node_id, values in checked.items():
                self._update_node_tx(node_id, values)
            return
        out = None
        with self._lock:
            if self._tx is not None:          # another thread's transaction: wait for it
                for node_id, values in checked.items():
                    self._update_node_tx(node_id, values)
                return
            view = self._view
            nodes = self._nodes
            for node_id, values in checked.items():
                if node_id not in view:
                    raise NodeNotFoundError(f"cannot update node {node_id}: not in the graph")
                if self.local_policy is not None:
                    self._check_local("node", node_id,
                                      {"attrs": dict.fromkeys(values, (0, 0, 0))})
                if not _cannot_grow(values, nodes[node_id].attrs):
                    self._check_node_limits(node_id, values)
            hlc = self.clock.tick()
            me = self.replica_id
            events: list[Event] = []
            merge_attrs = crdt.merge_attrs
            nodes = self._nodes
            want = self._signals.wants("node_updated")
            entries: list[dict[str, object]] = []
            for node_id, values in checked.items():
                regs = {k: (hlc, me, v) for k, v in values.items()}
                _, keys = merge_attrs(nodes[node_id], regs)
                if keys and want:
                    events.append(("node_updated", (self._node(node_id), keys)))
                entries.append({"id": node_id, "attrs": regs})
            if not entries:
                return
            self._version += 1
            outbox = self._outbox
            if outbox is not None:
                out = outbox.add_entries(entries, hlc)
        try:
            self._signals.post(events)
        finally:
            if out is not None:
                outbox.send(out)   # type: ignore[union-attr]  # out comes from this outbox

    def published_hlc(self) -> int:
        """Every local write stamped up to this HLC has been handed to the publisher."""
        outbox = self._outbox
        return max(self.sent_hlc, outbox.sent_top if outbox is not None else 0)

    def _update_node_tx(self, node_id: int, values: Attrs) -> None:
        with self._write(rollback=False) as tx:
            if node_id not in self._view:
                raise NodeNotFoundError(f"cannot update node {node_id}: not in the graph")
            self._check_node_limits(node_id, values)
            hlc = self.clock.tick()
            me = self.replica_id
            self._local_node(tx, node_id, attrs={k: (hlc, me, v) for k, v in values.items()})

    def delete_node(self, node_id: int) -> None:
        """Delete a node and every edge from or to it."""
        with self._write(rollback=False) as tx:
            if node_id not in self._view:
                raise NodeNotFoundError(f"cannot delete node {node_id}: not in the graph")
            if self.local_policy is not None:       # refuse before its edges are touched
                self._check_local("node", node_id, {"cleared": 1})
            hlc = self.clock.tick()
            receipt = crdt.removal_receipt(hlc, self.replica_id)
            self._cascade = self._view[node_id].type
            try:
                for key in sorted(self._out.get(node_id, set()) | self._in.get(node_id, set())):
                    edge = self._edges[key]
                    if edge.present():
                        self._local_edge(tx, key, rem=tuple(edge.add.items()), cleared=hlc,
                                         attrs=receipt)
            finally:
                self._cascade = None
            node = self._nodes[node_id]
            self._local_node(tx, node_id, rem=tuple(node.add.items()), cleared=hlc,
                             attrs=receipt)

    def insert_or_assign_edge(self, src: int, dst: int, type: str,  # noqa: A002
                              attrs: Attrs | None = None) -> Edge:
        """Create the edge (src, dst, type) or, if it exists, set the given attributes."""
        check_type_name(type, "edge type")
        values = check_attrs(attrs) if attrs else {}
        with self._write(rollback=False) as tx:
            for end in (src, dst):
                if end not in self._view:
                    raise NodeNotFoundError(f"cannot link {src}->{dst} ({type}): no node {end}")
            key = (src, dst, type)
            hlc = self.clock.tick()
            me = self.replica_id
            regs = {k: (hlc, me, v) for k, v in values.items()}
            if key in self._visible_edges:
                if regs:
                    self._local_edge(tx, key, attrs=regs)
            else:
                self._local_edge(tx, key, add=((me, hlc),), attrs=regs)
            return self._edge(key)

    def delete_edge(self, src: int, dst: int, type: str) -> None:  # noqa: A002
        with self._write(rollback=False) as tx:
            key = (src, dst, type)
            if key not in self._visible_edges:
                raise EdgeNotFoundError(f"cannot delete edge {src}->{dst} ({type}): not found")
            hlc = self.clock.tick()
            self._local_edge(tx, key, rem=tuple(self._edges[key].add.items()), cleared=hlc,
                             attrs=crdt.removal_receipt(hlc, self.replica_id))

    def _local_node(self, tx: _Transaction, node_id: int, **delta: Any) -> None:
        if self.local_policy is not None:
            self._check_local("node", node_id, delta)
        if node_id not in tx.undo_nodes:
            before = self._nodes.get(node_id)
            tx.undo_nodes[node_id] = before.copy() if before is not None else None
        self._merge_node(node_id, delta, tx.events)
        out = tx.out_nodes.get(node_id)
        if out is None:
            out = tx.out_nodes[node_id] = ElementState()
        crdt.merge_into(out, **delta)

    def _local_edge(self, tx: _Transaction, key: EdgeKey, **delta: Any) -> None:
        if self.local_policy is not None:
            self._check_local("edge", key, delta)
        if key not in tx.undo_edges:
            before = self._edges.get(key)
            tx.undo_edges[key] = before.copy() if before is not None else None
        self._merge_edge(key, delta, tx.events)
        out = tx.out_edges.get(key)
        if out is None:
            out = tx.out_edges[key] = ElementState()
        crdt.merge_into(out, **delta)

    def _check_local(self, element: str, key: Any, delta: dict[str, Any]) -> None:
        """Ask the write policy about a local write before it changes anything; a refusal
        raises WriteRefusedError naming the write (what every other replica would refuse)."""
        from dsr.writes import local_writes
        refusal = self.local_policy.refusal
        valued = getattr(self.local_policy, "valued", frozenset())
        for write in local_writes(self, self.agent, element, key, delta, self._cascade, valued):
            problem = refusal(write)
            if problem is not None:
                raise WriteRefusedError(problem)

    # ------------------------------------------------------------------ merge + derived view
    def _merge_node(self, node_id: int, delta: dict[str, Any], events: list[Event] | None) -> bool:
        state = self._nodes.get(node_id)
        if state is None:
            state = self._nodes[node_id] = ElementState()
            self._dead_nodes.add(node_id)
        if len(delta) == 1 and "attrs" in delta:   # attribute-only: visibility cannot change
            changed, keys = crdt.merge_attrs(state, delta["attrs"])
            if keys and events is not None and node_id in self._view \
                    and self._signals.wants("node_updated"):
                events.append(("node_updated", (self._node(node_id), keys)))
            return changed
        changed, keys = crdt.merge_into(state, **delta)
        if changed:
            self._sync_node(node_id, keys, events)
        return changed

    def _merge_edge(self, key: EdgeKey, delta: dict[str, Any], events: list[Event] | None) -> bool:
        state = self._edges.get(key)
        if state is None:
            state = self._edges[key] = ElementState()
            self._out.setdefault(key[0], set()).add(key)
            self._in.setdefault(key[1], set()).add(key)
        changed, keys = crdt.merge_into(state, **delta)
        if changed:
            self._sync_edge(key, keys, events)
        return changed

    def _unlink_edge(self, key: EdgeKey) -> None:
        for index, end in ((self._out, key[0]), (self._in, key[1])):
            keys = index.get(end)
            if keys is not None:
                keys.discard(key)
                if not keys:
                    del index[end]
        self._sync_edge(key, [], None)

    def _sync_node(self, node_id: int, keys: list[str], events: list[Event] | None) -> None:
        """Bring the derived view of one node in line with its state; queue signals."""
        state = self._nodes.get(node_id)
        old = self._view.get(node_id)
        new = None
        if state is not None:
            if state.present():
                self._dead_nodes.discard(node_id)
                if state.meta is not None:
                    hlc, _, (type_, name) = state.meta
                    new = _NodeView(type_, name, hlc)
            else:
                self._dead_nodes.add(node_id)
        renamed: list[int] = []
        if old is not None and (new is None or new != old):
            self._types[old.type].discard(node_id)
            if not self._types[old.type]:
                del self._types[old.type]
            renamed += self._names.remove(old.name, node_id)
            del self._view[node_id]
        if new is not None and (old is None or new != old):
            self._types.setdefault(new.type, set()).add(node_id)
            renamed += self._names.add(new.name, node_id, new.created)
            self._view[node_id] = new
        want = events is not None
        signals = self._signals
        if old is None and new is not None:
            if want and signals.wants("node_added"):
                events.append(("node_added", (self._node(node_id),)))
            self._sync_incident(node_id, events)
        elif old is not None and new is None:
            self._sync_incident(node_id, events)
            if want and signals.wants("node_deleted"):
                events.append(("node_deleted", (node_id,)))
        elif old is not None and new is not None and want and signals.wants("node_updated"):
            changed = list(keys)
            if old.type != new.type:
                changed.append("type")
            if old.name != new.name:
                changed.append("name")
            if changed:
                events.append(("node_updated", (self._node(node_id), changed)))
        if renamed and want and signals.wants("node_updated"):
            for other in dict.fromkeys(renamed):
                if other in self._view:
                    events.append(("node_updated", (self._node(other), ["name"])))

    def _sync_incident(self, node_id: int, events: list[Event] | None) -> None:
        for key in sorted(self._out.get(node_id, set()) | self._in.get(node_id, set())):
            self._sync_edge(key, [], events)

    def _sync_edge(self, key: EdgeKey, keys: list[str], events: list[Event] | None) -> None:
        state = self._edges.get(key)
        was = key in self._visible_edges
        present = state is not None and state.present()
        if state is not None:
            if present:
                self._dead_edges.discard(key)
            else:
                self._dead_edges.add(key)
        now = present and key[0] in self._view and key[1] in self._view
        if was and not now:
            self._visible_edges.discard(key)
            self._edge_types[key[2]].discard(key)
            if not self._edge_types[key[2]]:
                del self._edge_types[key[2]]
            if events is not None and self._signals.wants("edge_deleted"):
                events.append(("edge_deleted", key))
        elif now and not was:
            self._visible_edges.add(key)
            self._edge_types.setdefault(key[2], set()).add(key)
            if events is not None and self._signals.wants("edge_added"):
                events.append(("edge_added", (self._edge(key),)))
        elif now and keys and events is not None and self._signals.wants("edge_updated"):
            events.append(("edge_updated", (self._edge(key), list(keys))))

    # ------------------------------------------------------------------ replication hooks
    def attach(self, publish: Publisher | None, *, linger_s: float = 0.0) -> None:
        """Called by the transport: where encoded local deltas go (None = offline).

        Deltas written in quick succession are coalesced (see outbox.py); `linger_s=0`
        publishes every delta on its own.  Detaching flushes what is pending."""
        with self._lock:
            old, self._outbox = self._outbox, None
            self._publish = publish
            if publish is not None:
                self._outbox = Outbox(self._encoder, publish, linger_s=linger_s)
        if old is not None:
            old.close()
            self.sent_hlc = max(self.sent_hlc, old.sent_top)

    def flush(self) -> None:
        """Publish coalesced deltas now instead of within the linger time."""
        outbox = self._outbox
        if outbox is not None:
            outbox.flush()

    def apply_message(self, message: wire.Decoded) -> int:
        """Merge a validated remote delta or state; returns how many elements changed."""
        if self._tx is not None and self._tx.owner == threading.get_ident():
            raise TransactionError("apply_message() inside a local transaction")
        with self._lock:
            top = message.top_hlc
            if top:
                self.clock.observe(top)
            # whoever hands a message to apply_message vouches for its writers (the transport
            # judges a state's table itself and passes none: dsr/transport.py _note_writers)
            bound, writers = self._bound, self._writers
            for replica, agent in message.writers.items():
                if int(replica) not in bound:
                    bound[int(replica)] = writers[int(replica)] = agent
            if message.kind == "delta" and message.replica not in bound:
                bound[message.replica] = writers[message.replica] = message.agent
            events: list[Event] = []
            changed = 0
            nodes, edges = self._nodes, self._edges
            view = self._view
            want_updated = self._signals.wants("node_updated")
            merge_attrs = crdt.merge_attrs
            types, names = self._types, self._names
            wants_added = self._signals.wants("node_added")
            out_index, in_index = self._out, self._in
            for node_id, state in message.nodes:
                current = nodes.get(node_id)
                if current is None:        # unknown element: the decoded state is installed
                    if state.cleared:
                        state.prune()
                    nodes[node_id] = state
                    changed += 1
                    meta = state.meta
                    if meta is None or not state.present():
                        self._dead_nodes.add(node_id)
                        continue
                    hlc, _, (type_, name) = meta      # a new visible node (a join: 10^4 times)
                    view[node_id] = _NodeView(type_, name, hlc)
                    of_type = types.get(type_)
                    if of_type is None:
                        types[type_] = {node_id}
                    else:
                        of_type.add(node_id)
                    renamed = names.add(name, node_id, hlc)
                    if wants_added:
                        events.append(("node_added", (self._node(node_id),)))
                    if node_id in out_index or node_id in in_index:
                        self._sync_incident(node_id, events)
                    if renamed and self._signals.wants("node_updated"):
                        for other in dict.fromkeys(renamed):
                            if other in view:
                                events.append(("node_updated", (self._node(other), ["name"])))
                elif state.meta is None and not state.add and not state.rem \
                        and not state.cleared:        # an update: the hot path, inlined
                    was_changed, keys = merge_attrs(current, state.attrs)
                    if was_changed:
                        changed += 1
                        if keys and want_updated and node_id in view:
                            events.append(("node_updated", (self._node(node_id), keys)))
                else:
                    changed += self._merge_node(node_id, {
                        "add": state.add.items(), "rem": state.rem.items(),
                        "cleared": state.cleared, "meta": state.meta, "attrs": state.attrs},
                        events)
            for key, state in message.edges:
                if key not in edges:
                    if state.cleared:
                        state.prune()
                    edges[key] = state
                    src, dst = key[0], key[1]
                    ends = out_index.get(src)
                    if ends is None:
                        out_index[src] = {key}
                    else:
                        ends.add(key)
                    ends = in_index.get(dst)
                    if ends is None:
                        in_index[dst] = {key}
                    else:
                        ends.add(key)
                    self._sync_edge(key, [], events)
                    changed += 1
                else:
                    changed += self._merge_edge(key, {
                        "add": state.add.items(), "rem": state.rem.items(),
                        "cleared": state.cleared, "attrs": state.attrs}, events)
            if changed:
                self._version += 1
            self._signals.post(events)
            return changed

    def element_state(self, element: str, key: int | EdgeKey) -> ElementState | None:
        """The replicated CRDT state of a node (key: id) or edge (key: (src, dst, type)), for
        write policies; callers must not mutate it."""
        return (self._nodes if element == "node" else self._edges).get(key)  # type: ignore[call-overload]

    def node_type_of(self, node_id: int) -> str | None:
        """Type from the replicated state, even for a node not visible (for write policies)."""
        state = self._nodes.get(node_id)
        return state.meta[2][0] if state is not None and state.meta is not None else None

    def writer_agent(self, replica: int) -> str | None:
        """The agent a replica id writes for, as far as this replica knows (first-hand or
        relayed by a state's `writers` table)."""
        return self._writers.get(replica)

    def bound_agent(self, replica: int) -> str | None:
        """The agent of a replica id known first-hand: from a message on that agent's own key,
        or vouched for by that agent's own state (dsr/state_trust.py)."""
        return self._bound.get(replica)

    def note_writer(self, replica: int, agent: str) -> None:
        """Record a first-hand binding replica id -> agent (it replaces a relayed one: what
        the agent's own key says beats what a relay said)."""
        if self._bound.get(replica) != agent:
            with self._lock:
                if replica not in self._bound:
                    self._bound[replica] = agent
                    self._writers[replica] = agent

    def note_relayed_writer(self, replica: int, agent: str) -> None:
        """Record a binding only relayed by another member's state (an agent that is not
        running): used to attribute that replica's writes to the write policy, never served
        in this replica's own state replies (it proves nothing: dsr/state_trust.py)."""
        if replica not in self._writers:
            with self._lock:
                self._writers.setdefault(replica, agent)

    def served_writers(self) -> dict[int, str]:
        """The `writers` table of this replica's state replies: only bindings it can prove
        (first-hand, vouched for by the agent itself, or taken from the state it joined
        with), never a claim it merely relayed or deferred."""
        with self._lock:
            return dict(self._bound)

    def state_message(self, seen: dict[int, int] | None = None) -> bytes:
        """Full CRDT state (uncompacted tombstones included) as a "state" message, stamped
        with this replica's clock and watermarks `seen` (see dsr/transport.py); cached per
        version (a cached reply's clock and watermarks are older, hence still true)."""
        with self._lock:
            cache = self._snapshot_cache
            if cache is not None and cache[0] == self._version:
                return cache[1]
            clock = self.clock.last or self.clock.tick()   # never 0: 0 means "not the last part"
            payload = wire.encode(kind="state", graph=self.graph_name, agent=self.agent,
                                  replica=self.replica_id, nodes=self._nodes.items(),
                                  edges=self._edges.items(), writers=self._bound,
                                  clock=clock, seen={**(seen or {}), self.replica_id: clock})
            self._snapshot_cache = (self._version, payload)
            return payload

    def state_parts(self, seen: dict[int, int] | None = None,
                    per_part: int = 2000) -> Iterator[bytes]:
        """The state as several "state" messages of at most `per_part` elements (nodes
        first), produced one by one: the transport replies each part as soon as it is encoded,
        so encoding here, transfer and decoding at the joiner overlap (join time).  Each part
        is a valid state (a join of element states); the last one carries `clock` and `seen`
        (only once every part has been merged does the receiver hold what they describe).
        The graph lock is held per part, not for the whole state.

        Each element's JSON is cached with the state object and its `rev` (crdt.py bumps it on
        every change): in a live graph a few elements change between two joins (poses, people)
        while encoding all of them cost a 10k-node join most of its time."""
        with self._lock:
            clock = self.clock.last or self.clock.tick()   # never 0: 0 means "not the last part"
            node_ids, edge_keys = list(self._nodes), list(self._edges)
            writers = dict(self._bound)
        seen = {**(seen or {}), self.replica_id: clock}
        chunks: list[tuple[list[int], list[EdgeKey]]] = []
        for start in range(0, len(node_ids), per_part):
            chunks.append((node_ids[start:start + per_part], []))
        for start in range(0, len(edge_keys), per_part):
            chunks.append(([], edge_keys[start:start + per_part]))
        if not chunks:
            chunks.append(([], []))
        node_cache, edge_cache = self._encoded_nodes, self._encoded_edges
        fresh_nodes: dict[int, tuple[ElementState, int, bytes]] = {}
        fresh_edges: dict[EdgeKey, tuple[ElementState, int, bytes]] = {}
        for index, (ids, keys) in enumerate(chunks):
            last = index == len(chunks) - 1
            with self._lock:
                node_parts = _encoded(self._nodes, ids, node_cache, fresh_nodes, wire.node_entry)
                edge_parts = _encoded(self._edges, keys, edge_cache, fresh_edges, wire.edge_entry)
                payload = wire.encode_parts(
                    kind="state", graph=self.graph_name, agent=self.agent,
                    replica=self.replica_id, nodes=node_parts, edges=edge_parts,
                    writers=writers, clock=clock if last else 0, seen=seen if last else None)
            yield payload
        # only what this state held is kept (removed and compacted elements drop out)
        self._encoded_nodes, self._encoded_edges = fresh_nodes, fresh_edges

    def compact(self, acked: Callable[[int, int], bool]) -> int:
        """Forget removed elements whose removal every member has seen; returns how many.

        `acked(replica, hlc)` says whether every member holds every write `replica` stamped up
        to `hlc`.  An element is forgotten when it is not present, carries a removal, and every
        stamp in it (adds, type/name, registers, the removal receipt) is acknowledged: no
        member can then send an add the removal did not observe, so forgetting it changes no
        replica's view (docs/dsr_wire_format.md, "Tombstones")."""
        with self._lock:
            if self._tx is not None:
                return 0
            removed = 0
            for node_id in list(self._dead_nodes):
                state = self._nodes.get(node_id)
                if state is None or state.present():
                    self._dead_nodes.discard(node_id)
                elif state.cleared and _settled(state, acked):
                    del self._nodes[node_id]
                    self._dead_nodes.discard(node_id)
                    removed += 1
            for key in list(self._dead_edges):
                edge = self._edges.get(key)
                if edge is None or edge.present():
                    self._dead_edges.discard(key)
                elif edge.cleared and _settled(edge, acked):
                    del self._edges[key]
                    self._dead_edges.discard(key)
                    for index, end in ((self._out, key[0]), (self._in, key[1])):
                        keys = index.get(end)
                        if keys is not None:
                            keys.discard(key)
                            if not keys:
                                del index[end]
                    removed += 1
            if removed:
                self._version += 1
            return removed

    def tombstones(self) -> int:
        """How many removed elements this replica still remembers."""
        return len(self._dead_nodes) + len(self._dead_edges)

    def state_equals(self, other: DSRGraph) -> bool:
        """True if both replicas hold the same CRDT state (tests)."""
        with self._lock:
            return self._nodes == other._nodes and self._edges == other._edges

    # ------------------------------------------------------------------ derived outputs
    def rt_parent(self, node_id: int) -> Edge | None:
        """The RT edge placing `node_id` in its parent.  If concurrent re-parenting left
        several, the most recently added one wins (same choice on every replica)."""
        with self._lock:
            keys = [k for k in self._in.get(node_id, ()) if k[2] == RT and k in self._visible_edges]
            if not keys:
                return None
            best = max(keys, key=lambda k: (max(self._edges[k].add.values()), k))
            return self._edge(best)

    def world_pose(self, node_id: int) -> poses.Pose:
        """(x, y, theta) of a node in the root frame, composing RT edges up to a node without
        an RT parent (the `world` node)."""
        with self._lock:
            if node_id not in self._view:
                raise NodeNotFoundError(f"world_pose: no node {node_id}")
            chain: list[poses.Pose] = []
            seen = {node_id}
            current = node_id
            while True:
                edge = self.rt_parent(current)
                if edge is None:
                    break
                try:
                    chain.append((float(edge.attrs["x"]), float(edge.attrs["y"]),
                                  float(edge.attrs["theta"])))
                except (KeyError, TypeError, ValueError):
                    raise PoseError(f"RT edge {edge.src}->{edge.dst} needs float x, y, theta; "
                                    f"has {sorted(edge.attrs)}") from None
                if edge.src in seen:
                    raise PoseError(f"RT cycle through node {edge.src}")
                seen.add(edge.src)
                current = edge.src
            return poses.compose_chain(reversed(chain))

    def to_networkx(self) -> networkx.MultiDiGraph:
        """Copy of the visible graph: nodes keyed by id with data {**attrs, type, name}
        (type/name win over attributes of the same key); edges keyed by edge type."""
        import networkx as nx
        graph = nx.MultiDiGraph(name=self.graph_name)
        with self._lock:
            for node in (self._node(i) for i in self._view):
                graph.add_node(node.id, **{**node.attrs, "type": node.type, "name": node.name})
            for key in self._visible_edges:
                graph.add_edge(key[0], key[1], key=key[2],
                               **{**self._edges[key].visible_attrs(), "type": key[2]})
        return graph

    def to_document(self) -> dict[str, Any]:
        """The visible graph as a plain dict in the graph-file format (files.py)."""
        from dsr.files import FORMAT
        with self._lock:
            return {"format": FORMAT,
                    "nodes": [{"id": n.id, "type": n.type, "name": n.name, "attrs": n.attrs}
                              for n in self.nodes()],
                    "edges": [{"src": e.src, "dst": e.dst, "type": e.type, "attrs": e.attrs}
                              for e in self.edges()]}

    def to_json(self, indent: bool = False) -> str:
        option = orjson.OPT_SORT_KEYS | (orjson.OPT_INDENT_2 if indent else 0)
        return orjson.dumps(self.to_document(), option=option).decode()

    def digest(self) -> str:
        """SHA-256 of the canonical visible graph: equal digests = identical graphs."""
        return hashlib.sha256(self.to_json().encode()).hexdigest()

    @classmethod
    def from_json(cls, text: str | bytes, agent: str, source: str = "<json>",
                  **kwargs: Any) -> DSRGraph:
        """New offline graph holding the nodes and edges of a graph document."""
        graph = cls(agent, **kwargs)
        graph.load_json(text, source=source)
        return graph

    def load_json(self, text: str | bytes, source: str = "<json>") -> list[int]:
        """Insert a graph document into this graph in one transaction; returns node ids."""
        from dsr.files import parse_document
        document = parse_document(text, source)
        with self.transaction() as tx_graph:
            return tx_graph._load_document(document, source)

    def _load_document(self, document: Any, source: str) -> list[int]:
        from dsr.errors import GraphFileError
        tx = self._tx
        assert tx is not None
        ids: list[int] = []
        by_name: dict[str, int] = {}
        for index, node in enumerate(document.nodes):
            try:
                check_name(node.name, allow_hash=True)
                created = self._insert_node(tx, node.type, node.name, dict(node.attrs), node.id)
            except DSRError as exc:
                raise GraphFileError(f"{source}: nodes[{index}] ({node.name!r}): {exc}") from None
            ids.append(created.id)
            by_name[node.name] = created.id
        for index, edge in enumerate(document.edges):
            ends = []
            for end in (edge.src, edge.dst):
                if isinstance(end, str):
                    found = by_name.get(end) or self._names.lookup(end)
                    if found is None:
                        raise GraphFileError(f"{source}: edges[{index}]: unknown node name {end!r}")
                    ends.append(found)
                else:
                    ends.append(end)
            try:
                self.insert_or_assign_edge(ends[0], ends[1], edge.type, dict(edge.attrs))
            except DSRError as exc:
                raise GraphFileError(f"{source}: edges[{index}]: {exc}") from None
        return ids

    def save(self, path: str) -> None:
        from pathlib import Path
        Path(path).write_text(self.to_json(indent=True) + "\n", encoding="utf-8")

    @classmethod
    def load(cls, path: str, agent: str, **kwargs: Any) -> DSRGraph:
        from pathlib import Path

        from dsr.errors import GraphFileError
        try:
            text = Path(path).read_bytes()
        except OSError as exc:
            raise GraphFileError(f"{path}: cannot read: {exc.strerror}") from None
        return cls.from_json(text, agent, source=str(path), **kwargs)


def _encoded(states: dict[Any, ElementState], keys: list[Any],
             cache: dict[Any, tuple[ElementState, int, bytes]],
             fresh: dict[Any, tuple[ElementState, int, bytes]],
             entry: Callable[[Any, ElementState], dict[str, object]]) -> list[bytes]:
    """The JSON of each element still in `states`, from `cache` when the element's state is
    the same object at the same rev, encoded anew otherwise; every one is put in `fresh`."""
    out: list[bytes] = []
    dumps = orjson.dumps
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
