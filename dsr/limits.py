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
        "max_waiting_deltas": "CHRONAV_DSR_MAX_WAITING_DELTAS"}


@dataclass(frozen=True, slots=True)
class Limits:
    max_value_bytes: int = 256 * 1024
    max_delta_bytes: int = 4 * 1024 * 1024
    max_state_bytes: int = 256 * 1024 * 1024
    max_clock_offset_ms: int = 1000
    max_waiting_deltas: int = 10_000

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
