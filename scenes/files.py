"""Reading one input file within a size bound, as a located error: the one door through which
chronav reads a file a person gave it (scene and agenda YAML, .ics calendars, trajectory CSV, map
images, chaos schedules).

Why a wrapper: the reading rules (regular files only, the bound checked before a byte is read,
never more than the bound + 1 read) are ``scenes.reading``'s, shared with ``grammar/``; here every
refusal becomes a :class:`SourceError` naming the file and saying what it is, so "not found" is
only ever said of a path that does not exist, and a file that is not UTF-8 names the line.
"""

from __future__ import annotations

from pathlib import Path

from scenes.reading import read_bounded as _read_bounded
from scenes.errors import SourceError


def read_bounded(path: str | Path, *, max_bytes: int, limit_env: str | None = None, what: str = "file") -> bytes:
    """The bytes of the regular file ``path``, refused before reading when larger than ``max_bytes``.

    ``limit_env`` names the variable that raises the bound (``CHRONAV_LIMIT_...``), or None for a
    fixed bound; ``what`` is how the message names the file ("YAML file", "map image")."""
    name = str(path)
    try:
        return _read_bounded(path, max_bytes=max_bytes, what=what, limit_env=limit_env)
    except FileNotFoundError:
        raise SourceError(name, None, None, "", "no such file") from None
    except ValueError as exc:   # not a regular file, or too large: the message says which
        raise SourceError(name, None, None, "", str(exc)) from None
    except OSError as exc:
        raise SourceError(name, None, None, "", f"cannot read it: {exc.strerror or exc}") from None


def decode_utf8(data: bytes, file: str) -> str:
    """UTF-8 text (a leading byte-order mark dropped), or a SourceError at the first bad byte."""
    try:
        return data.decode("utf-8").removeprefix("\ufeff")
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        column = exc.start - (data.rfind(b"\n", 0, exc.start) + 1) + 1
        raise SourceError(file, line, column, "", f"not UTF-8 text (byte 0x{data[exc.start]:02x}); "
                          "save the file as UTF-8") from None


def read_text_bounded(path: str | Path, *, max_bytes: int, limit_env: str | None = None,
                      what: str = "file") -> str:
    """:func:`read_bounded` decoded as UTF-8 text."""
    return decode_utf8(read_bounded(path, max_bytes=max_bytes, limit_env=limit_env, what=what), str(path))
