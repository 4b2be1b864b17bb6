"""Typed exceptions of the DSR package.

Why typed: agents catch exactly what they can recover from (a node vanished because another
agent deleted it, a name already taken) and let real bugs surface.
"""

from __future__ import annotations


class DSRError(Exception):
    """Base class of every error raised by the dsr package."""


class NodeNotFoundError(DSRError, KeyError):
    """No visible node with this id or name."""

    def __str__(self) -> str:  # KeyError quotes its argument; keep the message readable
        return str(self.args[0]) if self.args else "node not found"


class EdgeNotFoundError(DSRError, KeyError):
    """No visible edge (src, dst, type)."""

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else "edge not found"


class NameTakenError(DSRError, ValueError):
    """A local insert used a name that a visible node already holds."""


class InvalidAttributeError(DSRError, TypeError):
    """An attribute key or value is not one of the DSR attribute types."""


class InvalidIdentifierError(DSRError, ValueError):
    """A node id, type, name or edge type is malformed."""


class ReadOnlyGraphError(DSRError):
    """A write was attempted on a read-only replica (e.g. `chronav dsr dump`)."""


class TransactionError(DSRError):
    """Misuse of a transaction, e.g. calling dispatch() inside one."""


class PoseError(DSRError):
    """RT chain cannot be composed: missing pose attributes or a cycle."""


class GraphFileError(DSRError, ValueError):
    """A graph JSON document failed validation; the message names the file and the field."""


class WireError(DSRError, ValueError):
    """A received payload is not a valid DSR message (schema, writer or clock check failed)."""


class ConfigError(DSRError, ValueError):
    """Zenoh settings are invalid; the message names the environment variable or file."""


class PolicyError(DSRError, ValueError):
    """A write-policy file is invalid; the message names the file, line and key."""


class WriteRefusedError(DSRError, PermissionError):
    """A local write the write policy refuses; the message names the writer, the operation, the
    element type, the attribute and the policy file.  Every other replica would drop it."""
