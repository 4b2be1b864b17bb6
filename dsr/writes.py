"""What a DSR message does, as a list of attributable writes (input of write policies).

Why a separate step: a policy should answer "may agent A create a `robot` node / set `cmd_vx`
on a `robot` node / delete an `in` edge from a `person`?" without knowing the CRDT encoding.
This module turns a validated message into those questions.

Attribution:
- a delta is entirely the sender's (the transport has already refused deltas carrying another
  replica's dots or registers), including its removes;
- a state reply relays everybody's writes: each add dot, meta and attribute register is
  attributed to the agent of the replica that stamped it (the receiver's own record of writers
  first, then the state's `writers` table).  Removes in a state do not say who removed, so they
  are not attributable and yield no write.
Attribute registers stamped with the same (replica, hlc) as that replica's add dot are the
element's initial values (op "init"): policies grant them with the create.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import TYPE_CHECKING, Literal, NamedTuple, Protocol

if TYPE_CHECKING:
    from dsr.crdt import ElementState
    from dsr.wire import Decoded

Element = Literal["node", "edge"]
Op = Literal["create", "delete", "attr", "init"]


class Write(NamedTuple):
    """One attributable write.  Types are None when this replica has never seen the node."""

    writer: str | None          # agent name; None: a replica nobody has vouched for
    element: Element
    type: str | None            # node type, or edge type
    op: Op
    attr: str | None = None     # op "attr" (update) or "init" (value given at creation): the key
    src: str | None = None      # edges: type of the source node
    dst: str | None = None      # edges: type of the destination node
    cascade: str | None = None  # edge delete caused by deleting a node of this type (same delta)


class GraphLookup(Protocol):
    """What attribution needs from the receiving replica (dsr.DSRGraph provides it)."""

    def node_type_of(self, node_id: int) -> str | None: ...

    def writer_agent(self, replica: int) -> str | None: ...


def writes_of(message: Decoded, graph: GraphLookup) -> Iterator[Write]:
    """Every attributable write of a validated message (duplicates possible)."""
    delta = message.kind == "delta"
    created_types = {node_id: state.meta[2][0] for node_id, state in message.nodes
                     if state.meta is not None}
    deleted: dict[int, str | None] = {}
    writers: dict[int, str | None] = {}

    def writer(replica: int) -> str | None:
        if delta:
            return message.agent
        if replica not in writers:
            writers[replica] = graph.writer_agent(replica) or message.writers.get(str(replica))
        return writers[replica]

    def node_type(node_id: int) -> str | None:
        return graph.node_type_of(node_id) or created_types.get(node_id)

    for node_id, state in message.nodes:
        known = graph.node_type_of(node_id)
        new = state.meta[2][0] if state.meta is not None else None
        types = {t for t in (known, new) if t is not None} or {None}
        if delta and (state.rem or state.cleared):
            deleted[node_id] = known or new
        for type_ in types:
            yield from _element_writes(state, delta, writer, "node", type_, None, None, None)
    for (src, dst, edge_type), state in message.edges:
        cascade = None
        if delta and (state.rem or state.cleared):
            cascade = deleted.get(src) or deleted.get(dst)
        yield from _element_writes(state, delta, writer, "edge", edge_type, node_type(src),
                                   node_type(dst), cascade)


def _element_writes(state: ElementState, delta: bool, who: Callable[[int], str | None],
                    element: Element, type_: str | None, src: str | None, dst: str | None,
                    cascade: str | None) -> Iterator[Write]:
    creators = set(state.add)
    if state.meta is not None:
        creators.add(state.meta[1])
    for replica in creators:
        yield Write(who(replica), element, type_, "create", None, src, dst)
    if delta and (state.rem or state.cleared):
        yield Write(who(0), element, type_, "delete", None, src, dst, cascade)
    add = state.add
    for key, (hlc, replica, _value) in state.attrs.items():
        op: Op = "init" if add.get(replica) == hlc else "attr"
        yield Write(who(replica), element, type_, op, key, src, dst)
