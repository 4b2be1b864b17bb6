"""AGM's world XML (``<AGMModel>``): read it into a planning graph, and write any graph as it.

Why: RoboComp's AGM tools exchange worlds as XML (``xmlModelParser.py`` reads them,
``AGMGraph.toXMLString`` writes them); reading them lets ``chronav plan`` plan on the same world
as AGM's ``agglplan``, writing them lets AGM tools read chronav's live symbolic graph.

The format, as AGM reads it::

    <AGMModel>
        <symbol id="1" type="robot" [x="..." y="..."]>
            <attribute key="k" value="v"/>*
        </symbol>*
        <link src="1" dst="2" label="in" [enabled="false"]>
            <linkAttribute key="k" value="v"/>*
        </link>*
    </AGMModel>

Symbol ids are strings (integers in practice); a link's ``src``/``dst`` must name symbols read
before it. A link with ``enabled`` = false/f/fa/fal/fals/0/n/no (any case) is *disabled*: AGM's
planner never sees it (its link tests compare ``enabled`` with True), so the planning graph leaves
it out; it is kept for writing the world back. Attribute values are strings, as in AGM.

In the planning graph (``networkx.MultiDiGraph``) a symbol is the node keyed by its id, with
``type``, ``name`` = its id (so that target constants, which are ids, find it) and its attributes;
an attribute whose key is ``name`` or ``type`` is kept as ``agm:name`` / ``agm:type`` so as not to
clash, and written back under its own key. Parsing uses defusedxml: no entity expansion, no DTD
tricks (a "billion laughs" file is refused, not expanded).
"""

from __future__ import annotations

import json
import os
from collections.abc import Hashable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from xml.sax.saxutils import quoteattr

import networkx as nx
from defusedxml import DefusedXmlException
from defusedxml.ElementTree import DefusedXMLParser, ParseError

from scenes.reading import read_bounded
from grammar.errors import GrammarError, shorten

RESERVED = ("name", "type")
PREFIX = "agm:"
DISABLED = frozenset({"false", "f", "fa", "fal", "fals", "0", "n", "no"})
MAX_WORLD_BYTES = 64 * 1024 * 1024  # a world file larger than this is refused, not read
_UNCLOSED = ("mismatched tag", "no element found", "unclosed token")  # expat: an element left open


class WorldFileError(GrammarError):
    """A world file that cannot be read: ``file:line:col: message`` like grammar errors."""


@dataclass
class AgmSymbol:
    id: str
    type: str
    attrs: dict[str, str] = field(default_factory=dict)
    x: str | None = None
    y: str | None = None


@dataclass
class AgmLink:
    src: str
    dst: str
    label: str
    enabled: bool = True
    attrs: dict[str, str] = field(default_factory=dict)


@dataclass
class AgmWorld:
    """An AGM world as written in the file (disabled links included)."""

    symbols: dict[str, AgmSymbol] = field(default_factory=dict)
    links: list[AgmLink] = field(default_factory=list)

    def to_networkx(self, include_disabled: bool = False) -> nx.MultiDiGraph:
        """The planning graph (disabled links left out unless asked, then with ``enabled=False``)."""
        graph = nx.MultiDiGraph()
        for symbol in self.symbols.values():
            data: dict[str, Any] = {(PREFIX + k if k in RESERVED else k): v for k, v in symbol.attrs.items()}
            if symbol.x is not None:
                data[PREFIX + "x"] = symbol.x
            if symbol.y is not None:
                data[PREFIX + "y"] = symbol.y
            graph.add_node(symbol.id, **data, type=symbol.type, name=symbol.id)
        for link in self.links:
            if not link.enabled and not include_disabled:
                continue
            attrs: dict[str, Any] = {(PREFIX + k if k in ("type", "enabled") else k): v for k, v in link.attrs.items()}
            if not link.enabled:
                attrs["enabled"] = False
            if graph.has_edge(link.src, link.dst, key=link.label):
                continue
            graph.add_edge(link.src, link.dst, key=link.label, **attrs, type=link.label)
        return graph


