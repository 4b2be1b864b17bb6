"""DSRGraph: the local replica of the shared graph and the API agents call.

Why this structure: the replicated truth is the CRDT state (`crdt.ElementState` per node and
edge); everything an agent queries (visible nodes, names, types, adjacency) is an index derived
from it and kept in sync element by element, so queries are O(1)/O(degree) and signals are
computed exactly where the state changed.  Local writes are built as deltas and go through the
same merge code as remote deltas, so a replica cannot diverge from what it publishes.

DSRGraph composes the parts that do this and keeps the API agents, tools and tests call:
- dsr/graph_state.py GraphState: the node and edge tables and the derived indexes (merge,
  install, sync of one element);
- dsr/table.py ElementTable: one generic table for nodes and for edges (undo record and
  outgoing delta of a transaction, tombstones, the state-reply JSON cache);
- dsr/bindings.py WriterBindings: which agent each replica id writes for;
- dsr/graph_io.py: graph files (JSON) and networkx import/export;
- dsr/signals.py SignalHub and dsr/outbox.py Outbox: signal delivery and publishing.
What stays here: locking, transactions and local write checks, the replication hooks
(attach, apply_message, state replies, compaction) and poses.

Threading: one re-entrant lock guards the state.  A transaction holds it for its whole body
(remote merges wait, which gives the transaction isolation and makes rollback safe); signals are
queued and delivered by `dispatch()` on the caller's thread with no lock held.
"""

from __future__ import annotations

import secrets
import threading
from collections.abc import Callable, Iterable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from dsr import crdt, graph_io, poses, wire
from dsr.bindings import WriterBindings
from dsr.crdt import ElementState
from dsr.errors import (EdgeNotFoundError, InvalidAttributeError, InvalidIdentifierError,
                        NameTakenError, NodeNotFoundError, PoseError, ReadOnlyGraphError,
                        TransactionError, WriteRefusedError)
from dsr.graph_state import GraphState
from dsr.hlc import HybridLogicalClock
from dsr.limits import LIMITS, node_problem, value_bytes
from dsr.model import (Attrs, Edge, Node, check_agent_name, check_attrs, check_name,
                       check_node_id, check_type_name)
from dsr.outbox import Outbox, Outgoing
from dsr.signals import Event, PollSource, SignalHub, SpinPolicy
from dsr.table import Changes, Encoded, ElementTable
from dsr.writes import Element, Write

if TYPE_CHECKING:
    import networkx

EdgeKey = tuple[int, int, str]
Publisher = Callable[[bytes], None]
RT = "RT"


