"""The JSON wire format of DSR messages and the Zenoh key space (spec: docs/dsr_wire_format.md).

Why JSON + pydantic: any Zenoh client in any language can read and write the graph with a
JSON library, and one pydantic schema gives exact, field-naming errors for whatever arrives.
Messages are encoded with orjson; received ones are parsed and validated by msgspec structs
in C when they can be (the common case, see "struct validator" below), else by pydantic's Rust
core, whose schema stays the definition and words the errors.
"""

from __future__ import annotations

import operator
import re
from collections.abc import Iterable
from typing import Annotated, Any, Literal, Union

import msgspec
import orjson
from msgspec import Meta
from pydantic import BaseModel, ConfigDict, Field, StringConstraints, ValidationError

from dsr.crdt import REMOVAL_RECEIPT, Dots, ElementState, Register
from dsr.limits import LIMITS, value_bytes
from dsr.model import (AGENT_PATTERN, ATTR_KEY_PATTERN, NAME_PATTERN, TYPE_PATTERN, AgentName,
                       AttrKey, AttrValueSchema, NodeId, NodeName, TypeName, UInt63)

FORMAT = "chronav-dsr/1"
ENCODING = "application/json;chronav-dsr/1"
KEY_PREFIX = "chronav"

EdgeKey = tuple[int, int, str]
ReplicaId = Annotated[int, Field(strict=True, ge=1, le=2**63 - 1)]
Dot = tuple[ReplicaId, UInt63]
WireRegister = tuple[UInt63, ReplicaId, AttrValueSchema]
#: keys of a state's `writers` table: a replica id in decimal (JSON keys are strings)
REPLICA_KEY_PATTERN = r"^[1-9][0-9]{0,18}$"
ReplicaKey = Annotated[str, StringConstraints(pattern=REPLICA_KEY_PATTERN)]


class _Entry(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)
    add: list[Dot] = []
    rem: list[Dot] = []
    cleared: UInt63 = 0
    attrs: dict[AttrKey, WireRegister] = {}


class NodeEntry(_Entry):
    id: NodeId
    meta: tuple[UInt63, ReplicaId, TypeName, NodeName] | None = None


class EdgeEntry(_Entry):
    src: NodeId
    dst: NodeId
    type: TypeName


class Message(BaseModel):
    """One delta (kind "delta", published on the delta key), a full state (query reply), or a
    digest (kind "digest", on the delta key: the sender's clock and what it has seen)."""

    model_config = ConfigDict(extra="forbid", frozen=True)
    format: Literal["chronav-dsr/1"]
    kind: Literal["delta", "state", "digest"]
    graph: AgentName
    agent: AgentName
    replica: ReplicaId
    #: state replies only: which agent wrote with which replica id (decimal string keys)
    writers: dict[ReplicaKey, AgentName] = {}
    #: states and digests: the sender's HLC when it sent the message (every write it made up to
    #: this time was published before it, on the same key)
    clock: UInt63 = 0
    #: states and digests: per writer replica, the sender holds every write it stamped up to hlc
    seen: dict[ReplicaKey, UInt63] = {}
    nodes: list[NodeEntry] = []
    edges: list[EdgeEntry] = []


_TYPE_RE = re.compile(TYPE_PATTERN)
_AGENT_RE = re.compile(AGENT_PATTERN)


# ---- key space --------------------------------------------------------------------------------

def delta_key(graph: str, agent: str) -> str:
    return f"{KEY_PREFIX}/{graph}/delta/{agent}"


def state_key(graph: str, agent: str) -> str:
    return f"{KEY_PREFIX}/{graph}/state/{agent}"


def member_key(graph: str, agent: str) -> str:
    return f"{KEY_PREFIX}/{graph}/members/{agent}"


def last_chunk(key: str) -> str:
    """The agent name a key claims (its last chunk)."""
    return key.rsplit("/", 1)[-1]


# ---- encode -----------------------------------------------------------------------------------

