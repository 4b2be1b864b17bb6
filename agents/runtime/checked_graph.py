"""The graph an agent is handed: every write passes through the vocabulary first.

Why a wrapper in the runtime (and not a check in each agent or in the DSR): the DSR knows no
vocabulary (it imports nothing of chronav), and a check each agent must remember to call is a
check that gets forgotten (``vocabulary.check_attrs`` was called only from a test while a typo'd
``now_S`` passed the ``*`` grants of the write policy).  ``run_agent`` (agents/runtime/base.py)
and the in-process scheduler (agents/runtime/lockstep.py) hand every agent a ``CheckedGraph``, so
no agent can write around the vocabulary.

A write of an unknown node type, edge type or attribute key, a value of the wrong kind, or a
state outside its set (``mission.state = "finished"``) is refused *before* it reaches the graph:
nothing changes, nothing is published, the agent goes on with its next statement (a refused
``insert_node`` returns None).  Like the write policy's refusals of remote deltas, each refusal
is logged (once per distinct refusal, then counted) and counted: ``CheckedGraph.refused``, and the
replica's counters under the reason ``vocabulary`` (what ``chronav dsr stats`` shows in its
"refused (by reason)" column).  Reads and everything else go to the wrapped graph unchanged.
"""

from __future__ import annotations

import logging
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from typing import Any

from agents.world.vocabulary import VocabularyError, check_attrs, check_edge

log = logging.getLogger("chronav.vocabulary")
#: the reason under which refusals are counted in the replica's stats (``chronav dsr stats``)
REASON = "vocabulary"
#: distinct refusal messages logged per graph; later ones are only counted
LOGGED_REFUSALS = 50


class CheckedGraph:
    """A DSR graph whose writes are checked against the vocabulary, on behalf of ``agent``."""

    def __init__(self, graph: Any, agent: str) -> None:
        self._graph = graph
        self.agent = agent
        #: writes refused so far, and the last refusal's sentence
        self.refused = 0
        self.last_refusal = ""
        self._seen: dict[str, int] = {}

    # Everything that is not a write is the wrapped graph's own (reads, signals, dispatch...).
    def __getattr__(self, name: str) -> Any:
        return getattr(self._graph, name)

    @property
    def unchecked(self) -> Any:
        """The wrapped graph (for the runtime's own bookkeeping, never for an agent's writes)."""
        return self._graph

    # ------------------------------------------------------------------ checked writes
    def insert_node(self, type: str, name: str, attrs: Mapping[str, Any] | None = None,
                    **kwargs: Any) -> Any:
        problem = _problem(lambda: check_attrs(type, attrs or {}))
        if problem is not None:
            return self._refuse(f"create node {name!r}", problem)
        return self._graph.insert_node(str(type), name, attrs, **kwargs)   # a StrEnum member: its plain value

    def update_node(self, node_id: int, attrs: Mapping[str, Any]) -> None:
        node_type = self._graph.node_type_of(node_id)   # no snapshot of the node: this is the hot path
        if node_type is not None:      # an unknown node: the graph's own error, as before
            problem = _problem(lambda: check_attrs(node_type, attrs))
            if problem is not None:
                return self._refuse(f"set attributes of {self._name(node_id)}", problem)
        return self._graph.update_node(node_id, attrs)

    def update_nodes(self, updates: Mapping[int, Mapping[str, Any]]) -> None:
        """All or nothing, like the graph's own batch: one refused node refuses the batch."""
        for node_id, attrs in updates.items():
            node_type = self._graph.node_type_of(node_id)
            if node_type is None:
                continue
            problem = _problem(lambda t=node_type, a=attrs: check_attrs(t, a))
            if problem is not None:
                return self._refuse(f"set attributes of {self._name(node_id)} (a batch of {len(updates)})", problem)
        return self._graph.update_nodes(updates)

    def _name(self, node_id: int) -> str:
        node = self._graph.get_node(node_id)
        return repr(node.name) if node is not None else f"node {node_id}"

    def insert_or_assign_edge(self, src: int, dst: int, type: str,
                              attrs: Mapping[str, Any] | None = None) -> Any:
        problem = _problem(lambda: check_edge(type, attrs or {}))
        if problem is not None:
            return self._refuse(f"write edge {src}->{dst}", problem)
        return self._graph.insert_or_assign_edge(src, dst, str(type), attrs)

    @contextmanager
    def transaction(self) -> Iterator[CheckedGraph]:
        """The graph's transaction; writes made through what it yields are checked too."""
        with self._graph.transaction():
            yield self

    # ------------------------------------------------------------------ refusals
    def _refuse(self, what: str, problem: str) -> None:
        text = (f"agent {self.agent!r} may not {what}: {problem} (agents/world/vocabulary.py); refused, "
                "the graph is unchanged")
        self.refused += 1
        self.last_refusal = text
        stats = getattr(getattr(self._graph, "replica", None), "stats", None)
        if stats is not None:      # shown by `chronav dsr stats`, beside the write policy's refusals
            stats.rejects[REASON] = stats.rejects.get(REASON, 0) + 1
            stats.last_reject = f"{self.agent} (own write): {text}"
        count = self._seen.get(text, 0) + 1
        if count == 1 and len(self._seen) >= LOGGED_REFUSALS:
            return None
        self._seen[text] = count
        if count == 1 or count % 1000 == 0:
            log.warning("DSR vocabulary: %s (%d time%s)", text, count, "" if count == 1 else "s")
        return None


def _problem(check: Any) -> str | None:
    try:
        check()
    except VocabularyError as exc:
        return str(exc)
    return None