class _Builder:
    """ElementTree parser target that builds an ``AgmWorld`` and knows the line of each element."""

    def __init__(self, file: str) -> None:
        self.file = file
        self.world = AgmWorld()
        self.parser: DefusedXMLParser | None = None
        self.stack: list[str] = []
        self.opened: list[tuple[dict[str, str], int]] = []  # each open element's attributes and line
        self.symbol: AgmSymbol | None = None
        self.link: AgmLink | None = None

    def _where(self) -> tuple[int, int]:
        expat = getattr(self.parser, "parser", None)
        if expat is None:
            return 0, 0
        return expat.CurrentLineNumber, expat.CurrentColumnNumber + 1

    def error(self, message: str) -> WorldFileError:
        line, column = self._where()
        return WorldFileError(message, self.file, line, column)

    def _need(self, tag: str, attrs: Mapping[str, str], key: str) -> str:
        if key not in attrs:
            raise self.error(f"<{tag}> has no {key!r} attribute")
        return attrs[key]

    def unclosed(self) -> str | None:
        """The innermost open <symbol>/<link>, as written and where (for errors about a missing end)."""
        for (attrs, line), tag in zip(reversed(self.opened), reversed(self.stack)):
            if tag in ("symbol", "link"):
                shown = "".join(f" {k}={quoteattr(shorten(str(v), 40))}" for k, v in list(attrs.items())[:4])
                return f"<{tag}{shown}> opened at line {line}"
        return None

    def start(self, tag: str, attrs: dict[str, str]) -> None:
        parent = self.stack[-1] if self.stack else None
        if parent in ("symbol", "link") and tag in ("symbol", "link"):  # '<link ...>' meant as '<link .../>'
            raise self.error(f"<{tag}> inside {self.unclosed()}: that <{parent}> is not closed (end it "
                             f"with '/>' or '</{parent}>')")
        self.stack.append(tag)
        self.opened.append((attrs, self._where()[0]))
        if parent is None:
            if tag != "AGMModel":
                raise self.error(f"the root element is <{shorten(tag)}>; an AGM world is <AGMModel>")
        elif tag == "symbol" and parent == "AGMModel":
            symbol_id = self._need(tag, attrs, "id").strip()
            if not symbol_id:
                raise self.error("<symbol> has an empty 'id'")
            if symbol_id in self.world.symbols:
                raise self.error(f"symbol id {shorten(symbol_id)!r} is used twice")
            symbol_type = self._need(tag, attrs, "type").strip()
            if not symbol_type:
                raise self.error(f"symbol {shorten(symbol_id)!r} has an empty 'type'")
            self.symbol = AgmSymbol(symbol_id, symbol_type, x=attrs.get("x"), y=attrs.get("y"))
            self.world.symbols[symbol_id] = self.symbol
        elif tag == "link" and parent == "AGMModel":
            src, dst = self._need(tag, attrs, "src").strip(), self._need(tag, attrs, "dst").strip()
            label = self._need(tag, attrs, "label").strip()
            for end, role in ((src, "src"), (dst, "dst")):
                if end not in self.world.symbols:
                    raise self.error(f"link {shorten(src)}->{shorten(dst)}({shorten(label)}): {role} "
                                     f"{shorten(end)!r} is not a symbol declared before it")
            if not label:
                raise self.error(f"link {shorten(src)}->{shorten(dst)} has an empty 'label'")
            enabled = attrs.get("enabled", "true").strip().lower() not in DISABLED
            self.link = AgmLink(src, dst, label, enabled)
            self.world.links.append(self.link)
        elif tag == "attribute" and parent == "symbol" and self.symbol is not None:
            self.symbol.attrs[self._need(tag, attrs, "key")] = self._need(tag, attrs, "value")
        elif tag == "linkAttribute" and parent == "link" and self.link is not None:
            self.link.attrs[self._need(tag, attrs, "key")] = self._need(tag, attrs, "value")
        else:
            where = f"inside <{parent}>" if parent else "at the top"
            raise self.error(f"unexpected <{shorten(tag)}> {where}; an AGM world has <symbol> and <link> "
                             "in <AGMModel>, <attribute> in <symbol>, <linkAttribute> in <link>")

    def end(self, tag: str) -> None:
        self.stack.pop()
        self.opened.pop()
        if tag == "symbol":
            self.symbol = None
        elif tag == "link":
            self.link = None

    def data(self, text: str) -> None:
        pass

    def close(self) -> AgmWorld:
        return self.world


