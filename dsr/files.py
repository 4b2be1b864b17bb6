"""Whole-graph JSON documents (initial worlds, snapshots), validated with pydantic.

Why a separate, human-oriented format: world files are written by hand, so edges may name their
ends by node name, ids are optional, and errors must point at the file and the field.
The CRDT state (tombstones, clocks) is not here: that is the wire "state" message.

    {"format": "chronav-dsr-graph/1",
     "nodes": [{"id": 1, "type": "world", "name": "world", "attrs": {}}, ...],
     "edges": [{"src": "world", "dst": "kitchen", "type": "RT",
                "attrs": {"x": 1.0, "y": 2.0, "theta": 0.0}}, ...]}
"""

from __future__ import annotations

from typing import Final, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from dsr.errors import GraphFileError
from dsr.model import AttrKey, AttrValueSchema, NodeId, NodeName, TypeName

FORMAT: Final = "chronav-dsr-graph/1"


class NodeDoc(BaseModel):
    model_config = ConfigDict(extra="forbid")
    id: NodeId | None = None
    type: TypeName
    name: NodeName
    attrs: dict[AttrKey, AttrValueSchema] = Field(default_factory=dict)


class EdgeDoc(BaseModel):
    model_config = ConfigDict(extra="forbid")
    src: NodeId | NodeName
    dst: NodeId | NodeName
    type: TypeName
    attrs: dict[AttrKey, AttrValueSchema] = Field(default_factory=dict)


class GraphDocument(BaseModel):
    model_config = ConfigDict(extra="forbid")
    format: Literal["chronav-dsr-graph/1"] = FORMAT
    nodes: list[NodeDoc] = Field(default_factory=list)
    edges: list[EdgeDoc] = Field(default_factory=list)

    @model_validator(mode="after")
    def _unique(self) -> GraphDocument:
        names: dict[str, int] = {}
        ids: dict[int, int] = {}
        for index, node in enumerate(self.nodes):
            if node.name in names:
                raise ValueError(f"nodes[{index}]: name {node.name!r} already used by "
                                 f"nodes[{names[node.name]}]")
            names[node.name] = index
            if node.id is not None:
                if node.id in ids:
                    raise ValueError(f"nodes[{index}]: id {node.id} already used by "
                                     f"nodes[{ids[node.id]}]")
                ids[node.id] = index
        return self


def parse_document(text: str | bytes, source: str = "<json>") -> GraphDocument:
    """Validate a graph document; GraphFileError names `source` and the failing field."""
    try:
        return GraphDocument.model_validate_json(text)
    except ValidationError as exc:
        first = exc.errors()[0]
        loc = ".".join(str(p) for p in first["loc"]) or "<root>"
        more = exc.error_count() - 1
        extra = f" (+{more} more errors)" if more > 0 else ""
        raise GraphFileError(f"{source}: {loc}: {first['msg']}{extra}") from None
