"""A process's own log file, cut on the wall clock's hours in a real-time run.

Why the process cuts its own log, and not the launcher: the launcher sends each process's stdout
and stderr to ``logs/<name>.log`` (tools/system/supervisor.py), and what lands there is not only
Python's logging but faulthandler's stacks and the Rust side of Zenoh and Rerun, written straight
to the file descriptors.  Only the process can move those descriptors to a new file without
losing a line (``os.dup2`` is atomic) and without routing its output through the launcher, which
would then have to keep up with every agent or stall it.  Copy-and-truncate, the other classic,
loses what is written between the two.

What a user sees: the current part is always ``<name>.log`` (what ``tail -f`` and the docs name);
each earlier part is ``<name>-YYYYmmdd-HHMM.log``, stamped with the local time its slot began
(``-HHMMSS`` when parts are shorter than a minute, as in the suite's short soak).
Parts follow the wall clock, like the lines' own time stamps, not the scene's clock (a real-time
run's recording is cut by the scene's hours: agents/runtime/recording.py).

Turned on by two variables the launcher sets: ``CHRONAV_LOG_FILE`` (the file the process's output
goes to, set for every process it starts) and ``CHRONAV_LOG_ROTATE_S`` (seconds per part, 3600 in
a real-time run; a whole divisor of a day, so that parts start on the hour).  A cut that fails
(the disk is full, the folder went away) leaves the output where it was and is tried again at the
next slot: a log never stops an agent.
"""

from __future__ import annotations

import contextlib
import logging
import os
import sys
import time
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path

LOG_FILE_ENV = "CHRONAV_LOG_FILE"
LOG_ROTATE_ENV = "CHRONAV_LOG_ROTATE_S"
DAY_S = 86_400

log = logging.getLogger("chronav.log_rotation")


def rotate_period_s(environ: Mapping[str, str] = os.environ) -> int | None:
    """``CHRONAV_LOG_ROTATE_S`` as whole seconds, None when unset or empty; a bad value is refused
    in the user's words (ValueError) before the process starts its work."""
    raw = environ.get(LOG_ROTATE_ENV, "").strip()
    if not raw:
        return None
    try:
        period = int(raw)
    except ValueError:
        raise ValueError(f"{LOG_ROTATE_ENV}={raw!r}: give the seconds per log part as a whole number, "
                         f"e.g. 3600") from None
    if period < 1 or DAY_S % period:
        raise ValueError(f"{LOG_ROTATE_ENV}={raw!r}: a log part spans a whole divisor of a day "
                         f"(1 to 86400 seconds, e.g. 60, 3600), so that parts start on the hour")
    return period


def slot_start_s(wall_s: float, period_s: int) -> float:
    """The start of the slot ``wall_s`` falls in: slots of ``period_s`` counted from local midnight."""
    local = time.localtime(wall_s)
    since_midnight = local.tm_hour * 3600 + local.tm_min * 60 + local.tm_sec + (wall_s % 1.0)
    return wall_s - since_midnight % period_s


