"""Reading one input file within a size bound: the one door through which chronav reads a file a
person gave it (scene and agenda YAML, .ics calendars, trajectory CSV, map images, chaos schedules).

Why one function: a path on the command line or in a scene may name anything, and the naive
``path.read_bytes()`` trusts it.  ``/dev/zero`` reads until memory runs out; a FIFO (named pipe)
blocks forever waiting for a writer; a directory or a device is not a file at all.  So the file is
opened without blocking (``O_NONBLOCK``: opening a FIFO returns at once), the *opened* file is
checked to be a regular file (no race between a check and the read), its size is checked against
the caller's bound before a byte is read, and at most ``max_bytes + 1`` bytes are ever read (a file
that grows while it is read is still refused).  Every refusal is a :class:`SourceError` naming the
file and saying what it is, so "not found" is only ever said of a path that does not exist.

``grammar/`` cannot import this module (the foundation layers are independent): its two readers
(grammar files, AGM worlds) apply the same rules in ``grammar/files.py``.
"""

from __future__ import annotations

import errno
import os
import stat
from pathlib import Path

from scenes.errors import SourceError


def _kind(mode: int) -> str:
    """What a file that is not a regular file is, in a user's words."""
    if stat.S_ISDIR(mode):
        return "a directory"
    if stat.S_ISFIFO(mode):
        return "a FIFO (named pipe)"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    if stat.S_ISSOCK(mode):
        return "a socket"
    return "not a regular file"


def read_bounded(path: str | Path, *, max_bytes: int, limit_env: str | None = None, what: str = "file") -> bytes:
    """The bytes of the regular file ``path``, refused before reading when larger than ``max_bytes``.

    ``limit_env`` names the variable that raises the bound (``CHRONAV_LIMIT_...``), or None for a
    fixed bound; ``what`` is how the message names the file ("YAML file", "map image")."""
    name = str(path)
    how = f" ({limit_env})" if limit_env else ""
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0))
    except FileNotFoundError:
        raise SourceError(name, None, None, "", "no such file") from None
    except IsADirectoryError:
        raise SourceError(name, None, None, "", f"is a directory, not a {what}") from None
    except OSError as exc:
        if exc.errno == errno.ENXIO:   # a socket, or a FIFO opened for writing only
            raise SourceError(name, None, None, "", f"is not a regular file; give a {what}") from None
        raise SourceError(name, None, None, "", f"cannot read it: {exc.strerror or exc}") from None
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            raise SourceError(name, None, None, "", f"is {_kind(info.st_mode)}, not a {what}; give a regular file")
        if info.st_size > max_bytes:
            raise SourceError(name, None, None, "", f"{info.st_size:,} bytes; a {what} may have at most "
                              f"{max_bytes:,}{how}")
        os.set_blocking(fd, True)
        with os.fdopen(fd, "rb", closefd=True) as handle:
            fd = -1
            data = handle.read(max_bytes + 1)
    except OSError as exc:
        raise SourceError(name, None, None, "", f"cannot read it: {exc.strerror or exc}") from None
    finally:
        if fd >= 0:
            os.close(fd)
    if len(data) > max_bytes:
        raise SourceError(name, None, None, "", f"more than {max_bytes:,} bytes; a {what} may have at most "
                          f"{max_bytes:,}{how}")
    return data


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
