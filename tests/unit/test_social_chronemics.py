"""R(t): ramps, overlap, cancellation, forbidden while active, colour bands."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pydantic import ValidationError

from agents.lib.agenda.chronemics import (
    ChronemicsParams,
    interaction_cost_profile,
    interaction_cost_profiles,
    is_active,
    r_band,
    r_of_t,
    r_profile,
)
from agents.lib.agenda.model import ActivityWindow, AgendaError

P = ChronemicsParams()
H = 3600.0
THERAPY = ActivityWindow("tv", 11 * H, 12 * H)


@pytest.mark.parametrize(("t", "expected"), [
    (9 * H, 1.5),                    # nothing within 45 min
    (11 * H - 45 * 60, 1.5),         # ramp starts
    (11 * H - 22.5 * 60, 2.5),       # half way up
    (11 * H - 9 * 60, 3.1),          # 4/5 of the way
    (11 * H, 3.5),                   # start
    (11.5 * H, 3.5),                 # during
    (12 * H, 3.5),                   # end
    (12 * H + 22.5 * 60, 2.5),       # half way down, "the same way"
    (12 * H + 45 * 60, 1.5),
    (13 * H, 1.5),
])
def test_single_activity_ramps(t: float, expected: float) -> None:
    assert r_of_t(t, [THERAPY], P) == pytest.approx(expected)


def test_overlap_takes_the_maximum_and_cancelled_is_ignored() -> None:
    second = ActivityWindow("tv", 12 * H + 30 * 60, 13 * H)        # its ramp starts at 11:45
    t = 12 * H + 15 * 60
    alone_first = r_of_t(t, [THERAPY], P)                          # falling: 3.5 - 2 * 15/45
    alone_second = r_of_t(t, [second], P)                          # rising: 1.5 + 2 * 30/45
    assert alone_first == pytest.approx(3.5 - 2 * 15 / 45)
    assert alone_second == pytest.approx(1.5 + 2 * 30 / 45)
    assert r_of_t(t, [THERAPY, second], P) == pytest.approx(max(alone_first, alone_second))
    cancelled = ActivityWindow("tv", 12 * H + 30 * 60, 13 * H, cancelled=True)
    assert r_of_t(t, [THERAPY, cancelled], P) == pytest.approx(alone_first)
    assert r_of_t(12.75 * H, [cancelled], P) == 1.5
    assert not is_active(12.75 * H, [cancelled])


def test_profile_is_vectorised_and_forbidden_while_active() -> None:
    times = np.array([10 * H, 11 * H, 11.5 * H, 12.25 * H])
    np.testing.assert_allclose(r_profile(times, [THERAPY], P), [1.5, 3.5, 3.5, 2.5 + 1.0 / 3.0])
    forbidden = interaction_cost_profile(times, [THERAPY], P, forbidden_while_active=True)
    assert forbidden[0] == 1.5 and math.isinf(forbidden[1]) and math.isinf(forbidden[2])
    assert forbidden[3] == pytest.approx(2.5 + 1.0 / 3.0)            # the ramp after stays finite


def test_many_objects_at_once() -> None:
    """interaction_cost_profiles (one row per object, what the planner's table is built from):
    values derived by hand for two windows, none, a cancelled one, overlapping ones forbidden
    while active, and ramps of 1000 s before and 2000 s after; then without ramps."""
    params = ChronemicsParams(ramp_before_s=1000.0, ramp_after_s=2000.0)
    a = [ActivityWindow("a", 1000.0, 2000.0), ActivityWindow("a", 5000.0, 6000.0)]
    c = [ActivityWindow("c", 1000.0, 2000.0, cancelled=True)]
    d = [ActivityWindow("d", 0.0, 100.0), ActivityWindow("d", 50.0, 3000.0)]
    times = np.array([500.0, 1500.0, 3000.0, 4500.0, 4750.0])
    rows = interaction_cost_profiles(times, [a, [], c, d], params, [False, False, True, True])
    np.testing.assert_allclose(rows[0], [2.5, 3.5, 2.5, 2.5, 3.0])   # up 1/2, in, down 1/2, up 1/2, up 3/4
    np.testing.assert_array_equal(rows[1], 1.5)
    np.testing.assert_array_equal(rows[2], 1.5)
    np.testing.assert_allclose(rows[3], [math.inf, math.inf, 3.5, 2.0, 1.75])   # [start, end) forbidden
    sharp = ChronemicsParams(ramp_before_s=0.0, ramp_after_s=0.0)
    np.testing.assert_array_equal(interaction_cost_profiles([500.0, 1000.0, 2000.0, 2000.5], [a], sharp, [False])[0],
                                  [1.5, 3.5, 3.5, 1.5])
    assert interaction_cost_profiles(times, [], params, []).shape == (0, 5)


def test_configurable_ramp_and_values() -> None:
    params = ChronemicsParams(r_min=1.0, r_max=5.0, ramp_before_s=600, ramp_after_s=0)
    assert r_of_t(11 * H - 300, [THERAPY], params) == pytest.approx(3.0)
    assert r_of_t(12 * H + 1, [THERAPY], params) == 1.0
    with pytest.raises(ValidationError, match="r_max"):
        ChronemicsParams(r_min=3.0, r_max=2.0)


def test_colour_bands() -> None:
    assert [r_band(r, P) for r in (1.5, 1.99, 2.0, 2.49, 2.5, 3.0, 3.5, math.inf)] == [0, 0, 1, 1, 2, 3, 3, 3]


def test_activity_window_validation() -> None:
    with pytest.raises(AgendaError, match="activity on 'tv': end_s"):
        ActivityWindow("tv", 10.0, 5.0)