def _entry_fields(entry: dict[str, object], state: ElementState) -> dict[str, object]:
    if state.add:
        entry["add"] = list(state.add.items())
    if state.rem:
        entry["rem"] = list(state.rem.items())
    if state.cleared:
        entry["cleared"] = state.cleared
    if state.attrs:
        entry["attrs"] = state.attrs
    return entry


def node_entry(node_id: int, state: ElementState) -> dict[str, object]:
    entry: dict[str, object] = {"id": node_id}
    if state.meta is not None:
        hlc, replica, (type_, name) = state.meta
        entry["meta"] = (hlc, replica, type_, name)
    return _entry_fields(entry, state)


def edge_entry(key: EdgeKey, state: ElementState) -> dict[str, object]:
    return _entry_fields({"src": key[0], "dst": key[1], "type": key[2]}, state)


class DeltaEncoder:
    """Encodes this replica's deltas with a pre-serialised header (hot path of every write)."""

    def __init__(self, graph: str, agent: str, replica: int) -> None:
        self._prefix = (b'{"format":"' + FORMAT.encode() + b'","kind":"delta","graph":'
                        + orjson.dumps(graph) + b',"agent":' + orjson.dumps(agent)
                        + b',"replica":' + str(replica).encode() + b',"nodes":')

    def encode(self, nodes: list[dict[str, object]], edges: list[dict[str, object]]) -> bytes:
        return self._prefix + orjson.dumps(nodes) + b',"edges":' + orjson.dumps(edges) + b"}"

    def digest(self, clock: int, seen: dict[int, int]) -> bytes:
        """A digest: this replica's clock and watermarks, on the delta key (docs: "Digests")."""
        return (self._prefix.replace(b'"kind":"delta"', b'"kind":"digest"')
                + b'[],"edges":[],"clock":' + str(clock).encode() + b',"seen":'
                + orjson.dumps({str(r): h for r, h in seen.items()}) + b"}")

    def node_attrs(self, node_id: int, attrs: dict[str, tuple[int, int, object]]) -> bytes:
        return (self._prefix + b'[{"id":' + str(node_id).encode() + b',"attrs":'
                + orjson.dumps(attrs) + b'}],"edges":[]}')


def encode(*, kind: str, graph: str, agent: str, replica: int,
           nodes: Iterable[tuple[int, ElementState]], edges: Iterable[tuple[EdgeKey, ElementState]],
           writers: dict[int, str] | None = None, clock: int = 0,
           seen: dict[int, int] | None = None) -> bytes:
    message: dict[str, object] = {"format": FORMAT, "kind": kind, "graph": graph,
                                  "agent": agent, "replica": replica}
    if writers:
        message["writers"] = {str(r): a for r, a in writers.items()}
    if clock:
        message["clock"] = clock
    if seen:
        message["seen"] = {str(r): h for r, h in seen.items()}
    message["nodes"] = [node_entry(i, s) for i, s in nodes]
    message["edges"] = [edge_entry(k, s) for k, s in edges]
    return orjson.dumps(message)


def encode_parts(*, kind: str, graph: str, agent: str, replica: int, nodes: list[bytes],
                 edges: list[bytes], writers: dict[int, str] | None = None, clock: int = 0,
                 seen: dict[int, int] | None = None) -> bytes:
    """`encode` for elements already encoded one by one (the JSON of node_entry/edge_entry):
    the same bytes, spliced (DSRGraph.state_parts caches each element's JSON)."""
    head = encode(kind=kind, graph=graph, agent=agent, replica=replica, nodes=(), edges=(),
                  writers=writers, clock=clock, seen=seen)
    tail = b'"nodes":[],"edges":[]}'
    if not head.endswith(tail):
        raise AssertionError("encode() must end with the nodes and edges lists")
    return (head[:-len(tail)] + b'"nodes":[' + b",".join(nodes) + b'],"edges":['
            + b",".join(edges) + b"]}")


