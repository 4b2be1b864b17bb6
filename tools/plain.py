"""Text for a reader at any width: plurals, lists cut with a count, and wrapping that keeps words whole.

Why one module: rich falls back to 80 columns whenever stdout is not a terminal (a pipe, a file,
CI), and its tables then fold long names mid-word (``therapis``/``t_eva``).  Commands that print
tables therefore print a plain layout when their console is not a terminal, built from these
helpers, so that every command wraps the same way: between words, never inside a name.
"""

from __future__ import annotations

import textwrap
from collections.abc import Iterable, Sequence
from typing import Any, Final, TypedDict

DEFAULT_WIDTH = 80


class PrintOptions(TypedDict):
    """Keyword options of ``rich.console.Console.print`` (typed, so ``print(text, **WHOLE_LINE)`` checks)."""

    highlight: bool
    markup: bool
    soft_wrap: bool


#: A message printed as it is: no colouring guessed from its text, no markup read in it (a path or
#: a name with brackets stays whole), and not folded at the console's width (the terminal wraps).
WHOLE_LINE: Final[PrintOptions] = {"highlight": False, "markup": False, "soft_wrap": True}


def plural(count: int, noun: str, plural_form: str | None = None) -> str:
    """``plural(1, "mission")`` -> ``"1 mission"``; ``plural(4, "mission")`` -> ``"4 missions"``."""
    return f"{count:,} {noun if count == 1 else (plural_form or noun + 's')}"


def listed(names: Sequence[object], limit: int = 8) -> str:
    """``a, b, c`` or, past ``limit`` names, ``a, b, ... and 18 more``: a message names what
    exists without turning into a wall of names."""
    shown = [str(n) for n in names[:limit]]
    rest = len(names) - len(shown)
    return ", ".join(shown) + (f" ... and {rest:,} more" if rest > 0 else "")


def wrapped(text: str, width: int, *, indent: str = "", first: str = "") -> list[str]:
    """``text`` wrapped at ``width`` between words (a name longer than a line stays whole on its own
    line rather than being split); ``first`` prefixes the first line (default none), ``indent``
    the others."""
    return textwrap.wrap(text, width=max(width, len(first) + 10), initial_indent=first, subsequent_indent=indent,
                         break_long_words=False, break_on_hyphens=False) or [first.rstrip()]


def cut(text: str, width: int) -> str:
    """One line of at most ``width`` characters, ``...`` marking what was cut."""
    return text if len(text) <= width else text[:max(width - 3, 1)].rstrip() + "..."


def is_plain(console: Any) -> bool:
    """Whether a rich console writes to something that is not a terminal (pipe, file, CI log):
    there the plain layouts are printed instead of tables."""
    return not console.is_terminal


def console_width(console: Any) -> int:
    """The console's width (rich uses $COLUMNS, else 80 when not on a terminal)."""
    return int(getattr(console, "width", DEFAULT_WIDTH) or DEFAULT_WIDTH)


def print_lines(console: Any, lines: Iterable[str]) -> None:
    """Lines as they are: no markup, no highlighting, no re-wrapping by rich."""
    for line in lines:
        console.print(line, markup=False, highlight=False, soft_wrap=True)