class LogRotation:
    """Cuts ``path`` into parts at every slot boundary; ``maybe_rotate`` is called from the
    process's main loop (a clock read when no cut is due).

    ``fds``: the descriptors to move, by default stdout and stderr as the OS and Python see them
    (the router reads fd 1 through a pipe and prints on a copy of it: dsr/acl_denials.py); only
    those that write to ``path`` are moved, and with none the file is left alone (a process run
    by hand with the variables set writes to its terminal)."""

    def __init__(self, path: Path, period_s: int, clock: Callable[[], float] = time.time,
                 fds: Iterable[int] | None = None) -> None:
        self.path = path
        self.period_s = period_s
        self._clock = clock
        self._fds = tuple(fds) if fds is not None else None
        # What the file holds already (a restarted agent appends to its predecessor's part, the
        # launcher may have written to it first) belongs to the slot of its last write.
        try:
            held = path.stat()
            held_since = held.st_mtime if held.st_size else clock()
        except OSError:
            held_since = clock()
        self._slot_s = slot_start_s(held_since, period_s)

    @classmethod
    def from_env(cls, environ: Mapping[str, str] = os.environ) -> LogRotation | None:
        """The rotation the launcher asked for, or None (a process run by hand, a fast run)."""
        period = rotate_period_s(environ)
        target = environ.get(LOG_FILE_ENV, "").strip()
        if period is None or not target:
            return None
        return cls(Path(target), period)

    def part_path(self, slot_s: float) -> Path:
        """``<name>-YYYYmmdd-HHMM.log``, with seconds when parts are shorter than whole minutes."""
        stamp = time.strftime("%Y%m%d-%H%M" if self.period_s % 60 == 0 else "%Y%m%d-%H%M%S",
                              time.localtime(slot_s))
        return self.path.with_name(f"{self.path.stem}-{stamp}{self.path.suffix}")

    def maybe_rotate(self) -> Path | None:
        """Cut the file if its slot is over: the finished part's path, else None."""
        now = self._clock()
        if now < self._slot_s + self.period_s:
            return None
        finished = self._slot_s
        self._slot_s = slot_start_s(now, self.period_s)
        try:
            return self._cut(self.part_path(finished), now)
        except OSError as exc:
            log.warning("could not start a new log part after %s (%s): this part goes on and the cut is "
                        "tried again at the next slot", self.path, exc.strerror or exc)
            return None

    def _writers(self) -> list[int]:
        """The descriptors that write to ``path`` now (compared by device and inode)."""
        file = os.stat(self.path)
        candidates = self._fds if self._fds is not None else _standard_fds()
        writers = []
        for fd in candidates:
            try:
                st = os.fstat(fd)
            except OSError:
                continue
            if (st.st_dev, st.st_ino) == (file.st_dev, file.st_ino) and fd not in writers:
                writers.append(fd)
        return writers

    def _cut(self, part: Path, now: float) -> Path | None:
        """New file first, then the renames, then the descriptors: a failure before the renames
        changes nothing, and no line written meanwhile is lost (it lands in the finished part)."""
        if not self.path.exists() or self.path.stat().st_size == 0:
            return None                                   # nothing to keep: no empty parts
        writers = self._writers()
        if not writers:
            return None
        part = _free_name(part)
        fresh = self.path.with_name(f".{self.path.name}.next")
        new_fd = os.open(fresh, os.O_WRONLY | os.O_APPEND | os.O_CREAT | os.O_TRUNC, 0o644)
        try:
            for stream in (sys.stdout, sys.stderr):
                with contextlib.suppress(OSError, ValueError, AttributeError):
                    stream.flush()                        # Python's buffers into the finished part
            try:
                os.rename(self.path, part)
            except OSError:
                os.unlink(fresh)
                raise
            try:
                os.rename(fresh, self.path)
            except OSError:
                os.rename(part, self.path)                # back as it was: this part goes on
                os.unlink(fresh)
                raise
            # the clock that decided the cut: time.localtime() without an argument reads a coarser
            # clock, a few ms behind, and stamped cuts just after a boundary with the second before
            stamp = time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(now))
            with contextlib.suppress(OSError):            # a full disk: the line is lost, the cut goes on
                os.write(new_fd, f"{stamp} log continued from {part.name}\n".encode())
            for fd in writers:
                os.dup2(new_fd, fd)
        finally:
            os.close(new_fd)
        return part


def _standard_fds() -> list[int]:
    fds = [1, 2]
    for stream in (sys.stdout, sys.stderr):
        try:
            fds.append(stream.fileno())
        except (OSError, ValueError, AttributeError):   # closed, or not a real file (a test's capture)
            pass
    return fds


def _free_name(part: Path) -> Path:
    """``part``, or ``part`` with ``-2``, ``-3``... when a part of that slot exists (the clock was
    set back, or a slot was cut by two processes' lives)."""
    if not part.exists():
        return part
    n = 2
    while (candidate := part.with_name(f"{part.stem}-{n}{part.suffix}")).exists():
        n += 1
    return candidate