# ---- decode + checks --------------------------------------------------------------------------

def _describe(error: ValidationError, limit: int = 3) -> str:
    parts = []
    for item in error.errors()[:limit]:
        loc = ".".join(str(p) for p in item["loc"]) or "<root>"
        parts.append(f"{loc}: {item['msg']}")
    more = error.error_count() - limit
    return "; ".join(parts) + (f" (+{more} more)" if more > 0 else "")


class Decoded:
    """A validated message, already in the replica's internal form: (id, ElementState) and
    ((src, dst, type), ElementState) pairs, so that merging a state into an empty graph is
    just installing the decoded elements.  `top_hlc` is the largest timestamp it mentions."""

    __slots__ = ("agent", "clock", "edges", "graph", "kind", "nodes", "replica", "seen",
                 "top_hlc", "writers")

    def __init__(self, kind: str, graph: str, agent: str, replica: int, writers: dict[str, str],
                 nodes: list[tuple[int, ElementState]],
                 edges: list[tuple[EdgeKey, ElementState]], top_hlc: int, clock: int = 0,
                 seen: dict[int, int] | None = None) -> None:
        self.kind, self.graph, self.agent, self.replica = kind, graph, agent, replica
        self.writers, self.nodes, self.edges, self.top_hlc = writers, nodes, edges, top_hlc
        self.clock, self.seen = clock, seen or {}
        if clock > top_hlc:
            self.top_hlc = clock


def _state_of(entry: _Entry, meta: tuple[int, int, str, str] | None) -> ElementState:
    state = ElementState(cleared=entry.cleared, attrs=dict(entry.attrs))
    for replica, hlc in entry.add:
        if hlc > state.add.get(replica, -1):
            state.add[replica] = hlc
    for replica, hlc in entry.rem:
        if hlc > state.rem.get(replica, -1):
            state.rem[replica] = hlc
    if meta is not None:
        state.meta = (meta[0], meta[1], (meta[2], meta[3]))
    return state


def _from_model(message: Message) -> Decoded:
    nodes = [(n.id, _state_of(n, n.meta)) for n in message.nodes]
    edges = [((e.src, e.dst, e.type), _state_of(e, None)) for e in message.edges]
    for entries in (nodes, edges):
        for _, state in entries:
            for key, reg in state.attrs.items():
                if type(reg[2]) in (str, list) and value_bytes(reg[2]) > LIMITS.max_value_bytes:
                    from dsr.errors import WireError
                    raise WireError(f"invalid DSR message: attribute {key!r}: value of "
                                    f"{value_bytes(reg[2])} bytes exceeds the limit of "
                                    f"{LIMITS.max_value_bytes} bytes per value")
    return Decoded(message.kind, message.graph, message.agent, message.replica,
                   dict(message.writers), nodes, edges, _top_hlc(nodes, edges), message.clock,
                   {int(r): h for r, h in message.seen.items()})


def _top_hlc(nodes: list[tuple[int, ElementState]],
             edges: list[tuple[EdgeKey, ElementState]]) -> int:
    best = 0
    for entries in (nodes, edges):
        for _, state in entries:
            top = state.max_hlc()
            if top > best:
                best = top
    return best


def decode(payload: bytes) -> Decoded:
    """Parse and validate one message, or raise WireError naming the offending field.

    The pydantic `Message` schema is the definition.  A fast validator, msgspec structs
    validated in C (`struct_decode`), accepts a subset of what the schema accepts and builds
    the same result; anything else (malformed, or beyond its conservative cuts, such as a
    string of over a quarter of the value limit in characters) goes through pydantic, which
    either accepts it or produces the error (differential property tests,
    tests/unit/test_dsr_wire.py, check that the two agree).
    """
    from dsr.errors import WireError
    fast = struct_decode(payload)
    if fast is not None:
        return fast
    try:
        return _from_model(Message.model_validate_json(payload))
    except ValidationError as exc:
        raise WireError(f"invalid DSR message: {_describe(exc)}") from None


