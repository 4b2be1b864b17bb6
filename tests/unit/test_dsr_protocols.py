"""dsr.protocols: DSRGraph meets GraphReader/GraphWriter member by member (mypy proves the types in
`make test`; this checks the names and parameter shapes at run time, so a split or rename of
DSRGraph that drops or renames a method agents call through the protocols fails here too)."""

from __future__ import annotations

import inspect
from collections.abc import Callable

import pytest

from dsr import DSRGraph
from dsr.protocols import GraphReader, GraphWriter


def _members(protocol: type) -> dict[str, object]:
    found: dict[str, object] = {}
    for klass in reversed(protocol.__mro__):
        if klass in (GraphReader, GraphWriter):
            found.update({k: v for k, v in vars(klass).items() if not k.startswith("_")})
    return found


def _shape(function: Callable[..., object]) -> list[tuple[str, inspect._ParameterKind, bool]]:
    parameters = inspect.signature(function).parameters.values()
    return [(p.name, p.kind, p.default is inspect.Parameter.empty) for p in parameters]


@pytest.mark.parametrize("protocol", [GraphReader, GraphWriter])
def test_dsr_graph_has_every_protocol_member_with_the_same_parameters(protocol: type) -> None:
    members = _members(protocol)
    assert "get_node_by_name" in members
    for name, member in members.items():
        actual = inspect.getattr_static(DSRGraph, name)
        if isinstance(member, property):
            assert isinstance(actual, property), name
            continue
        assert callable(member), name
        assert _shape(getattr(DSRGraph, name)) == _shape(member), name


def test_the_writer_adds_writes_and_the_reader_has_none() -> None:
    reader, writer = set(_members(GraphReader)), set(_members(GraphWriter))
    assert reader < writer
    assert {"insert_node", "update_node", "delete_node", "insert_or_assign_edge", "delete_edge",
            "transaction"} <= writer - reader

