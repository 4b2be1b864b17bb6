"""Value types of the DSR: nodes, edges, attribute values, and their validation rules.

Why two layers: `Node`/`Edge` are the cheap immutable snapshots agents receive from queries and
signals (plain dataclasses, built thousands of times per second); the pydantic annotations
below are the single source of validation rules, reused by the JSON file schema (files.py) and
the wire schema (wire.py) so that a value accepted locally is accepted by every other replica.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from typing import Annotated, Any, Union

from pydantic import AfterValidator, AllowInfNan, BeforeValidator, Field, Strict, StringConstraints

from dsr.errors import InvalidAttributeError, InvalidIdentifierError
from dsr.limits import LIMITS, value_bytes

AttrValue = Union[bool, int, float, str, list[float], list[str]]  # noqa: UP007 (runtime alias)
Attrs = dict[str, AttrValue]

#: Patterns are used with fullmatch() in Python ('$' alone would accept a trailing newline,
#: which pydantic's Rust regex refuses: replicas must agree on what is valid).
INT64_MIN = -(2**63)
INT64_MAX = 2**63 - 1
#: Node ids are positive and fit in a signed 64-bit integer (C++, Rust, Go, SQL all agree).
#: Ids below 2**32 are left for hand-written worlds; generated ids have a random nonzero
#: 31-bit prefix (see graph.IdAllocator).
ID_MAX = INT64_MAX

TYPE_PATTERN = r"^[A-Za-z_][A-Za-z0-9_\-]{0,63}$"
_TYPE_RE = re.compile(TYPE_PATTERN)
#: Names are free text without control characters.  Local inserts also refuse '#': the view
#: shows the loser of a concurrent name clash as "<name>#<id>" (see names.py), and a snapshot
#: saved in that state stores the shown name, so files and the wire accept '#'.
NAME_PATTERN = r"^[^\x00-\x1f]{1,256}$"
_NAME_RE = re.compile(NAME_PATTERN)
AGENT_PATTERN = r"^[A-Za-z0-9_][A-Za-z0-9_\-.]{0,63}$"
_AGENT_RE = re.compile(AGENT_PATTERN)
ATTR_KEY_PATTERN = r"^[^\x00-\x1f]{1,128}$"
_ATTR_KEY_RE = re.compile(ATTR_KEY_PATTERN)


@dataclass(frozen=True, slots=True)
class Node:
    """Immutable snapshot of a visible node (a copy: mutating `attrs` changes nothing)."""

    id: int
    type: str
    name: str
    attrs: Attrs = field(default_factory=dict)


@dataclass(frozen=True, slots=True)
class Edge:
    """Immutable snapshot of a visible edge, keyed by (src, dst, type)."""

    src: int
    dst: int
    type: str
    attrs: Attrs = field(default_factory=dict)

    @property
    def key(self) -> tuple[int, int, str]:
        return (self.src, self.dst, self.type)


_new = object.__new__
_slots = vars(Node)           # the slot descriptors of the frozen dataclass
_set_id, _set_type = _slots["id"].__set__, _slots["type"].__set__
_set_name, _set_attrs = _slots["name"].__set__, _slots["attrs"].__set__


def make_node(node_id: int, type_: str, name: str, attrs: Attrs) -> Node:
    """Node(...) without the frozen dataclass's __init__ (a snapshot is built for every
    signal: this halves its cost); same object, same equality."""
    node = _new(Node)
    _set_id(node, node_id)
    _set_type(node, type_)
    _set_name(node, name)
    _set_attrs(node, attrs)
    return node


# ---- pydantic annotations shared by the file and wire schemas -------------------------------

def _floats(values: list[int | float]) -> list[float]:
    return [float(v) for v in values]


NodeId = Annotated[int, Strict(), Field(ge=1, le=ID_MAX)]
Int64 = Annotated[int, Strict(), Field(ge=INT64_MIN, le=INT64_MAX)]
UInt63 = Annotated[int, Strict(), Field(ge=0, le=INT64_MAX)]
FiniteFloat = Annotated[float, Strict(), AllowInfNan(False)]
TypeName = Annotated[str, Strict(), StringConstraints(pattern=TYPE_PATTERN)]
NodeName = Annotated[str, Strict(), StringConstraints(pattern=NAME_PATTERN)]
AttrKey = Annotated[str, Strict(), StringConstraints(pattern=ATTR_KEY_PATTERN)]
AgentName = Annotated[str, Strict(), StringConstraints(pattern=AGENT_PATTERN)]
def _int64_only(value: Any) -> Any:
    """JSON integers must fit in int64 (the float branch would otherwise take them)."""
    if type(value) is int and not INT64_MIN <= value <= INT64_MAX:
        raise ValueError(f"integer {value} does not fit in int64")
    return value


def _int64_items(value: Any) -> Any:
    if type(value) is list:
        for item in value:
            _int64_only(item)
    return _int64_only(value)


FloatList = Annotated[list[Union[Int64, FiniteFloat]], AfterValidator(_floats)]  # noqa: UP007
StrList = list[Annotated[str, Strict()]]
AttrValueSchema = Annotated[Union[Annotated[bool, Strict()], Int64, FiniteFloat,  # noqa: UP007
                                  Annotated[str, Strict()], FloatList, StrList],
                            BeforeValidator(_int64_items)]


# ---- fast checks for the local API (hot path: no pydantic object per call) ------------------

def check_type_name(value: Any, what: str = "type") -> str:
    if not isinstance(value, str) or not _TYPE_RE.fullmatch(value):
        raise InvalidIdentifierError(
            f"{what} {value!r} must match {TYPE_PATTERN} (letters, digits, '_' or '-')")
    return value if type(value) is str else str(value)   # a StrEnum member: its plain value


def check_name(value: Any, allow_hash: bool = False) -> str:
    if not isinstance(value, str) or not _NAME_RE.fullmatch(value) \
            or (not allow_hash and "#" in value):
        raise InvalidIdentifierError(
            f"node name {value!r} must be 1-256 characters without '#' or control characters")
    return value


def check_agent_name(value: Any, what: str = "agent") -> str:
    """Agent and graph names become Zenoh key chunks, so no '/', '*', '$', '?' or '#'."""
    if not isinstance(value, str) or not _AGENT_RE.fullmatch(value):
        raise InvalidIdentifierError(
            f"{what} name {value!r} must match {AGENT_PATTERN}")
    return value


def check_node_id(value: Any) -> int:
    if type(value) is not int or not 1 <= value <= ID_MAX:
        raise InvalidIdentifierError(f"node id {value!r} must be an int in [1, 2**63-1]")
    return value


def _too_large(key: str, value: AttrValue) -> InvalidAttributeError:
    return InvalidAttributeError(
        f"attribute {key!r}: value of {value_bytes(value)} bytes exceeds the limit of "
        f"{LIMITS.max_value_bytes} bytes per value (CHRONAV_DSR_MAX_VALUE_BYTES)")


def check_attr_value(key: str, value: Any) -> AttrValue:
    """Return `value` normalised to a DSR attribute type, or raise naming `key`."""
    kind = type(value)
    if kind is bool:
        return value
    if kind is str:
        if len(value) * 4 > LIMITS.max_value_bytes and value_bytes(value) > LIMITS.max_value_bytes:
            raise _too_large(key, value)
        return value
    if kind is float:
        if not math.isfinite(value):
            raise InvalidAttributeError(f"attribute {key!r}: {value!r} is not a finite float")
        return value
    if kind is int:
        if not INT64_MIN <= value <= INT64_MAX:
            raise InvalidAttributeError(f"attribute {key!r}: {value} does not fit in 64 bits")
        return value
    if isinstance(value, (list, tuple)) or hasattr(value, "tolist"):
        items = value.tolist() if hasattr(value, "tolist") else list(value)
        if not isinstance(items, list):  # numpy scalar
            return check_attr_value(key, items)
        if items and all(isinstance(item, str) for item in items):
            items = [item if type(item) is str else str(item) for item in items]   # StrEnum members
            if value_bytes(items) > LIMITS.max_value_bytes:
                raise _too_large(key, items)
            return items
        if 8 * len(items) > LIMITS.max_value_bytes:
            raise _too_large(key, [0.0] * len(items))
        out: list[float] = []
        for item in items:
            if isinstance(item, bool) or not isinstance(item, (int, float)):
                raise InvalidAttributeError(
                    f"attribute {key!r}: lists must hold only floats or only strings, "
                    f"got {type(item).__name__} {item!r}")
            number = float(item)
            if not math.isfinite(number):
                raise InvalidAttributeError(f"attribute {key!r}: {item!r} is not finite")
            out.append(number)
        return out
    if isinstance(value, str):  # StrEnum members (agents/world/vocabulary.py): their plain value
        return check_attr_value(key, str(value))
    if isinstance(value, bool):
        return bool(value)
    if isinstance(value, int):  # numpy integers, IntEnum
        return check_attr_value(key, int(value))
    if isinstance(value, float) or hasattr(value, "__float__") and not isinstance(value, str):
        try:
            return check_attr_value(key, float(value))
        except (TypeError, ValueError):
            pass
    raise InvalidAttributeError(
        f"attribute {key!r}: type {type(value).__name__} is not one of "
        "bool, int, float, str, list[float], list[str]")


def check_attrs(attrs: Any) -> Attrs:
    """Validate a whole attribute mapping; keys are non-empty strings."""
    if not isinstance(attrs, dict):
        raise InvalidAttributeError(f"attrs must be a dict, got {type(attrs).__name__}")
    out: Attrs = {}
    for key, value in attrs.items():
        if type(key) is not str or key not in _GOOD_KEYS:
            if not isinstance(key, str) or not _ATTR_KEY_RE.fullmatch(key):
                raise InvalidAttributeError(f"attribute key {key!r} must be a non-empty string")
            key = str(key)                      # a StrEnum member (the vocabulary's keys): its value
            if len(_GOOD_KEYS) < 4096:
                _GOOD_KEYS.add(key)
        kind = type(value)
        if kind is bool or (kind is float and -_HUGE < value < _HUGE) \
                or (kind is int and INT64_MIN <= value <= INT64_MAX) \
                or (kind is str and len(value) <= _SHORT):
            out[key] = value                    # the common cases, checked inline
        else:
            out[key] = check_attr_value(key, value)
    return out


#: attribute keys already checked (agents use a small vocabulary)
_GOOD_KEYS: set[str] = set()
_HUGE = float("inf")
#: strings this short are under any value limit (4 bytes per character at most)
_SHORT = LIMITS.max_value_bytes // 4
