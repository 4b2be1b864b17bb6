"""Reading a grammar, target or world file within a size bound, only if it is a regular file.

Why: ``chronav grammar check /dev/zero`` read until memory ran out, and a grammar that includes a
FIFO (named pipe) waited forever for a writer.  The rules are those of ``scenes/files.py`` (the
reader of every other input), repeated here because the foundation layers ``scenes`` and
``grammar`` may not import each other: open without blocking, check that the opened file is a
regular file and not larger than the bound, read at most ``max_bytes + 1`` bytes.
"""

from __future__ import annotations

import errno
import os
import stat

MAX_GRAMMAR_BYTES = 16 * 1024 * 1024
"""Largest grammar or target file read (AGM's biggest real grammars are some 100 KB)."""


def _kind(mode: int) -> str:
    if stat.S_ISDIR(mode):
        return "a directory"
    if stat.S_ISFIFO(mode):
        return "a FIFO (named pipe)"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    return "not a regular file"


def regular_file_problem(path: str | os.PathLike[str]) -> str | None:
    """Why ``path`` (which exists) cannot be read as a file, or None if it is a regular file."""
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return None
    return None if stat.S_ISREG(mode) else f"is {_kind(mode)}, not a file"


def read_bounded(path: str | os.PathLike[str], max_bytes: int, what: str) -> bytes:
    """The bytes of the regular file ``path``; OSError subclasses with a message in a user's words
    (``FileNotFoundError`` when it does not exist, ``ValueError`` when it is not a regular file or
    too large), which the callers turn into their own located errors."""
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0))
    except IsADirectoryError:
        raise ValueError(f"is a directory, not a {what} file") from None
    except OSError as exc:
        if exc.errno == errno.ENXIO:
            raise ValueError(f"is not a regular file; give a {what} file") from None
        raise
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            raise ValueError(f"is {_kind(info.st_mode)}, not a {what} file; give a regular file")
        if info.st_size > max_bytes:
            raise ValueError(f"{what} file of {info.st_size:,} bytes; chronav reads at most {max_bytes:,}")
        os.set_blocking(fd, True)
        with os.fdopen(fd, "rb", closefd=True) as handle:
            fd = -1
            data = handle.read(max_bytes + 1)
    finally:
        if fd >= 0:
            os.close(fd)
    if len(data) > max_bytes:
        raise ValueError(f"{what} file of more than {max_bytes:,} bytes; chronav reads at most {max_bytes:,}")
    return data
