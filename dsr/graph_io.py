"""Graph import and export: graph documents (JSON, dsr/files.py format) and networkx copies.

Why its own module: reading and writing whole graphs is a use of the graph's public queries
and writes, not part of replication; DSRGraph's methods of the same names (to_json, load_json,
to_networkx, save, load...) call these functions, so agents and tools keep calling the graph.
Every function here that reads takes the visible graph as the queries show it.
"""

from __future__ import annotations

import hashlib
from pathlib import Path
from typing import TYPE_CHECKING, Any

import orjson

from dsr.errors import DSRError, GraphFileError
from dsr.model import check_name

if TYPE_CHECKING:
    import networkx

    from dsr.graph import DSRGraph


def to_document(graph: DSRGraph) -> dict[str, Any]:
    """The visible graph as a plain dict in the graph-file format (files.py)."""
    from dsr.files import FORMAT
    return {"format": FORMAT,
            "nodes": [{"id": n.id, "type": n.type, "name": n.name, "attrs": n.attrs}
                      for n in graph.nodes()],
            "edges": [{"src": e.src, "dst": e.dst, "type": e.type, "attrs": e.attrs}
                      for e in graph.edges()]}


def to_json(graph: DSRGraph, indent: bool = False) -> str:
    """The graph document as canonical JSON (sorted keys)."""
    option = orjson.OPT_SORT_KEYS | (orjson.OPT_INDENT_2 if indent else 0)
    return orjson.dumps(graph.to_document(), option=option).decode()


def digest(graph: DSRGraph) -> str:
    """SHA-256 of the canonical visible graph: equal digests = identical graphs."""
    return hashlib.sha256(to_json(graph).encode()).hexdigest()


def to_networkx(graph: DSRGraph) -> networkx.MultiDiGraph:
    """Copy of the visible graph: nodes keyed by id with data {**attrs, type, name}
    (type/name win over attributes of the same key); edges keyed by edge type."""
    import networkx as nx
    copy = nx.MultiDiGraph(name=graph.graph_name)
    for node in graph.nodes():
        copy.add_node(node.id, **{**node.attrs, "type": node.type, "name": node.name})
    for edge in graph.edges():
        copy.add_edge(edge.src, edge.dst, key=edge.type, **{**edge.attrs, "type": edge.type})
    return copy


def load_json(graph: DSRGraph, text: str | bytes, source: str = "<json>") -> list[int]:
    """Insert a graph document into `graph` in one transaction; returns the node ids.  A bad
    document raises GraphFileError naming `source`, the entry and the problem."""
    from dsr.files import parse_document
    document = parse_document(text, source)
    with graph.transaction():
        return _insert_document(graph, document, source)


def _insert_document(graph: DSRGraph, document: Any, source: str) -> list[int]:
    ids: list[int] = []
    by_name: dict[str, int] = {}
    for index, node in enumerate(document.nodes):
        try:
            check_name(node.name, allow_hash=True)
            created = graph.insert_file_node(node.type, node.name, dict(node.attrs), node.id)
        except DSRError as exc:
            raise GraphFileError(f"{source}: nodes[{index}] ({node.name!r}): {exc}") from None
        ids.append(created.id)
        by_name[node.name] = created.id
    for index, edge in enumerate(document.edges):
        ends = []
        for end in (edge.src, edge.dst):
            if isinstance(end, str):
                found = by_name.get(end) or graph.node_id_of(end)
                if found is None:
                    raise GraphFileError(f"{source}: edges[{index}]: unknown node name {end!r}")
                ends.append(found)
            else:
                ends.append(end)
        try:
            graph.insert_or_assign_edge(ends[0], ends[1], edge.type, dict(edge.attrs))
        except DSRError as exc:
            raise GraphFileError(f"{source}: edges[{index}]: {exc}") from None
    return ids


def save(graph: DSRGraph, path: str) -> None:
    Path(path).write_text(to_json(graph, indent=True) + "\n", encoding="utf-8")


def read(path: str) -> bytes:
    """The bytes of a graph file, or GraphFileError saying why it cannot be read."""
    try:
        return Path(path).read_bytes()
    except OSError as exc:
        raise GraphFileError(f"{path}: cannot read: {exc.strerror}") from None
