"""The DSR graph as agents and libraries use it: a read side and a write side, as typing Protocols.

Why: code outside the DSR took the graph as ``Any`` (66 signatures), so neither a reader nor mypy
could tell what a function does with it, and a wrapper (a read-only view, the runtime's checked
graph, a test double) had no contract to meet. ``GraphReader`` is what reading takes (queries,
poses, change signals); ``GraphWriter`` adds the writes and transactions. ``DSRGraph`` satisfies
both (checked by mypy below and by tests/unit/test_dsr_protocols.py); anything else with the same
methods does too, structurally, without inheriting from anything.

A function that only reads takes a ``GraphReader``: that says it does not change the graph.
"""

from __future__ import annotations

from collections.abc import Callable
from contextlib import AbstractContextManager
from typing import TYPE_CHECKING, Any, Protocol

from dsr.model import Attrs, Edge, Node
from dsr.poses import Pose

__all__ = ["GraphReader", "GraphWriter"]


class GraphReader(Protocol):
    """Reading the graph: nodes, edges, attributes, poses, and being told of changes."""

    @property
    def version(self) -> int: ...

    def get_node(self, node_id: int) -> Node | None: ...

    def get_node_by_name(self, name: str) -> Node | None: ...

    def node_id_of(self, name: str) -> int | None: ...

    def require_node(self, node: int | str) -> Node: ...

    def get_attr(self, node_id: int, key: str, default: Any = None) -> Any: ...

    def nodes(self) -> list[Node]: ...

    def nodes_of_type(self, type: str) -> list[Node]: ...

    def get_edge(self, src: int, dst: int, type: str) -> Edge | None: ...

    def edges(self) -> list[Edge]: ...

    def edges_from(self, node_id: int, type: str | None = None) -> list[Edge]: ...

    def edges_to(self, node_id: int, type: str | None = None) -> list[Edge]: ...

    def edges_of_type(self, type: str) -> list[Edge]: ...

    def rt_parent(self, node_id: int) -> Edge | None: ...

    def world_pose(self, node_id: int) -> Pose: ...

    def connect(self, signal: str, callback: Callable[..., Any]) -> None: ...

    def disconnect(self, signal: str, callback: Callable[..., Any]) -> None: ...

    def to_networkx(self) -> networkx.MultiDiGraph: ...


class GraphWriter(GraphReader, Protocol):
    """Reading and writing: node and edge changes, grouped by ``transaction`` into one delta."""

    def transaction(self) -> AbstractContextManager[GraphWriter]: ...

    def insert_node(self, type: str, name: str, attrs: Attrs | None = None,
                    *, id: int | None = None) -> Node: ...

    def update_node(self, node_id: int, attrs: Attrs) -> None: ...

    def update_nodes(self, updates: dict[int, Attrs]) -> None: ...

    def delete_node(self, node_id: int) -> None: ...

    def insert_or_assign_edge(self, src: int, dst: int, type: str, attrs: Attrs | None = None) -> Edge: ...

    def delete_edge(self, src: int, dst: int, type: str) -> None: ...

    def flush(self) -> None: ...


if TYPE_CHECKING:   # mypy proves DSRGraph meets both contracts; nothing runs
    import networkx

    from dsr.graph import DSRGraph

    def _dsr_graph_reads(graph: DSRGraph) -> GraphReader:
        return graph

    def _dsr_graph_writes(graph: DSRGraph) -> GraphWriter:
        return graph
