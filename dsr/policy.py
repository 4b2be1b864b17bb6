"""Write policies: which agent may write which nodes, edges and attributes ("trust").

Why on receipt, in every replica: a rogue or buggy process can put anything on the delta keys
(Zenoh ACLs, docs/deployment.md, decide who may publish at all); each replica therefore asks its
policy about every write of every remote delta and state before merging.  A refused delta is
dropped whole (a graph never holds half of one); a state keeps only its acceptable part (it
relays many writers, dsr/state_review.py).  Refusals are counted in
`ReplicaStats.rejected_policy` and logged.

Policies:
- `AllowAll` (library default of `join()`): tools, tests, benchmarks.
- `RulePolicy` (dsr/policy_rules.py): the declarative table; chronav's own table and its loader
  (`agents/world/write_policy.py`, `policy_from_env()`) live above the DSR, which reads no files.
- `DenyTypes`: a coarse per-type refusal, kept for simple tests.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Literal, Protocol

from dsr.state_review import review_state


if TYPE_CHECKING:
    from dsr.wire import Decoded
    from dsr.writes import GraphLookup, Write

ElementKind = Literal["node", "edge"]


class WritePolicy(Protocol):
    def check(self, message: Decoded, graph: GraphLookup) -> str | None:
        """For a validated remote delta: None if every write is allowed, else a sentence
        saying which write is refused and why (the delta is then dropped whole)."""
        ...

    def review_state(self, message: Decoded, graph: GraphLookup
                     ) -> tuple[Decoded | None, str | None]:
        """For a validated state reply: (what to merge, or None to refuse it whole; what was
        dropped and why, or None)."""
        ...


class LocalCheck(Protocol):
    def refusal(self, write: Write) -> str | None:
        """For a local write (DSRGraph.local_policy): None if allowed, else the sentence of
        WriteRefusedError (writer, operation, element type, attribute, policy source)."""
        ...


class TypePolicy:
    """Base of the simple policies: one yes/no per (writing agent, element kind, type).  A
    delta is refused whole; a state keeps only the writes its writers were allowed
    (dsr/state_review.py), so a state, the sender's own or one relaying it, never brings
    what a delta could not (a member's state fetched after its first writes did)."""

    def allows(self, *, agent: str | None, kind: ElementKind, type: str | None) -> bool:
        """`agent` None: a write nobody has vouched for (relayed in a state)."""
        raise NotImplementedError

    def check(self, message: Decoded, graph: GraphLookup) -> str | None:
        if message.kind != "delta":
            return None
        agent = message.agent
        for node_id, state in message.nodes:
            type_ = state.meta[2][0] if state.meta is not None else graph.node_type_of(node_id)
            if not self.allows(agent=agent, kind="node", type=type_):
                return f"policy refuses node type {type_!r} from agent {agent!r}"
        for (_, _, edge_type), _state in message.edges:
            if not self.allows(agent=agent, kind="edge", type=edge_type):
                return f"policy refuses edge type {edge_type!r} from agent {agent!r}"
        return None

    def review_state(self, message: Decoded, graph: GraphLookup
                     ) -> tuple[Decoded | None, str | None]:
        return review_state(message, graph, self.allowed)

    def allowed(self, write: Write) -> bool:
        return self.allows(agent=write.writer, kind=write.element, type=write.type)

    def refusal(self, write: Write) -> str | None:
        if self.allows(agent=write.writer or "", kind=write.element, type=write.type):
            return None
        return f"policy refuses {write.element} type {write.type!r} from agent {write.writer!r}"


class AllowAll(TypePolicy):
    """Every agent may write everything."""

    def allows(self, *, agent: str | None, kind: ElementKind, type: str | None) -> bool:
        return True

    def check(self, message: Decoded, graph: GraphLookup) -> str | None:
        return None

    def review_state(self, message: Decoded, graph: GraphLookup
                     ) -> tuple[Decoded | None, str | None]:
        return message, None


class DenyTypes(TypePolicy):
    """Refuse writes of the given node/edge types by the given agents (or by anyone)."""

    def __init__(self, types: set[str], agents: set[str] | None = None) -> None:
        self.types = set(types)
        self.agents = None if agents is None else set(agents)

    def allows(self, *, agent: str | None, kind: ElementKind, type: str | None) -> bool:
        """An unattributed write (agent None) of a refused type is refused: it may be one of
        the refused agents'."""
        if self.agents is not None and agent is not None and agent not in self.agents:
            return True
        return type not in self.types