def parse_agm_world(text: str, file: str = "<string>") -> AgmWorld:
    """Parse AGM world XML text; errors are ``WorldFileError`` with file, line and column."""
    builder = _Builder(file)
    parser = DefusedXMLParser(target=builder, forbid_dtd=True, forbid_entities=True, forbid_external=True)
    builder.parser = parser
    try:
        parser.feed(text.removeprefix("\ufeff"))
        parser.close()   # returns the target's close(), typed as an Element by the stubs
        return builder.world
    except WorldFileError:
        raise
    except ParseError as exc:
        line, column = getattr(exc, "position", (0, 0))
        message = str(exc).split(":", 1)[0] if ":" in str(exc) else str(exc)
        open_element = builder.unclosed()
        hint = f": {open_element} is not closed" if open_element and message in _UNCLOSED else ""
        raise WorldFileError(f"not well-formed XML ({message}){hint}", file, line, column + 1) from None
    except DefusedXmlException as exc:
        line, column = builder._where()
        raise WorldFileError(f"refused: the file uses a DTD or entities ({type(exc).__name__}); an AGM "
                             "world needs neither", file, line, column) from None


def load_agm_world(path: str | os.PathLike[str]) -> AgmWorld:
    file = str(path)
    try:   # a regular file of at most MAX_WORLD_BYTES: never /dev/zero, a FIFO or a directory
        data = read_bounded(path, max_bytes=MAX_WORLD_BYTES, what="world file")
    except FileNotFoundError:
        raise WorldFileError("world file not found", file) from None
    except ValueError as exc:
        raise WorldFileError(str(exc), file) from None
    except OSError as exc:
        raise WorldFileError(f"cannot read world file: {exc.strerror or exc}", file) from None
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise WorldFileError(f"not UTF-8 text ({exc.reason})", file) from None
    return parse_agm_world(text, file)


# ----------------------------------------------------------------------------- writing
def _is_int(key: Hashable) -> bool:
    if isinstance(key, bool):
        return False
    if isinstance(key, int):
        return True
    return isinstance(key, str) and key.isdigit() and len(key) < 19


def _text(value: Any) -> str:
    if isinstance(value, str):
        return value
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(value)
    try:
        return json.dumps(value, default=str, sort_keys=True)
    except (TypeError, ValueError):
        return str(value)


def agm_ids(graph: nx.MultiDiGraph) -> dict[Hashable, str]:
    """The AGM symbol id of every node: its key when that is an integer (DSR ids, AGM worlds),
    else the next free integer, in node order."""
    ids = {key: str(int(key)) for key in graph.nodes if _is_int(key)}
    next_id = max((int(v) for v in ids.values()), default=0) + 1
    for key in graph.nodes:
        if key not in ids:
            ids[key] = str(next_id)
            next_id += 1
    return ids


def agm_world_xml(graph: nx.MultiDiGraph) -> str:
    """``graph`` (nodes with ``type``/``name``, edges typed by attribute ``type`` or key) as AGM
    world XML, laid out like ``AGMGraph.toXMLString``: symbols by id, then links by (src, dst,
    label). A node whose name differs from its id keeps it as attribute ``name``."""
    ids = agm_ids(graph)
    lines = ["<AGMModel>"]
    for key in sorted(graph.nodes, key=lambda k: int(ids[k])):
        data = graph.nodes[key]
        node_type = str(data.get("type", "unknown"))
        attrs: dict[str, str] = {}
        name = data.get("name")
        if name is not None and str(name) != ids[key]:
            attrs["name"] = _text(name)
        pos = ""
        for k, v in data.items():
            if k in RESERVED:
                continue
            if k in (PREFIX + "x", PREFIX + "y"):
                pos += f" {k[len(PREFIX):]}={quoteattr(_text(v))}"
                continue
            attrs[k[len(PREFIX):] if k.startswith(PREFIX) else str(k)] = _text(v)
        lines.append(f"\t<symbol id={quoteattr(ids[key])} type={quoteattr(node_type)}{pos}>")
        for k in sorted(attrs):
            lines.append(f"\t\t<attribute key={quoteattr(k)} value={quoteattr(attrs[k])} />")
        lines.append("\t</symbol>")
    edges = []
    for src, dst, key, data in graph.edges(keys=True, data=True):
        label = data.get("type", key)
        edges.append((int(ids[src]), int(ids[dst]), str(label), src, dst, data))
    for s, d, label, _src, _dst, data in sorted(edges, key=lambda e: e[:3]):
        enabled = "" if data.get("enabled", True) is not False else ' enabled="false"'
        lines.append(f"\t<link src=\"{s}\" dst=\"{d}\" label={quoteattr(label)}{enabled}>")
        for k in sorted(str(k) for k in data if k not in ("type", "enabled")):
            name = k[len(PREFIX):] if k.startswith(PREFIX) else k
            lines.append(f"\t\t<linkAttribute key={quoteattr(name)} value={quoteattr(_text(data[k]))} />")
        lines.append("\t</link>")
    lines.append("</AGMModel>")
    return "\n".join(lines) + "\n"


