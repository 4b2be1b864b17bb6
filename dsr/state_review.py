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
from dsr.writes import (Element, GraphLookup, Write, explain, init_value, message_node_types,
                        node_types, removes)

if TYPE_CHECKING:
    from dsr.wire import Decoded

Allowed = Callable[[Write], bool]
_MAX_REPORTED = 3


class _Review:
    def __init__(self, message: Decoded, graph: GraphLookup, allowed: Allowed,
                 valued: frozenset[str] = frozenset()) -> None:
        self.message, self.graph, self.allowed = message, graph, allowed
        self.valued = valued
        self.problems: list[str] = []
        self.dropped = 0
        self._writers: dict[int, str | None] = {}
        self._memo: dict[tuple[object, ...], str | None] = {}   # question -> refusal
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
        if len(self.problems) < _MAX_REPORTED and problem not in self.problems:
            self.problems.append(problem)

    def ok(self, replica: int, element: Element, types: tuple[str | None, ...], op: str,
           attr: str | None, src: str | None, dst: str | None, value: object = None) -> bool:
        """Memoised per stamping replica: a 10,000-node state repeats a few dozen questions."""
        key = (replica, element, types, op, attr, src, dst, value)
        if key not in self._memo:
            who = self.writer(replica)
            writes = [Write(who, element, t, op, attr, src, dst, value=value)  # type: ignore[arg-type]
                      for t in types]
            refused = next((w for w in writes if not self.allowed(w)), None)
            self._memo[key] = None if refused is None else explain(refused)
        problem = self._memo[key]
        if problem is None:
            return True
        self.refuse(problem)
        return False

    def element(self, state: ElementState, local: ElementState | None, element: Element,
                types: tuple[str | None, ...], src: str | None, dst: str | None
                ) -> ElementState | None:
        """None when every part is acceptable (the common case: no copy), else the kept part."""
        ok = self.ok
        bad_adds = [r for r in state.add if not ok(r, element, types, "create", None, src, dst)]
        bad_meta = state.meta is not None and not ok(state.meta[1], element, types, "create",
                                                     None, src, dst)
        add = state.add
        valued = self.valued
        bad_attrs = [key for key, (hlc, replica, value) in state.attrs.items()
                     if key != REMOVAL_RECEIPT and not ok(
                         replica, element, types, "init" if add.get(replica) == hlc else "attr",
                         key, src, dst, init_value(value) if key in valued
                         and add.get(replica) == hlc else None)]
        bad_removal = removes(state) and _news(state, local) and not self._removal_allowed(
            state, element, types, src, dst)
        if not (bad_adds or bad_meta or bad_attrs or bad_removal):
            return None
        kept = ElementState(add={r: h for r, h in state.add.items() if r not in bad_adds},
                            meta=None if bad_meta else state.meta,
                            attrs={k: v for k, v in state.attrs.items() if k not in bad_attrs})
        if bad_removal:
            kept.attrs.pop(REMOVAL_RECEIPT, None)
        else:
            kept.rem, kept.cleared = dict(state.rem), state.cleared
        return kept

    def _removal_allowed(self, state: ElementState, element: Element,
                         types: tuple[str | None, ...], src: str | None, dst: str | None) -> bool:
        receipt = state.attrs.get(REMOVAL_RECEIPT)
        horizon = max(state.cleared, max(state.rem.values(), default=0))
        what = f"{types[0]!r} {element}"
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


def review_state(message: Decoded, graph: GraphLookup, allowed: Allowed,
                 valued: frozenset[str] = frozenset()) -> tuple[Decoded, str | None]:
    """The acceptable part of a state, and a summary of what was dropped (None: nothing).
    `valued`: keys whose initial values the policy judges (dsr/writes.py Write.value)."""
    from dsr.wire import Decoded as DecodedMessage

    review = _Review(message, graph, allowed, valued)
    element_state = graph.element_state
    nodes = []
    for node_id, state in message.nodes:
        local = element_state("node", node_id) if removes(state) else None
        kept = review.element(state, local, "node", tuple(node_types(node_id, state, graph)),
                              None, None)
        nodes.append((node_id, state if kept is None else kept))
    edges = []
    for key, state in message.edges:
        local = element_state("edge", key) if removes(state) else None
        kept = review.element(state, local, "edge", (key[2],), review.type_of(key[0]),
                              review.type_of(key[1]))
        edges.append((key, state if kept is None else kept))
    if not review.dropped:
        return message, None
    kept_message = DecodedMessage(message.kind, message.graph, message.agent, message.replica,
                                  message.writers, nodes, edges, message.top_hlc)
    summary = f"dropped {review.dropped} part(s) of the state: " + "; ".join(review.problems)
    return kept_message, summary
