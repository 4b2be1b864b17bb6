"""Reviewing a state reply against a write policy: keep what its writers were allowed to write.

Why filter instead of refusing whole (as deltas are): a state relays the writes of every agent
its sender ever merged.  Refusing a whole state because one relayed piece is not acceptable
would stop anti-entropy for everything else it carries; keeping only the acceptable pieces is
still a valid CRDT join (a smaller state), and every replica that runs the same policy keeps the
same pieces, so replicas still converge.

Attribution inside a state:
- add dots, `meta` and attribute registers name the replica that stamped them; its agent comes
  from this replica's record of writers, else from the state's `writers` table;
- removals (`rem`, `cleared`) do not name the remover; the removal receipt
  (crdt.REMOVAL_RECEIPT, stamped at `cleared`) does.  A removal that would change what this
  replica holds is kept only if its receipt covers it and names an agent allowed to delete the
  element (edges: or to delete one of its end nodes).

Limit (documented in docs/deployment.md): a sender can lie about who stamped a register (there
are no signatures); the policy then stops buggy agents and processes without grants, and the
Zenoh ACL decides who may serve state at all.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

from dsr.crdt import REMOVAL_RECEIPT, ElementState
from dsr.writes import Element, GraphLookup, Write, message_node_types, node_types, removes

if TYPE_CHECKING:
    from dsr.wire import Decoded

Allowed = Callable[[Write], bool]
_MAX_REPORTED = 3


class _Review:
    def __init__(self, message: Decoded, graph: GraphLookup, allowed: Allowed) -> None:
        self.message, self.graph, self.allowed = message, graph, allowed
        self.problems: list[str] = []
        self.dropped = 0
        self._writers: dict[int, str | None] = {}
        self.created = message_node_types(message, graph)

    def writer(self, replica: int) -> str | None:
        if replica not in self._writers:
            self._writers[replica] = (self.graph.writer_agent(replica)
                                      or self.message.writers.get(str(replica)))
        return self._writers[replica]

    def type_of(self, node_id: int) -> str | None:
        return self.graph.node_type_of(node_id) or self.created.get(node_id)

    def refuse(self, problem: str) -> None:
        self.dropped += 1
        if len(self.problems) < _MAX_REPORTED:
            self.problems.append(problem)

    def ok(self, write: Write) -> bool:
        if self.allowed(write):
            return True
        from dsr.policy_rules import explain
        self.refuse(explain(write))
        return False

    def element(self, state: ElementState, local: ElementState | None, element: Element,
                types: set[str | None], src: str | None, dst: str | None) -> ElementState:
        kept = ElementState()

        def writes(replica: int, op: str, attr: str | None = None) -> list[Write]:
            who = self.writer(replica)
            return [Write(who, element, t, op, attr, src, dst) for t in types]  # type: ignore[arg-type]

        for replica, hlc in state.add.items():
            if all(self.ok(w) for w in writes(replica, "create")):
                kept.add[replica] = hlc
        if state.meta is not None and all(self.ok(w) for w in writes(state.meta[1], "create")):
            kept.meta = state.meta
        for key, register in state.attrs.items():
            if key == REMOVAL_RECEIPT:
                continue
            hlc, replica = register[0], register[1]
            op = "init" if state.add.get(replica) == hlc else "attr"
            if all(self.ok(w) for w in writes(replica, op, key)):
                kept.attrs[key] = register
        if removes(state):
            if not _news(state, local) or self._removal_allowed(state, element, types, src, dst):
                kept.rem, kept.cleared = dict(state.rem), state.cleared
                receipt = state.attrs.get(REMOVAL_RECEIPT)
                if receipt is not None:
                    kept.attrs[REMOVAL_RECEIPT] = receipt
        return kept

    def _removal_allowed(self, state: ElementState, element: Element, types: set[str | None],
                         src: str | None, dst: str | None) -> bool:
        from dsr.policy_rules import explain
        receipt = state.attrs.get(REMOVAL_RECEIPT)
        horizon = max(state.cleared, max(state.rem.values(), default=0))
        what = f"{next(iter(types))!r} {element}"
        if receipt is None or receipt[0] < horizon:
            self.refuse(f"a removal of a {what} without a receipt naming its remover")
            return False
        who = self.writer(receipt[1])
        delete = [Write(who, element, t, "delete", None, src, dst) for t in types]
        if all(self.allowed(w) for w in delete):
            return True
        if element == "edge" and any(
                self.allowed(Write(who, "node", end, "delete")) for end in (src, dst) if end):
            return True     # deleting a node deletes its edges
        self.refuse(explain(delete[0]))
        return False


def _news(state: ElementState, local: ElementState | None) -> bool:
    """Would this removal information change what the replica holds?"""
    if local is None:
        return True
    if state.cleared > local.cleared:
        return True
    return any(hlc > local.rem.get(replica, 0) for replica, hlc in state.rem.items())


def review_state(message: Decoded, graph: GraphLookup, allowed: Allowed) -> tuple[Decoded, str | None]:
    """The acceptable part of a state, and a summary of what was dropped (None: nothing)."""
    from dsr.wire import Decoded as DecodedMessage

    review = _Review(message, graph, allowed)
    nodes = [(node_id, review.element(state, graph.element_state("node", node_id), "node",
                                      node_types(node_id, state, graph), None, None))
             for node_id, state in message.nodes]
    edges = [(key, review.element(state, graph.element_state("edge", key), "edge", {key[2]},
                                  review.type_of(key[0]), review.type_of(key[1])))
             for key, state in message.edges]
    if not review.dropped:
        return message, None
    kept = DecodedMessage(message.kind, message.graph, message.agent, message.replica,
                          message.writers, nodes, edges, message.top_hlc)
    summary = f"dropped {review.dropped} part(s) of the state: " + "; ".join(review.problems)
    return kept, summary