@dataclass
class _Transaction:
    owner: int
    rollback: bool
    nodes: Changes[int] = field(default_factory=Changes)
    edges: Changes[EdgeKey] = field(default_factory=Changes)
    events: list[Event] = field(default_factory=list)

    def changed(self) -> bool:
        return bool(self.nodes.out or self.edges.out)


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
        self._signals = SignalHub(spin)     # spin None: SpinPolicy.from_env()
        #: element states and the indexes derived from them (dsr/graph_state.py); the
        #: attributes below are the same objects, named for the queries and hot paths here
        self._state = state = GraphState(self._signals)
        self._node_table, self._edge_table = state.node_table, state.edge_table
        self._nodes, self._edges = state.nodes, state.edges
        self._out, self._in = state.outgoing, state.incoming
        self._view, self._types, self._names = state.view, state.types, state.names
        self._visible_edges, self._edge_types = state.visible_edges, state.edge_types
        self._tx: _Transaction | None = None
        self._tx_depth = 0
        self._version = 0
        self._snapshot_cache: tuple[int, bytes] | None = None
        #: replica id -> agent: who wrote what this replica holds (dsr/bindings.py)
        self.writers = WriterBindings(self.replica_id, self.agent, self._lock)
        #: encodes this replica's deltas and digests (dsr/wire.py)
        self.encoder = wire.DeltaEncoder(self.graph_name, self.agent, self.replica_id)
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

    @property
    def node_states(self) -> Mapping[int, ElementState]:
        """Replicated CRDT state of every node this replica holds, visible or not (admission
        checks, tests); callers must not mutate it."""
        return self._nodes

    @property
    def edge_states(self) -> Mapping[EdgeKey, ElementState]:
        """Replicated CRDT state of every edge this replica holds (see node_states)."""
        return self._edges

    def get_node(self, node_id: int) -> Node | None:
        with self._lock:
            return self._state.node(node_id) if node_id in self._view else None

    def get_node_by_name(self, name: str) -> Node | None:
        with self._lock:
            node_id = self._names.lookup(name)
            return self._state.node(node_id) if node_id is not None else None

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
            node = self._state.node
            return [node(i) for i in sorted(self._view)]

    def nodes_of_type(self, type: str) -> list[Node]:  # DSR vocabulary
        with self._lock:
            node = self._state.node
            return [node(i) for i in sorted(self._types.get(type, ()))]

    def get_edge(self, src: int, dst: int, type: str) -> Edge | None:
        with self._lock:
            key = (src, dst, type)
            return self._state.edge(key) if key in self._visible_edges else None

    def edges(self) -> list[Edge]:
        with self._lock:
            edge = self._state.edge
            return [edge(k) for k in sorted(self._visible_edges)]

    def edges_from(self, node_id: int, type: str | None = None) -> list[Edge]:
        return self._incident(self._out, node_id, type)

    def edges_to(self, node_id: int, type: str | None = None) -> list[Edge]:
        return self._incident(self._in, node_id, type)

    def _incident(self, index: dict[int, set[EdgeKey]], node_id: int,
                  type_: str | None) -> list[Edge]:
        with self._lock:
            visible, edge = self._visible_edges, self._state.edge
            return [edge(k) for k in sorted(index.get(node_id, ()))
                    if k in visible and (type_ is None or k[2] == type_)]

    def edges_of_type(self, type: str) -> list[Edge]:
        with self._lock:
            edge = self._state.edge
            return [edge(k) for k in sorted(self._edge_types.get(type, ()))]

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
            tx = self._tx
            outer = tx is None
            if tx is None:
                tx = self._tx = _Transaction(owner=threading.get_ident(), rollback=rollback)
            elif rollback and not tx.rollback:
                raise TransactionError("transaction opened inside a single write")
            self._tx_depth += 1
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
            out = outbox = None
            if outer:
                self._tx = None
                if tx.changed():
                    self._check_size(tx)
                outbox = self._outbox
                out = self._commit(tx, outbox)
        finally:
            self._lock.release()
        if out is not None and outbox is not None:
            outbox.send(out)

    def _check_size(self, tx: _Transaction) -> None:
        """Refuse (and undo) a write whose delta receivers would drop as too large."""
        limit = LIMITS.max_delta_bytes
        estimate = 0
        for state in (*tx.nodes.out.values(), *tx.edges.out.values()):
            estimate += 200 + sum(value_bytes(reg[2]) + 60 for reg in state.attrs.values())
        if estimate * 2 < limit:
            return
        size = len(self.encoder.encode(self._node_table.entries(tx.nodes.out),
                                       self._edge_table.entries(tx.edges.out)))
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
        if not tx.changed():
            return None
        self._version += 1
        return outbox.add(tx.nodes.out, tx.edges.out, self.clock.last) \
            if outbox is not None else None

    def _undo(self, tx: _Transaction) -> None:
        node_ids = self._node_table.restore(tx.nodes)
        edge_keys = self._edge_table.restore(tx.edges)
        for key in edge_keys:
            if key not in self._edges:
                self._state.unlink_edge(key)
        for node_id in node_ids:
            self._state.sync_node(node_id, [], None)
        for key in edge_keys:
            self._state.sync_edge(key, [], None)
        self._version += 1

    # ------------------------------------------------------------------ local writes
    def insert_node(self, type: str, name: str, attrs: Attrs | None = None,
                    *, id: int | None = None) -> Node:
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
        self._local(tx, self._node_table, node_id, add=((me, hlc),),
                    meta=(hlc, me, (type_, name)),
                    attrs={k: (hlc, me, v) for k, v in values.items()})
        return self._state.node(node_id)

    def update_node(self, node_id: int, attrs: Attrs) -> None:
        """Set attributes of a visible node (last writer wins per attribute).

        Outside a transaction this is the hot path of every agent (poses, sensor values), so
        it bypasses the transaction machinery: merge, encode one small delta, publish."""
        values = check_attrs(attrs)
        if self.read_only:
            raise ReadOnlyGraphError(f"graph replica of agent {self.agent!r} is read-only")
        out = outbox = event = None
        with self._lock:
            if self._tx is not None:
                self._update_node_tx(node_id, values)
                return
            if node_id not in self._view:      # (_check_updates for one node, inlined)
                raise NodeNotFoundError(f"cannot update node {node_id}: not in the graph")
            if self.local_policy is not None:
                self._check_local("node", node_id, {"attrs": dict.fromkeys(values, (0, 0, 0))})
            if not _cannot_grow(values, self._nodes[node_id].attrs):
                self._check_node_limits(node_id, values)
            hlc = self.clock.tick()
            me = self.replica_id
            regs: dict[str, tuple[int, int, object]] = {
                k: (hlc, me, v) for k, v in values.items()}
            _, keys = crdt.merge_attrs(self._nodes[node_id], regs)
            if keys and self._signals.wants("node_updated"):
                event = ("node_updated", (self._state.node(node_id), keys))
            self._version += 1
            outbox = self._outbox
            if outbox is not None:
                out = outbox.add_attrs(node_id, regs, hlc)
        try:                        # (_deliver, inlined: the hot path of every agent)
            if event is not None:
                self._signals.post([event])
        finally:
            if out is not None and outbox is not None:
                outbox.send(out)

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
        out = outbox = None
        with self._lock:
            if self._tx is not None:          # another thread's transaction: wait for it
                for node_id, values in checked.items():
                    self._update_node_tx(node_id, values)
                return
            self._check_updates(checked.items())
            if not checked:
                return
            hlc = self.clock.tick()
            events, entries = self._merge_updates(checked, hlc)
            self._version += 1
            outbox = self._outbox
            if outbox is not None:
                out = outbox.add_entries(entries, hlc)
        self._deliver(events, outbox, out)

    def _check_updates(self, updates: Iterable[tuple[int, Attrs]]) -> None:
        """Refuse attribute updates of a node that is not visible, that the write policy
        refuses, or that would take a node over a node limit.  Caller holds the lock."""
        view, nodes, policy = self._view, self._nodes, self.local_policy
        for node_id, values in updates:
            if node_id not in view:
                raise NodeNotFoundError(f"cannot update node {node_id}: not in the graph")
            if policy is not None:
                self._check_local("node", node_id, {"attrs": dict.fromkeys(values, (0, 0, 0))})
            if not _cannot_grow(values, nodes[node_id].attrs):
                self._check_node_limits(node_id, values)

    def _merge_updates(self, checked: dict[int, Attrs], hlc: int
                       ) -> tuple[list[Event], list[dict[str, object]]]:
        """Merge checked attribute updates stamped `hlc`: the signal events and the delta's
        entries.  Caller holds the lock."""
        me = self.replica_id
        events: list[Event] = []
        entries: list[dict[str, object]] = []
        merge_attrs, nodes, node = crdt.merge_attrs, self._nodes, self._state.node
        want = self._signals.wants("node_updated")
        for node_id, values in checked.items():
            regs = {k: (hlc, me, v) for k, v in values.items()}
            _, keys = merge_attrs(nodes[node_id], regs)
            if keys and want:
                events.append(("node_updated", (node(node_id), keys)))
            entries.append({"id": node_id, "attrs": regs})
        return events, entries

    def _deliver(self, events: list[Event], outbox: Outbox | None, out: Outgoing | None) -> None:
        """After a write, with the lock released: queue its signals, publish its delta."""
        try:
            self._signals.post(events)
        finally:
            if out is not None and outbox is not None:
                outbox.send(out)

    def published_hlc(self) -> int:
        """Every local write stamped up to this HLC has been handed to the publisher."""
        outbox = self._outbox
        return max(self.sent_hlc, outbox.sent_top if outbox is not None else 0)

    def _update_node_tx(self, node_id: int, values: Attrs) -> None:
        with self._write(rollback=False) as tx:
            if node_id not in self._view:
                raise NodeNotFoundError(f"cannot update node {node_id}: not in the graph")
            if not _cannot_grow(values, self._nodes[node_id].attrs):    # as update_node does
                self._check_node_limits(node_id, values)
            hlc = self.clock.tick()
            me = self.replica_id
            self._local(tx, self._node_table, node_id,
                        attrs={k: (hlc, me, v) for k, v in values.items()})

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
                    if self._edges[key].present():
                        self._remove(tx, self._edge_table, key, hlc, receipt)
            finally:
                self._cascade = None
            self._remove(tx, self._node_table, node_id, hlc, receipt)

    def insert_or_assign_edge(self, src: int, dst: int, type: str,
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
                    self._local(tx, self._edge_table, key, attrs=regs)
            else:
                self._local(tx, self._edge_table, key, add=((me, hlc),), attrs=regs)
            return self._state.edge(key)

    def delete_edge(self, src: int, dst: int, type: str) -> None:
        with self._write(rollback=False) as tx:
            key = (src, dst, type)
            if key not in self._visible_edges:
                raise EdgeNotFoundError(f"cannot delete edge {src}->{dst} ({type}): not found")
            hlc = self.clock.tick()
            self._remove(tx, self._edge_table, key, hlc, crdt.removal_receipt(hlc, self.replica_id))

    def _remove(self, tx: _Transaction, table: ElementTable[Any], key: Any, hlc: int,
                receipt: dict[str, Any]) -> None:
        """Remove a node or an edge: observe every add it holds, clear its registers up to
        `hlc`, and leave the removal receipt (crdt.removal_receipt)."""
        self._local(tx, table, key, rem=tuple(table.states[key].add.items()), cleared=hlc,
                    attrs=receipt)

    def _local(self, tx: _Transaction, table: ElementTable[Any], key: Any,
               **delta: Any) -> None:
        """A local change of one element inside a transaction: checked against the write
        policy, recorded for undo, merged here, added to the outgoing delta."""
        if self.local_policy is not None:
            self._check_local(table.kind, key, delta)
        if table is self._node_table:
            table.record(tx.nodes, key)
            self._state.merge_node(key, delta, tx.events)
            table.stage(tx.nodes, key, delta)
        else:
            table.record(tx.edges, key)
            self._state.merge_edge(key, delta, tx.events)
            table.stage(tx.edges, key, delta)

    def _check_local(self, element: Element, key: Any, delta: dict[str, Any]) -> None:
        """Ask the write policy about a local write before it changes anything; a refusal
        raises WriteRefusedError naming the write (what every other replica would refuse)."""
        from dsr.writes import attr_writes, local_writes
        refusal = self.local_policy.refusal
        if len(delta) == 1 and "attrs" in delta:        # an attribute update: the common write
            writes: Iterable[Write] = attr_writes(self, self.agent, element, key, delta["attrs"])
        else:
            valued: frozenset[str] = getattr(self.local_policy, "valued", frozenset())
            writes = local_writes(self, self.agent, element, key, delta, self._cascade, valued)
        for write in writes:
            problem = refusal(write)
            if problem is not None:
                raise WriteRefusedError(problem)

    # ------------------------------------------------------------------ merge + derived view
    # ------------------------------------------------------------------ replication hooks
    def attach(self, publish: Publisher | None, *, linger_s: float = 0.0) -> None:
        """Called by the transport: where encoded local deltas go (None = offline).

        Deltas written in quick succession are coalesced (see outbox.py); `linger_s=0`
        publishes every delta on its own.  Detaching flushes what is pending."""
        with self._lock:
            old, self._outbox = self._outbox, None
            self._publish = publish
            if publish is not None:
                self._outbox = Outbox(self.encoder, publish, linger_s=linger_s)
        if old is not None:
            old.close()
            self.sent_hlc = max(self.sent_hlc, old.sent_top)

    def flush(self) -> None:
        """Publish coalesced deltas now instead of within the linger time."""
        outbox = self._outbox
        if outbox is not None:
            outbox.flush()

    def apply_message(self, message: wire.Decoded) -> int:
        """Merge a validated remote delta or state; returns how many elements changed.

        Whoever hands a message here vouches for its writers (the transport judges a state's
        table itself and passes none: dsr/admission.py note_state_writers)."""
        if self._tx is not None and self._tx.owner == threading.get_ident():
            raise TransactionError("apply_message() inside a local transaction")
        with self._lock:
            top = message.top_hlc
            if top:
                self.clock.observe(top)
            self.writers.vouch(message.writers,
                               message.replica if message.kind == "delta" else None,
                               message.agent)
            events: list[Event] = []
            changed = self._state.apply_nodes(message.nodes, events)
            changed += self._state.apply_edges(message.edges, events)
            if changed:
                self._version += 1
            self._signals.post(events)
            return changed

    # ------------------------------------------------------------------ for the transport
    def element_state(self, element: str, key: object) -> ElementState | None:
        """The replicated CRDT state of a node (key: id) or edge (key: (src, dst, type)), for
        write policies; callers must not mutate it."""
        table: Mapping[Any, ElementState] = self._nodes if element == "node" else self._edges
        return table.get(key)

    def node_type_of(self, node_id: int) -> str | None:
        """Type from the replicated state, even for a node not visible (for write policies)."""
        state = self._nodes.get(node_id)
        return state.meta[2][0] if state is not None and state.meta is not None else None

    def writer_agent(self, replica: int) -> str | None:
        """The agent a replica id writes for, as far as this replica knows (first-hand or
        relayed by a state's `writers` table: dsr/bindings.py)."""
        return self.writers.writer_agent(replica)

    def served_writers(self) -> dict[int, str]:
        """The `writers` table of this replica's state replies: only bindings it can prove
        (first-hand, vouched for by the agent itself, or taken from the state it joined
        with), never a claim it merely relayed or deferred."""
        return self.writers.served()

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
                                  edges=self._edges.items(), writers=self.writers.bound,
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
        The graph lock is held per part, not for the whole state; each element's JSON comes
        from its table's cache when unchanged (ElementTable.encoded_parts)."""
        with self._lock:
            clock = self.clock.last or self.clock.tick()   # never 0: 0 means "not the last part"
            node_ids, edge_keys = list(self._nodes), list(self._edges)
            writers = dict(self.writers.bound)
        seen = {**(seen or {}), self.replica_id: clock}
        chunks: list[tuple[list[int], list[EdgeKey]]] = []
        for start in range(0, len(node_ids), per_part):
            chunks.append((node_ids[start:start + per_part], []))
        for start in range(0, len(edge_keys), per_part):
            chunks.append(([], edge_keys[start:start + per_part]))
        if not chunks:
            chunks.append(([], []))
        fresh_nodes: dict[int, Encoded] = {}
        fresh_edges: dict[EdgeKey, Encoded] = {}
        for index, (ids, keys) in enumerate(chunks):
            last = index == len(chunks) - 1
            with self._lock:
                payload = wire.encode_parts(
                    kind="state", graph=self.graph_name, agent=self.agent,
                    replica=self.replica_id,
                    nodes=self._node_table.encoded_parts(ids, fresh_nodes),
                    edges=self._edge_table.encoded_parts(keys, fresh_edges),
                    writers=writers, clock=clock if last else 0, seen=seen if last else None)
            yield payload
        self._node_table.keep_encoded(fresh_nodes)
        self._edge_table.keep_encoded(fresh_edges)

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
            removed = self._state.compact(acked)
            if removed:
                self._version += 1
            return removed

    def tombstones(self) -> int:
        """How many removed elements this replica still remembers."""
        return len(self._node_table.dead) + len(self._edge_table.dead)

    def counts(self) -> dict[str, int]:
        """Visible nodes and edges and remembered tombstones: what a long run watches for growth."""
        with self._lock:
            return {"nodes": len(self._view), "edges": len(self._visible_edges), "tombstones": self.tombstones()}

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
            return self._state.edge(best)

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
                    chain.append((_coordinate(edge.attrs["x"]), _coordinate(edge.attrs["y"]),
                                  _coordinate(edge.attrs["theta"])))
                except (KeyError, TypeError, ValueError):
                    raise PoseError(f"RT edge {edge.src}->{edge.dst} needs float x, y, theta; "
                                    f"has {sorted(edge.attrs)}") from None
                if edge.src in seen:
                    raise PoseError(f"RT cycle through node {edge.src}")
                seen.add(edge.src)
                current = edge.src
            return poses.compose_chain(reversed(chain))

    # ------------------------------------------------------------------ graph files (graph_io)
    def to_networkx(self) -> networkx.MultiDiGraph:
        """Copy of the visible graph (dsr/graph_io.py to_networkx)."""
        with self._lock:
            return graph_io.to_networkx(self)

    def to_document(self) -> dict[str, Any]:
        """The visible graph as a plain dict in the graph-file format (files.py)."""
        with self._lock:
            return graph_io.to_document(self)

    def to_json(self, indent: bool = False) -> str:
        return graph_io.to_json(self, indent)

    def digest(self) -> str:
        """SHA-256 of the canonical visible graph: equal digests = identical graphs."""
        return graph_io.digest(self)

    @classmethod
    def from_json(cls, text: str | bytes, agent: str, source: str = "<json>",
                  **kwargs: Any) -> DSRGraph:
        """New offline graph holding the nodes and edges of a graph document."""
        graph = cls(agent, **kwargs)
        graph.load_json(text, source=source)
        return graph

    def load_json(self, text: str | bytes, source: str = "<json>") -> list[int]:
        """Insert a graph document into this graph in one transaction; returns node ids."""
        return graph_io.load_json(self, text, source)

    def insert_file_node(self, type_: str, name: str, values: Attrs,
                         node_id: int | None) -> Node:
        """Insert a node of a graph file inside the current transaction (dsr/graph_io.py):
        unlike insert_node, its name may be a shown name with '#' (checked by the caller)."""
        tx = self._tx
        if tx is None:
            raise TransactionError("insert_file_node() outside a transaction")
        return self._insert_node(tx, type_, name, values, node_id)

    def node_id_of(self, name: str) -> int | None:
        """Id of the node shown as `name`, or None."""
        with self._lock:
            return self._names.lookup(name)

    def save(self, path: str) -> None:
        graph_io.save(self, path)

    @classmethod
    def load(cls, path: str, agent: str, **kwargs: Any) -> DSRGraph:
        return cls.from_json(graph_io.read(path), agent, source=str(path), **kwargs)


def _coordinate(value: object) -> float:
    """An RT edge's x, y or theta as a float (TypeError/ValueError if it is not a number)."""
    if isinstance(value, (int, float, str)):
        return float(value)
    raise TypeError(f"not a number: {value!r}")
