"""Write policies: which remote agent may write which node and edge types.

Why a hook now: the later "trust" work will restrict, e.g., who may move the robot or edit the
agenda.  The transport asks the policy about every element of every remote delta before
merging; a refused delta is dropped whole (so a graph never holds half of one), counted in
`ReplicaStats.rejected_policy`, and logged.
"""

from __future__ import annotations

from typing import Literal, Protocol

ElementKind = Literal["node", "edge"]


class WritePolicy(Protocol):
    def allows(self, *, agent: str, kind: ElementKind, type: str | None) -> bool:  # noqa: A002
        """May `agent` write an element of this kind and type?  `type` is None for an
        attribute update of a node this replica has never seen (type unknown)."""
        ...


class AllowAll:
    """Default policy: every agent may write everything."""

    def allows(self, *, agent: str, kind: ElementKind, type: str | None) -> bool:  # noqa: A002
        return True


class DenyTypes:
    """Refuse writes of the given node/edge types by the given agents (or by anyone)."""

    def __init__(self, types: set[str], agents: set[str] | None = None) -> None:
        self.types = set(types)
        self.agents = None if agents is None else set(agents)

    def allows(self, *, agent: str, kind: ElementKind, type: str | None) -> bool:  # noqa: A002
        if self.agents is not None and agent not in self.agents:
            return True
        return type not in self.types
