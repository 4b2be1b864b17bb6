"""The cyclic GC is paused while states are decoded, merged and encoded, and a join of a large
graph freezes it out of later collections; the collector's own setting always comes back."""

from __future__ import annotations

import gc

import pytest

from dsr.collector import GC_THRESHOLDS, gc_paused, tune_collector


@pytest.fixture
def restore_gc():
    was = gc.isenabled()
    yield
    gc.unfreeze()              # give back whatever a test froze
    if was:
        gc.enable()
    else:
        gc.disable()


def test_paused_inside_and_enabled_again_after(restore_gc):
    gc.enable()
    with gc_paused():
        assert not gc.isenabled()
        with gc_paused():     # nested (a state part inside the join): still paused after it
            pass
        assert not gc.isenabled()
    assert gc.isenabled()


def test_an_error_inside_still_enables_it(restore_gc):
    gc.enable()
    with pytest.raises(ValueError), gc_paused():
        raise ValueError("bad state")
    assert gc.isenabled()


def test_a_disabled_collector_stays_disabled(restore_gc):
    gc.disable()               # an agent that manages its own collections
    with gc_paused(freeze_if=lambda: True):
        pass
    assert not gc.isenabled()
    assert gc.get_freeze_count() == 0


def test_freezes_only_when_asked_and_the_condition_holds(restore_gc):
    gc.enable()
    gc.unfreeze()
    with gc_paused(freeze_if=lambda: False):
        kept = [{"x": i} for i in range(100)]
    assert gc.get_freeze_count() == 0
    with gc_paused(freeze_if=lambda: True):
        kept.append({"y": 1})
    assert gc.get_freeze_count() > 0 and gc.isenabled()


@pytest.fixture
def restore_thresholds():
    was = gc.get_threshold()
    yield
    gc.set_threshold(*was)


def test_a_replica_process_raises_the_collector_thresholds_and_never_lowers_them(
        restore_thresholds):
    gc.set_threshold(700, 10, 10)                       # CPython's default
    tune_collector()
    assert gc.get_threshold() == GC_THRESHOLDS
    gc.set_threshold(GC_THRESHOLDS[0] * 2, 5, 100)      # a process that chose more
    tune_collector()
    assert gc.get_threshold() == (GC_THRESHOLDS[0] * 2, GC_THRESHOLDS[1], 100)
    gc.set_threshold(0)                                 # automatic collection turned off
    tune_collector()
    assert gc.get_threshold()[0] == 0
