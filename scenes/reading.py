"""Reading one input file within a size bound, only if it is a regular file: the one reader under
every file a person gives chronav (scenes, agendas, calendars, trajectories, maps, schedules,
grammars, targets, AGM worlds).

Why a module with no chronav imports, in ``scenes``: the layout's top folders are fixed, and
``grammar`` (one layer above ``scenes``, pyproject.toml's import contracts) reads files a person
named too, and must refuse the same things the same way.  Each caller wraps :func:`read_bounded`
in its own located error (scenes.files: ``SourceError``; grammar: its ``GrammarError``); this
module imports nothing of chronav, so the rules cannot drift with either.

Why each step: a path on the command line or in a scene may name anything, and the naive
``path.read_bytes()`` trusts it.  ``/dev/zero`` reads until memory runs out; a FIFO (named pipe)
blocks forever waiting for a writer; a directory or a device is not a file at all.  So the file is
opened without blocking (``O_NONBLOCK``: opening a FIFO returns at once), the *opened* file is
checked to be a regular file (no race between a check and the read), its size is checked against
the caller's bound before a byte is read, and at most ``max_bytes + 1`` bytes are ever read (a file
that grows while it is read is still refused).  Memory is asked for by what the file holds, never
by the bound: one buffer of its size plus one byte, then small chunks only if it grew meanwhile
(a bound of gigabytes must not reserve gigabytes for a file of a few kilobytes; under an
address-space limit that reservation alone fails with MemoryError).
"""

from __future__ import annotations

import errno
import os
import stat


#: read size once a file turned out longer than its size said (it grows while being read)
GROWTH_CHUNK_BYTES = 64 * 1024


class NotRegularFile(ValueError):
    """The path is a directory, FIFO, device or socket; the message says which, in a user's words."""


class FileTooLarge(ValueError):
    """The file holds more than the bound allows; ``size`` is None when it grew while being read."""

    def __init__(self, message: str, size: int | None, max_bytes: int) -> None:
        super().__init__(message)
        self.size = size
        self.max_bytes = max_bytes


def describe_mode(mode: int) -> str:
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


def regular_file_problem(path: str | os.PathLike[str]) -> str | None:
    """Why ``path`` (which exists) cannot be read as a file, or None if it is a regular file."""
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return None
    return None if stat.S_ISREG(mode) else f"is {describe_mode(mode)}, not a file"


def read_bounded(path: str | os.PathLike[str], *, max_bytes: int, what: str = "file",
                 limit_env: str | None = None) -> bytes:
    """The bytes of the regular file ``path``, refused before reading when larger than ``max_bytes``.

    ``what`` is how the messages name the file ("YAML file", "grammar file"); ``limit_env`` names
    the variable that raises the bound (``CHRONAV_LIMIT_...``), or None for a fixed bound.
    Raises :class:`NotRegularFile` or :class:`FileTooLarge` (both ``ValueError``, messages without
    the file's name, which the caller's located error adds), ``FileNotFoundError`` when nothing is
    there, or another ``OSError`` when the system refuses the read."""
    how = f" ({limit_env})" if limit_env else ""
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0))
    except IsADirectoryError:
        raise NotRegularFile(f"is a directory, not a {what}") from None
    except OSError as exc:
        if exc.errno == errno.ENXIO:   # a socket, or a FIFO opened for writing only
            raise NotRegularFile(f"is not a regular file; give a {what}") from None
        raise
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            raise NotRegularFile(f"is {describe_mode(info.st_mode)}, not a {what}; give a regular file")
        if info.st_size > max_bytes:
            raise FileTooLarge(f"{info.st_size:,} bytes; a {what} may have at most {max_bytes:,}{how}",
                               info.st_size, max_bytes)
        os.set_blocking(fd, True)
        data = _read_upto(fd, info.st_size, max_bytes)
    finally:
        os.close(fd)
    if len(data) > max_bytes:
        raise FileTooLarge(f"more than {max_bytes:,} bytes; a {what} may have at most {max_bytes:,}{how}",
                           None, max_bytes)
    return data


def _read_upto(fd: int, size: int, max_bytes: int) -> bytes:
    """At most ``max_bytes + 1`` bytes of ``fd``: first ``size + 1`` (the file's size as fstat gave
    it; the extra byte tells whether it grew), then chunks of GROWTH_CHUNK_BYTES until the end or
    past the bound.  ``os.read`` may return less than asked (pipes, reads of 2 GiB and more): loop."""
    parts: list[bytes] = []
    total = 0
    want = min(size, max_bytes) + 1
    while total <= max_bytes:
        chunk = os.read(fd, min(want - total, max_bytes + 1 - total) if total < want
                        else min(GROWTH_CHUNK_BYTES, max_bytes + 1 - total))
        if not chunk:
            break
        parts.append(chunk)
        total += len(chunk)
    return parts[0] if len(parts) == 1 else b"".join(parts)