def foreign_writer(message: Decoded) -> str | None:
    """In a delta every add, meta and attribute must be written by the sending replica.

    Returns a description of the first violation, or None.  (`rem` legitimately names other
    replicas: it lists the adds the remover observed.)
    """
    own = message.replica
    for entries in (message.nodes, message.edges):
        for _, state in entries:
            for replica in state.add:
                if replica != own:
                    return f"add dot of replica {replica}"
            for key, reg in state.attrs.items():
                if reg[1] != own:
                    return f"attribute {key!r} written by replica {reg[1]}"
            if state.meta is not None and state.meta[1] != own:
                return f"meta written by replica {state.meta[1]}"
    return None


def removal_problem(message: Decoded) -> str | None:
    """The one rule for removals, in deltas and in state replies alike: an entry with `rem`
    or `cleared` carries the receipt ``attrs["~removed"] = [cleared, remover, true]`` and no
    `rem` dot newer than `cleared`.  Returns a description of the first violation, or None."""
    for what, entries in (("node", message.nodes), ("edge", message.edges)):
        for key, state in entries:
            if not state.rem and not state.cleared:
                continue
            receipt = state.attrs.get(REMOVAL_RECEIPT)
            if receipt is None or receipt[0] != state.cleared or receipt[2] is not True:
                return (f"a removal of {what} {key} without a receipt naming its remover "
                        f"(attrs[{REMOVAL_RECEIPT!r}] = [cleared, remover replica, true])")
            if any(hlc > state.cleared for hlc in state.rem.values()):
                return f"a removal of {what} {key} whose rem holds adds newer than cleared"
    return None


def max_hlc(message: Decoded) -> int:
    return message.top_hlc


# ---- fast validator (msgspec: the common messages, validated in C) --------------------------

_U63 = 2**63 - 1
_MAX_VALUE = LIMITS.max_value_bytes
_BIG = float(2**63)
_INT64_MIN = -(2**63)


class _Reject(Exception):
    """Internal: the fast validator declines; pydantic decides."""


class _Checked:
    """Bounded memo of strings already matched against a pattern (names repeat endlessly)."""

    def __init__(self, pattern: re.Pattern[str], size: int = 4096) -> None:
        self._pattern = pattern
        self._ok: set[str] = set()
        self._size = size

    def __call__(self, value: object) -> str:
        if type(value) is not str:
            raise _Reject
        if value in self._ok:
            return value
        if not self._pattern.fullmatch(value):
            raise _Reject
        if len(self._ok) >= self._size:
            self._ok.clear()
        self._ok.add(value)
        return value


_type_name = _Checked(_TYPE_RE)
_agent_name = _Checked(_AGENT_RE)

# Why a fast validator before pydantic: building pydantic models and converting them to element
# states, or parsing with orjson and walking the result in Python (the previous fast path), cost
# ~100 ms for a 10k-node state and most of an update's receive cost; msgspec parses straight
# into typed structs and checks the bounds while parsing.  Its types are built from the
# schema's patterns and limits (the differential test holds them to the schema), with
# conservative cuts that send a message to pydantic: a string value is capped in characters
# (4 UTF-8 bytes each at most), a number beyond +-2**63 is refused even as a float, and so is
# a lone surrogate.  Cost: regex calls for tens of thousands of names and keys
# would double the parse, so a payload without any backslash (no JSON escape: no control
# character can hide in it, raw ones are invalid JSON) checks names and keys by length only;
# type and agent names repeat, so they are checked against memos after parsing.

def _anchored(pattern: str) -> str:
    """msgspec searches (re.search); '$' would also match before a trailing newline."""
    if not (pattern.startswith("^") and pattern.endswith("$")):
        raise ValueError(f"pattern {pattern!r} must be anchored with ^...$")
    return pattern[:-1] + r"\Z"


