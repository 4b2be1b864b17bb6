"""Names people type (rooms, objects, people, activities): how long, which characters, how shown.

Why one module: names travel from scene files, agenda files, .ics calendars and the command line
into the DSR, the recording and other people's terminals.  A 100 KB name or one holding a
terminal escape (``\\x1b[2J`` clears the screen) must be refused where it is read, and anything
printed that did not come from chronav itself goes through :func:`shown` first, so a name can
never drive the terminal of the person reading it.
"""

from __future__ import annotations

import unicodedata
from typing import Annotated

from pydantic import AfterValidator

from scenes.limits import NAME_CHARS


def check_name(value: str) -> str:
    """A name: not empty, at most NAME_CHARS characters, printable (no control characters), in
    Unicode's composed form (NFC).

    Why NFC: "josé" typed on one keyboard is é (one code point), pasted from another e + U+0301;
    both look the same to a person, so they are the same name (two people named "josé" in the two
    forms were accepted as different people)."""
    value = unicodedata.normalize("NFC", value)
    limit = NAME_CHARS.value()
    if len(value) > limit:
        raise ValueError(f"a name of {len(value):,} characters; names have at most {limit} "
                         f"({NAME_CHARS.env})")
    if not value.strip():
        raise ValueError("must not be empty")
    if any(not ch.isprintable() for ch in value):
        raise ValueError(f"{shown(value, 40)} contains control characters (such as a terminal escape or a "
                         "line break); use letters, digits, spaces and punctuation")
    return value


# A name or id as every model declares it (scenes, agenda, CLI).
Name = Annotated[str, AfterValidator(check_name)]


def shown(text: object, max_chars: int = 200) -> str:
    """``text`` made safe to print: control characters as ``\\x1b``-style escapes, cut to ``max_chars``."""
    raw = str(text)
    out = "".join(ch if ch.isprintable() else ch.encode("unicode_escape").decode("ascii") for ch in raw[:max_chars])
    return out + (f"... ({len(raw):,} characters)" if len(raw) > max_chars else "")
