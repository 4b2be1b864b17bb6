"""A long-lived process hands freed memory back (dsr/collector.py; issue 41: bounded over a week)."""

from __future__ import annotations

import platform

import pytest

import dsr.collector as collector


def test_release_free_memory_collects_cycles_and_trims_the_c_heap() -> None:
    class Node:
        def __init__(self) -> None:
            self.me = self

    import weakref

    cyclic = Node()
    alive = weakref.ref(cyclic)
    del cyclic
    returned = collector.release_free_memory()
    assert alive() is None                       # the cycle was collected
    if platform.system() == "Linux" and platform.libc_ver()[0] == "glibc":
        assert returned in (0, 1)                # glibc's malloc_trim ran (1: it gave pages back)


def test_the_timer_releases_at_most_once_per_period(monkeypatch: pytest.MonkeyPatch) -> None:
    now = [100.0]
    calls: list[float] = []
    monkeypatch.setattr(collector, "release_free_memory", lambda collect=True: calls.append(now[0]) or 0)
    timer = collector.FreeMemoryTimer(every_s=600.0, clock=lambda: now[0])
    for t in (100.0, 400.0, 699.0, 700.0, 1000.0, 1300.5):
        now[0] = t
        timer.maybe_release()
    assert calls == [700.0, 1300.5]