def _text(pattern: str, escapes: bool) -> Any:
    """A string type for a "no control character, min to max long" pattern: the pattern
    itself when the payload holds escapes, its length bounds otherwise."""
    bounds = re.fullmatch(r"\^\[\^\\x00-\\x1f\]\{(\d+),(\d+)\}\$", pattern)
    if bounds is None:
        raise ValueError(f"pattern {pattern!r} is not 'no control character, min..max long'")
    if escapes:
        return Annotated[str, Meta(pattern=_anchored(pattern))]
    return Annotated[str, Meta(min_length=int(bounds[1]), max_length=int(bounds[2]))]


_MU63 = Annotated[int, Meta(ge=0, le=_U63)]
_MReplica = Annotated[int, Meta(ge=1, le=_U63)]
_MNodeId = Annotated[int, Meta(ge=1, le=_U63)]
_MFloat = Annotated[float, Meta(gt=-_BIG, lt=_BIG)]   # finite; ints in lists become floats
_MInt64 = Annotated[int, Meta(ge=_INT64_MIN, le=_U63)]
_MStr = Annotated[str, Meta(max_length=_MAX_VALUE // 4)]


def _struct(name: str, fields: list[tuple[Any, ...]]) -> type:
    return msgspec.defstruct(name, fields, kw_only=True, forbid_unknown_fields=True)


def _of(origin: Any, *args: Any) -> Any:
    """`origin[args]`: a type built at run time from types held in variables (what msgspec
    decodes into), which a static type checker cannot follow when written as a subscript."""
    return origin[args if len(args) > 1 else args[0]]


def _wire_struct(list_item: Any, escapes: bool) -> type:
    """The message struct whose list values hold `list_item` (a union has one array type).
    Type and agent names are plain strings here: `struct_decode` checks them against memos
    of names already matched (a regex call per message would double an update's parse)."""
    value = _of(Union, bool, _MInt64, _MFloat, _MStr,
                _of(Annotated, _of(list, list_item), Meta(max_length=_MAX_VALUE // 8)))
    register = _of(tuple, _MU63, _MReplica, value)
    dots = list[tuple[_MReplica, _MU63]]
    entry = [("add", dots, []), ("rem", dots, []), ("cleared", _MU63, 0),
             ("attrs", _of(dict, _text(ATTR_KEY_PATTERN, escapes), register), {})]
    meta = _of(tuple, _MU63, _MReplica, str, _text(NAME_PATTERN, escapes))
    node = _struct("Node", [("id", _MNodeId), *entry, ("meta", meta | None, None)])
    edge = _struct("Edge", [("src", _MNodeId), ("dst", _MNodeId), ("type", str), *entry])
    return _struct("Wire", [
        ("format", Literal["chronav-dsr/1"]), ("kind", Literal["delta", "state", "digest"]),
        ("graph", str), ("agent", str), ("replica", _MReplica),
        ("writers", dict[_MReplica, str], {}), ("clock", _MU63, 0),
        ("seen", dict[_MReplica, _MU63], {}), ("nodes", _of(list, node), []),
        ("edges", _of(list, edge), [])])


def _decoders(escapes: bool) -> tuple[msgspec.json.Decoder[Any], msgspec.json.Decoder[Any]]:
    """Numeric lists only (ints become floats; nothing to check after parsing), then lists of
    numbers or strings (the all-numeric / all-string rule and the byte size of string lists
    are checked by `_lists_ok`: only messages holding a string list pay for it)."""
    return (msgspec.json.Decoder(_wire_struct(_MFloat, escapes)),
            msgspec.json.Decoder(_wire_struct(Union[_MFloat, str], escapes)))  # noqa: UP007


_PLAIN = _decoders(escapes=False)
_ESCAPED = _decoders(escapes=True)
_TYPE_OK = _type_name._ok    # names already matched (cleared in place when full)
_AGENT_OK = _agent_name._ok
_hlc_of = operator.itemgetter(0)
_hlc_of_dot = operator.itemgetter(1)


def _lists_ok(entries: list[Any]) -> bool:
    """The list values of the mixed decoder: all numbers or all strings, and a string list
    within the value limit (its bytes are the sum of its strings')."""
    for raw in entries:
        for reg in raw.attrs.values():
            value = reg[2]
            if type(value) is list and value:
                kind = type(value[0])
                if any(type(item) is not kind for item in value) \
                        or kind is str and value_bytes(value) > _MAX_VALUE:
                    return False
    return True


def _dots(pairs: list[tuple[int, int]]) -> Dots:
    """Decoded dots as replica -> latest hlc (sorted: a replica's largest stamp wins)."""
    return dict(pairs) if len(pairs) == 1 else dict(sorted(pairs))


def _entry_state(raw: Any, meta: Register | None, regs: list[Register],
                 dots: list[tuple[int, int]]) -> ElementState:
    """The element state of a whole decoded entry (not a plain update).  Its registers and
    dots are added to `regs` and `dots`: the caller takes their largest stamp once for the
    whole message (a max per element was a fifth of decoding a 10k-node state)."""
    add, rem, attrs = raw.add, raw.rem, raw.attrs
    if attrs:
        regs.extend(attrs.values())
    if add:
        dots.extend(add)
        add = _dots(add)
    else:
        add = {}
    if rem:
        dots.extend(rem)
        rem = _dots(rem)
    else:
        rem = {}
    return ElementState(add, rem, raw.cleared, meta, attrs)


def struct_decode(payload: bytes) -> Decoded | None:
    """Validated message for what the msgspec structs accept, None to defer to the others."""
    numeric, mixed = _ESCAPED if b"\\" in payload else _PLAIN
    try:
        message = numeric.decode(payload)
    except msgspec.ValidationError as exc:
        if "got `str`" not in str(exc):   # only a string in a list value needs the mixed one
            return None
        try:
            message = mixed.decode(payload)
        except msgspec.DecodeError:   # ValidationError is one
            return None
        if not (_lists_ok(message.nodes) and _lists_ok(message.edges)):
            return None
    except msgspec.DecodeError:
        return None
    nodes = []
    edges = []
    top = 0
    regs: list[Register] = []          # of whole entries (see _entry_state)
    dots: list[tuple[int, int]] = []
    try:
        if message.graph not in _AGENT_OK or message.agent not in _AGENT_OK:
            _agent_name(message.graph)
            _agent_name(message.agent)
        writers = message.writers
        if writers:
            writers = {str(replica): _agent_name(agent) for replica, agent in writers.items()}
        for raw in message.nodes:
            meta, attrs = raw.meta, raw.attrs
            if meta is None and not raw.add and not raw.rem and not raw.cleared:
                nodes.append((raw.id, ElementState({}, {}, 0, None, attrs)))  # an update:
                if attrs and (stamp := max(map(_hlc_of, attrs.values()))) > top:  # hot path
                    top = stamp
                continue
            if meta is not None:
                if meta[2] not in _TYPE_OK:
                    _type_name(meta[2])
                if meta[0] > top:
                    top = meta[0]
                meta = (meta[0], meta[1], (meta[2], meta[3]))
            if raw.cleared > top:
                top = raw.cleared
            nodes.append((raw.id, _entry_state(raw, meta, regs, dots)))
        for raw in message.edges:
            type_ = raw.type
            if type_ not in _TYPE_OK:
                _type_name(type_)
            if raw.cleared > top:
                top = raw.cleared
            edges.append(((raw.src, raw.dst, type_), _entry_state(raw, None, regs, dots)))
    except _Reject:
        return None
    if regs and (stamp := max(map(_hlc_of, regs))) > top:
        top = stamp
    if dots and (stamp := max(map(_hlc_of_dot, dots))) > top:
        top = stamp
    return Decoded(message.kind, message.graph, message.agent, message.replica, writers,
                   nodes, edges, top, message.clock, message.seen)