# ----------------------------------------------------------------------------- any world file
def load_world(path: str | os.PathLike[str]) -> nx.MultiDiGraph:
    """A planning world from a file: AGM world XML (``.xml``) or a networkx node-link JSON graph
    (``.json``: ``{"nodes": [{"id": .., "type": .., "name": ..}], "links"|"edges": [{"source": ..,
    "target": .., "key"|"type": ..}]}``)."""
    file = str(path)
    suffix = Path(path).suffix.lower()
    if suffix == ".xml":
        return load_agm_world(path).to_networkx()
    if suffix != ".json":
        raise WorldFileError(f"unknown world file type {shorten(suffix or '(none)')!r}: use an AGM world "
                             "(.xml) or a node-link graph (.json)", file)
    try:
        text = read_bounded(path, max_bytes=MAX_WORLD_BYTES, what="world file").decode("utf-8-sig")
    except FileNotFoundError:
        raise WorldFileError("world file not found", file) from None
    except UnicodeDecodeError as exc:
        raise WorldFileError(f"not UTF-8 text ({exc.reason})", file) from None
    except ValueError as exc:   # not a regular file, or too large
        raise WorldFileError(str(exc), file) from None
    except OSError as exc:
        raise WorldFileError(f"cannot read world file: {getattr(exc, 'strerror', None) or exc}", file) from None
    try:
        data = json.loads(text)
    except (ValueError, RecursionError) as exc:
        line, column = getattr(exc, "lineno", 0), getattr(exc, "colno", 0)
        raise WorldFileError(f"not JSON ({getattr(exc, 'msg', exc)})", file, line, column) from None
    return node_link_world(data, file)


def node_link_world(data: Any, file: str = "<json>") -> nx.MultiDiGraph:
    """Check the shape of a node-link document before networkx reads it (a list, or nodes that
    are not objects, would otherwise end in an AttributeError)."""
    if not isinstance(data, dict):
        raise WorldFileError(f"a world must be a JSON object with 'nodes' and 'links', not a "
                             f"{type(data).__name__}", file)
    nodes = data.get("nodes")
    if not isinstance(nodes, list):
        raise WorldFileError("key 'nodes': expected a list of node objects", file)
    edges_key = "links" if "links" in data else "edges"
    edges = data.get(edges_key, [])
    if not isinstance(edges, list):
        raise WorldFileError(f"key {edges_key!r}: expected a list of link objects", file)
    for i, node in enumerate(nodes):
        if not isinstance(node, dict) or "id" not in node:
            raise WorldFileError(f"nodes[{i}]: expected an object with an 'id'", file)
        if not isinstance(node.get("type"), str) or not node["type"]:
            raise WorldFileError(f"nodes[{i}] (id {shorten(str(node['id']))!r}): no 'type'", file)
    ids = {_hashable(node["id"]) for node in nodes}
    for i, edge in enumerate(edges):
        if not isinstance(edge, dict) or "source" not in edge or "target" not in edge:
            raise WorldFileError(f"{edges_key}[{i}]: expected an object with 'source' and 'target'", file)
        for end in ("source", "target"):
            if _hashable(edge[end]) not in ids:
                raise WorldFileError(f"{edges_key}[{i}]: {end} {shorten(str(edge[end]))!r} is not a node id", file)
        if not isinstance(edge.get("type", edge.get("key")), str):
            raise WorldFileError(f"{edges_key}[{i}]: no 'type' (or string 'key') for the link", file)
    from networkx.readwrite import json_graph

    try:
        return json_graph.node_link_graph({**data, "directed": True, "multigraph": True}, directed=True,
                                          multigraph=True, edges=edges_key)
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise WorldFileError(f"not a node-link graph: {shorten(str(exc), 200)}", file) from None


def _hashable(value: Any) -> Any:
    return json.dumps(value, sort_keys=True) if isinstance(value, (list, dict)) else value
