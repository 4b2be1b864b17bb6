"""An attribute value read as the type its reader expects: a number, a list of numbers, a list of names.

Why: ``Node.attrs`` maps to ``AttrValue`` (``bool | int | float | str | list[float] | list[str]``),
the union of everything the DSR may hold, so ``float(node.attrs["x"])`` or ``zip(xs, ys)`` is a type
error for mypy even where the reader knows the key holds a number or a list. These functions narrow
with the outcome the plain conversion had at run time: a value of the wrong kind raises
``TypeError`` (readers already catch it and skip the node), a non-numeric string ``ValueError``.
"""

from __future__ import annotations

__all__ = ["as_float", "as_floats", "as_strs"]


def as_float(value: object) -> float:
    """``float(value)`` for a number or a numeric string (as ``float()``); ``TypeError`` otherwise."""
    if isinstance(value, (int, float, str)):
        return float(value)
    raise TypeError(f"expected a number, got {type(value).__name__}")


def as_floats(value: object) -> list[float]:
    """A list attribute as floats (``[]`` stays ``[]``); ``TypeError`` for anything but a list of numbers."""
    if isinstance(value, list):
        return [as_float(v) for v in value]
    raise TypeError(f"expected a list of numbers, got {type(value).__name__}")


def as_strs(value: object) -> list[str]:
    """A list attribute as strings (each item through ``str()``); ``TypeError`` for anything but a list."""
    if isinstance(value, list):
        return [str(v) for v in value]
    raise TypeError(f"expected a list, got {type(value).__name__}")
