"""Deterministic resolution of node names held by several visible nodes.

Why: two agents may create a node with the same name concurrently (neither has seen the other's
insert yet).  Both nodes survive (no data is lost), and every replica shows the same view:
the holder created first, ordered by (insert HLC, node id), keeps the plain name; each other
holder is shown as "<name>#<id>".  When the winner is deleted the next holder gets the plain
name back.  The view is a pure function of the replicated state, so replicas agree.
"""

from __future__ import annotations


class NameIndex:
    def __init__(self) -> None:
        self._holders: dict[str, dict[int, int]] = {}   # name -> {node id: created hlc}
        self._winner: dict[str, int] = {}

    def _elect(self, name: str) -> int | None:
        holders = self._holders.get(name)
        if not holders:
            self._holders.pop(name, None)
            self._winner.pop(name, None)
            return None
        winner = min(holders.items(), key=lambda item: (item[1], item[0]))[0]
        self._winner[name] = winner
        return winner

    def add(self, name: str, node_id: int, created: int) -> list[int]:
        """Register a holder; returns OTHER node ids whose shown name changed."""
        holders = self._holders.get(name)
        if holders is None:                 # the common case: a name nobody holds
            self._holders[name] = {node_id: created}
            self._winner[name] = node_id
            return []
        before = self._winner.get(name)
        holders[node_id] = created
        after = self._elect(name)
        return [i for i in (before, after) if i is not None and i != node_id and before != after]

    def remove(self, name: str, node_id: int) -> list[int]:
        before = self._winner.get(name)
        holders = self._holders.get(name)
        if holders is not None:
            holders.pop(node_id, None)
        after = self._elect(name)
        return [i for i in (before, after) if i is not None and i != node_id and before != after]

    def winner(self, name: str) -> int | None:
        return self._winner.get(name)

    def shown(self, name: str, node_id: int) -> str:
        return name if self._winner.get(name) == node_id else f"{name}#{node_id}"

    def lookup(self, shown: str) -> int | None:
        """Node id shown under `shown` (plain name or "<name>#<id>")."""
        winner = self._winner.get(shown)
        if winner is not None:
            return winner
        base, sep, suffix = shown.rpartition("#")
        if sep and suffix.isdigit():
            node_id = int(suffix)
            if node_id in self._holders.get(base, ()) and self._winner.get(base) != node_id:
                return node_id
        return None

    def clear(self) -> None:
        self._holders.clear()
        self._winner.clear()
