"""What a remote delta does, as a list of attributable writes (the input of write policies).

Why a separate step: a policy should answer "may agent A create a `robot` node / set `cmd_vx`
on a `robot` node / delete an `in` edge from a `person`?" without knowing the CRDT encoding.

A delta is entirely its sender's: the transport has already refused deltas carrying another
replica's dots or registers, and the delta key names the sender (authenticated by the Zenoh
ACL in a secured deployment).  Attribute registers stamped with the same hlc as the element's
add dot are initial values (op "init", granted with the create); a removal's receipt register
(crdt.REMOVAL_RECEIPT) is part of the delete.  States relay many writers' writes and are
reviewed differently (dsr/state_review.py).
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Mapping
from typing import TYPE_CHECKING, Any, Literal, NamedTuple, Protocol

from dsr.crdt import REMOVAL_RECEIPT

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
    cascade: str | None = None  # edge delete caused by deleting a node of this type
    #: op "init" of a key some rule restricts at creation (`init_values`): the value given;
    #: else None (values stay out of the question, so decisions stay few and cacheable)
    value: object = None


class GraphLookup(Protocol):
    """What policies need from the receiving replica (dsr.DSRGraph provides it)."""

    def node_type_of(self, node_id: int) -> str | None: ...

    def writer_agent(self, replica: int) -> str | None: ...

    def element_state(self, element: str, key: int | tuple[int, int, str]
                      ) -> ElementState | None: ...


def removes(state: ElementState) -> bool:
    return bool(state.rem) or state.cleared > 0


def message_node_types(message: Decoded, graph: GraphLookup) -> dict[int, str]:
    """Node types as known here, completed by the nodes the message itself creates (an edge
    often arrives in the same delta as its new end node)."""
    types = {node_id: state.meta[2][0] for node_id, state in message.nodes
             if state.meta is not None}
    for node_id in list(types):
        known = graph.node_type_of(node_id)
        if known is not None:
            types[node_id] = known
    return types


def node_types(node_id: int, state: ElementState, graph: GraphLookup) -> set[str | None]:
    """A write to a node is checked against its current type and the type it would get."""
    known = graph.node_type_of(node_id)
    new = state.meta[2][0] if state.meta is not None else None
    return {t for t in (known, new) if t is not None} or {None}


def init_value(value: object) -> object:
    """The value of an initial register as a write names it (hashable; lists as tuples)."""
    return tuple(value) if type(value) is list else value


def delta_writes(message: Decoded, graph: GraphLookup,
                 valued: frozenset[str] = frozenset()) -> Iterator[Write]:
    """Every write of a validated delta, attributed to its sender (duplicates possible).
    `valued`: keys whose initial values the policy judges (Write.value)."""
    agent = message.agent
    created = message_node_types(message, graph)

    def type_of(node_id: int) -> str | None:
        return graph.node_type_of(node_id) or created.get(node_id)

    deleted: dict[int, str | None] = {}
    for node_id, state in message.nodes:
        if removes(state):
            deleted[node_id] = type_of(node_id)
        for type_ in node_types(node_id, state, graph):
            yield from _element_writes(agent, state, "node", type_, None, None, None, valued)
    for (src, dst, edge_type), state in message.edges:
        cascade = (deleted.get(src) or deleted.get(dst)) if removes(state) else None
        yield from _element_writes(agent, state, "edge", edge_type, type_of(src), type_of(dst),
                                   cascade, valued)


def _element_writes(agent: str, state: ElementState, element: Element, type_: str | None,
                    src: str | None, dst: str | None, cascade: str | None,
                    valued: frozenset[str] = frozenset()) -> Iterator[Write]:
    if state.add or state.meta is not None:
        yield Write(agent, element, type_, "create", None, src, dst)
    removal = removes(state)
    if removal:
        yield Write(agent, element, type_, "delete", None, src, dst, cascade)
    add = state.add
    for key, (hlc, replica, value) in state.attrs.items():
        if removal and key == REMOVAL_RECEIPT:
            continue
        op: Op = "init" if add.get(replica) == hlc else "attr"
        if op == "init" and key in valued:
            yield Write(agent, element, type_, op, key, src, dst, value=init_value(value))
        else:
            yield Write(agent, element, type_, op, key, src, dst)


def local_writes(graph: GraphLookup, agent: str, element: Element, key: int | tuple[int, int, str],
                 delta: Mapping[str, Any], cascade: str | None = None,
                 valued: frozenset[str] = frozenset()) -> Iterator[Write]:
    """The writes of one local change (the keyword pieces of a delta) before it is applied:
    the same questions receivers will ask about the delta (see delta_writes)."""
    from dsr.crdt import ElementState

    state = ElementState(add=dict(delta.get("add") or ()), rem=dict(delta.get("rem") or ()),
                         cleared=int(delta.get("cleared") or 0), meta=delta.get("meta"),
                         attrs=dict(delta.get("attrs") or {}))
    if element == "node":
        assert isinstance(key, int)
        for type_ in node_types(key, state, graph):
            yield from _element_writes(agent, state, "node", type_, None, None, None, valued)
    else:
        assert isinstance(key, tuple)
        src, dst, edge_type = key
        yield from _element_writes(agent, state, "edge", edge_type, graph.node_type_of(src),
                                   graph.node_type_of(dst), cascade, valued)


def attr_writes(graph: GraphLookup, agent: str, element: Element, key: int | tuple[int, int, str],
                attrs: Iterable[str]) -> list[Write]:
    """``local_writes`` of an attribute-only change (a delta of ``attrs`` registers alone: no add, no
    removal, no type): one ``attr`` write per key, without building the element state.  Why: every
    pose and sensor update of every agent is one, and the generic path was a tenth of the
    observer's time with a crowd (tests/unit/test_dsr_policy.py compares the two)."""
    if element == "node":
        assert isinstance(key, int)
        type_ = graph.node_type_of(key)
        return [Write(agent, "node", type_, "attr", name) for name in attrs]
    assert isinstance(key, tuple)
    src, dst, edge_type = key
    src_type, dst_type = graph.node_type_of(src), graph.node_type_of(dst)
    return [Write(agent, "edge", edge_type, "attr", name, src_type, dst_type) for name in attrs]


def explain(write: Write) -> str:
    """The refusal as a sentence an operator can match against the policy file."""
    if write.writer is None:
        return "a register stamped by a replica no agent vouches for"
    what = f"{write.type!r} {write.element}" if write.type else f"{write.element} of unknown type"
    if write.element == "edge":
        what += f" ({write.src or '?'} -> {write.dst or '?'})"
    if write.op == "attr":
        return f"agent {write.writer!r} may not set {write.attr!r} on a {what}"
    if write.op == "init":
        if write.value is not None:
            return (f"agent {write.writer!r} may not create a {what} with {write.attr!r} = "
                    f"{write.value!r}")
        return f"agent {write.writer!r} may not create a {what} with {write.attr!r}"
    return f"agent {write.writer!r} may not {write.op} a {what}"
