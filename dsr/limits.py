"""Size and clock limits every replica enforces, on local writes and on what it receives.

Why one place: a replica that accepts what another refuses diverges from it, so every member
of a graph must apply the same limits; they are documented in docs/dsr_wire_format.md
("Limits") and set per process from the environment (set them the same way on every host).

- `max_value_bytes` (CHRONAV_DSR_MAX_VALUE_BYTES, default 256 KiB): one attribute value:
  the UTF-8 bytes of a string, the sum of the UTF-8 bytes of a list of strings, 8 bytes per
  item of a list of numbers.  Local writes raise InvalidAttributeError; a received message
  holding a larger value is dropped whole.
- `max_delta_bytes` (CHRONAV_DSR_MAX_DELTA_BYTES, default 4 MiB): one delta payload.
  A local write (or transaction) that would encode to more raises InvalidAttributeError before
  anything changes; a larger received delta is dropped before it is parsed.
- `max_state_bytes` (CHRONAV_DSR_MAX_STATE_BYTES, default 256 MiB): one state reply.
- `max_clock_offset_ms` (CHRONAV_DSR_MAX_CLOCK_OFFSET_MS, default 1000): the HLC paper's
  maximum offset: a received message stamped more than this ahead of the receiver's wall
  clock is dropped, so no writer can drag the others' clocks further ahead than this.
- `max_node_attrs` (CHRONAV_DSR_MAX_NODE_ATTRS, default 512): attributes of one node.
- `max_node_bytes` (CHRONAV_DSR_MAX_NODE_BYTES, default 2 MiB): the sum of the sizes of one
  node's attribute values (each counted as for `max_value_bytes`).  Both are checked against
  what the node would hold after the write: a local write raises InvalidAttributeError, a
  received delta is dropped whole (reason `too_many_attrs` / `node_too_large`), a state reply
  loses that node's entry (same reasons).  Why: the value and message limits alone let a
  writer grow one node without bound over many deltas (60,000 attributes, 3.35 MB, were
  accepted by every agent).  Per node, so judged on each replica's current copy: writers
  must stay well below them (chronav's largest node holds a few dozen attributes).
- `max_waiting_deltas` (CHRONAV_DSR_MAX_WAITING_DELTAS, default 10,000): received deltas
  waiting in a replica's Zenoh channel to be handled (dsr/receiver.py).  When it is full,
  Zenoh's network thread waits and the senders are slowed down; nothing is dropped.  (Local to
  each process: it changes no replica's view of the graph.)
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass, fields

from dsr.errors import ConfigError

ENV_PREFIX = "CHRONAV_DSR_"
_ENV = {"max_value_bytes": "CHRONAV_DSR_MAX_VALUE_BYTES",
        "max_delta_bytes": "CHRONAV_DSR_MAX_DELTA_BYTES",
        "max_state_bytes": "CHRONAV_DSR_MAX_STATE_BYTES",
        "max_clock_offset_ms": "CHRONAV_DSR_MAX_CLOCK_OFFSET_MS",
        "max_waiting_deltas": "CHRONAV_DSR_MAX_WAITING_DELTAS",
        "max_node_attrs": "CHRONAV_DSR_MAX_NODE_ATTRS",
        "max_node_bytes": "CHRONAV_DSR_MAX_NODE_BYTES"}


@dataclass(frozen=True, slots=True)
class Limits:
    max_value_bytes: int = 256 * 1024
    max_delta_bytes: int = 4 * 1024 * 1024
    max_state_bytes: int = 256 * 1024 * 1024
    max_clock_offset_ms: int = 1000
    max_waiting_deltas: int = 10_000
    max_node_attrs: int = 512
    max_node_bytes: int = 2 * 1024 * 1024

    @classmethod
    def from_env(cls, environ: Mapping[str, str] | None = None) -> Limits:
        """Defaults overridden by CHRONAV_DSR_* variables; errors name the variable."""
        env = os.environ if environ is None else environ
        values: dict[str, int] = {}
        for field in fields(cls):
            var = _ENV[field.name]
            text = (env.get(var) or "").strip()
            if not text:
                continue
            try:
                number = int(text.replace("_", ""))
            except ValueError:
                raise ConfigError(f"{var}={text!r}: expected a whole number") from None
            if number < 1:
                raise ConfigError(f"{var}={text!r}: must be at least 1")
            values[field.name] = number
        return cls(**values)


#: the limits of this process (read once; tests pass their own to the functions that take one)
LIMITS = Limits.from_env()


def value_bytes(value: object) -> int:
    """The size of an attribute value as the limits count it (see the module docstring)."""
    kind = type(value)
    if kind is str:
        text: str = value  # type: ignore[assignment]
        return len(text) if text.isascii() else len(text.encode("utf-8", "surrogatepass"))
    if kind is list:
        items: list[object] = value  # type: ignore[assignment]
        if items and type(items[0]) is str:
            return sum(value_bytes(item) for item in items)
        return 8 * len(items)
    return 8


#: attribute key of a removal receipt (dsr/crdt.py REMOVAL_RECEIPT; not counted in a node)
_RECEIPT = "~removed"


def node_problem(node_id: int, held: Mapping[str, tuple[int, int, object]] | None,
                 new: Mapping[str, object], *, registers: bool,
                 limits: Limits | None = None) -> tuple[str, str] | None:
    """(reason, sentence) if the node would exceed `max_node_attrs` / `max_node_bytes` once
    `new` (key -> value, or key -> register when `registers`) is written over `held` (its
    current registers), else None.

    Cheap in the common case: writing scalars to keys the node already has cannot grow it
    past its current size by more than 8 bytes a key, so nothing is summed."""
    current: Mapping[str, object] = held if held is not None else {}
    if new.keys() <= current.keys():
        for item in new.values():
            kind = type(item[2] if registers else item)  # type: ignore[index]
            if kind is str or kind is list:
                break
        else:
            return None
    limits = limits or LIMITS
    keys = current.keys() | new.keys()
    keys.discard(_RECEIPT)
    if len(keys) > limits.max_node_attrs:
        return "too_many_attrs", (f"node {node_id} would have {len(keys)} attributes, over "
                                  f"the limit of {limits.max_node_attrs} per node "
                                  "(CHRONAV_DSR_MAX_NODE_ATTRS)")
    size = 0
    for key, item in new.items():
        if key != _RECEIPT:
            size += value_bytes(item[2] if registers else item)  # type: ignore[index]
    for key, reg in current.items():
        if key not in new and key != _RECEIPT:
            size += value_bytes(reg[2])  # type: ignore[index]
    if size > limits.max_node_bytes:
        return "node_too_large", (f"node {node_id} would hold {size} bytes of values, over "
                                  f"the limit of {limits.max_node_bytes} per node "
                                  "(CHRONAV_DSR_MAX_NODE_BYTES)")
    return None
