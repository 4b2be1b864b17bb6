"""The cyclic garbage collector in a process that holds a DSR replica.

Why a policy at all: a replica is ~10^5-10^6 small containers (element states, register tuples,
attribute dicts) that live as long as the agent and hold no reference cycles, and every remote
delta allocates more of them.  CPython's default collector (a young-generation collection every
700 net allocations, full ones every 100 young ones) walks that heap again and again for no
garbage: with the thresholds below a merged update costs about what it costs with the
collector off, half or less of the default's (docs/performance.md).  Reference counting still
frees everything that is not a cycle; cycles (rare: exceptions kept with their tracebacks, closures) are still collected,
only later.
"""

from __future__ import annotations

import gc
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from functools import cache

#: the collector's thresholds in a process holding a replica (see tune_collector)
GC_THRESHOLDS = (50_000, 20, 20)
#: a join that brings at least this many nodes freezes them out of the collector (gc_paused)
FREEZE_AFTER_JOIN_NODES = 1000


def tune_collector(thresholds: tuple[int, int, int] = GC_THRESHOLDS) -> None:
    """Raise the collector's thresholds to `thresholds` (called when a replica opens).

    Only ever raises them: a process that chose higher ones keeps them, and one that turned
    automatic collection off (threshold 0) stays so."""
    current = gc.get_threshold()
    if current[0] == 0:
        return
    gc.set_threshold(*(max(have, want) for have, want in zip(current, thresholds)))


@contextmanager
def gc_paused(freeze_if: Callable[[], bool] | None = None) -> Iterator[None]:
    """Pause the cyclic GC while a whole state is decoded and merged.

    Why: decoding a 10,000-node state allocates ~10^6 small objects, which triggers repeated
    full collections scanning the whole heap (measured: join time x1.7-2.5).  None of these
    objects form cycles, so deferring collection to the end loses nothing.

    After the join of a large graph (`freeze_if`) the objects are then moved out of the
    collector's reach (gc.freeze): the joined graph lives as long as the agent, and otherwise
    the first collections after the join walk all of it, once per generation it climbs
    (tens of ms each for 10k nodes; the first one still inside join()).  Freed elements are
    still freed by reference counting; only cyclic garbage pending at that moment would stay
    (an agent joins once, at its start, and the graph's objects hold no cycles).  Small
    graphs are not frozen: a process that joins many times (a test run) freezes nothing."""
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was_enabled:
            if freeze_if is not None and freeze_if():
                gc.freeze()
            gc.enable()


def release_free_memory(collect: bool = True) -> int:
    """Collect the cyclic garbage and hand the C heap's free pages back to the system; returns 0,
    or 1 when the C library gave memory back (glibc's ``malloc_trim``).

    Why: a process that lives for days (an in-process week, a launcher, an agent in real time)
    frees most of what a day allocates, but glibc keeps freed pages in its arenas, so the
    process's memory only ever climbs to its high-water mark plus fragmentation (measured on an
    in-process week: this call gave back 13-16 MB at each day's end, and the week's climb fell
    from 7-8 to 4 MB a day; docs/long_runs.md).  Called between days and every minute of an
    agent's life (``FreeMemoryTimer``), it costs one full collection (tens of ms on a heap of
    10^5-10^6 objects), or none with ``collect=False`` (an agent's loop, which a collection would
    pause that long; its cycles are left to its own collector)."""
    if collect:
        gc.collect()
    trim = _malloc_trim()
    return 0 if trim is None else int(trim(0))


@cache
def _malloc_trim() -> Callable[[int], int] | None:
    """glibc's ``malloc_trim``, looked up once; None on another C library (musl, macOS)."""
    import ctypes

    try:
        return ctypes.CDLL("libc.so.6").malloc_trim
    except (OSError, AttributeError):
        return None


class FreeMemoryTimer:
    """Calls ``release_free_memory`` (with ``collect``) at most every ``every_s`` seconds of the given
    clock."""

    def __init__(self, every_s: float = 60.0, clock: Callable[[], float] | None = None,
                 collect: bool = False) -> None:
        import time

        self.every_s = every_s
        self.collect = collect
        self.clock = clock or time.monotonic
        self._last = self.clock()

    def maybe_release(self) -> bool:
        """Release if ``every_s`` have passed since the last time; True when it ran."""
        now = self.clock()
        if now - self._last < self.every_s:
            return False
        self._last = now
        release_free_memory(self.collect)
        return True
