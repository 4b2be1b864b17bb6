"""ClockPace (agents/sim_robot/clock.py): how far each clock mode may move the sim clock, given
made-up wall times (the simulator itself is exercised by test_sim_clock_hold, test_idle_skip_events,
test_lockstep)."""

from __future__ import annotations

import pytest

from agents.sim_robot.clock import EXTERNAL_STEP_MAX_S, IDLE_STEP_MAX_S, MAX_SKIP_S, ClockPace

DT = 0.1


def pace(rate: float = 10.0, busy_rate: float = 1.0, skip_idle: bool = True) -> ClockPace:
    clock = ClockPace(rate=rate, busy_rate=busy_rate, control_dt=DT, skip_idle=skip_idle)
    clock.reanchor(wall_now=100.0, sim_now=3600.0)
    return clock


def test_driving_never_runs_ahead_of_the_rate() -> None:
    clock = pace(rate=10.0)
    assert clock.driving_allows(100.0, 3600.0), "the first step after an anchor is always allowed"
    # 1 wall s at rate 10 allows 10 sim s: the lockstep may be at 3610 and take one more step
    assert clock.driving_allows(101.0, 3610.0)
    assert not clock.driving_allows(101.0, 3610.0 + DT + 1e-9), "ahead of the rate: wait"


def test_busy_moves_at_busy_rate_one_control_step_at_most() -> None:
    clock = pace(busy_rate=1.0)
    assert clock.busy_step(100.05, 3600.0) == pytest.approx(0.05)
    assert clock.busy_step(105.0, 3600.0) == DT
    assert clock.busy_step(100.05, 3600.2) == 0.0, "ahead: no step, never backwards"


def test_busy_rate_zero_holds_the_clock() -> None:
    assert pace(busy_rate=0.0).busy_step(1e6, 3600.0) == 0.0


def test_idle_skips_to_the_deadline_in_pieces_that_end_at_events_and_the_day() -> None:
    clock = pace()
    assert clock.idle_skip(3600.0, 3700.0, end_s=50000.0, next_event_s=float("inf")) == 3700.0
    assert clock.idle_skip(3600.0, 9000.0, 50000.0, float("inf")) == 3600.0 + MAX_SKIP_S
    assert clock.idle_skip(3600.0, 3700.0, 50000.0, next_event_s=3650.0) == 3650.0
    assert clock.idle_skip(3600.0, 3700.0, end_s=3620.0, next_event_s=float("inf")) == 3620.0


@pytest.mark.parametrize("deadline", [None, 3600.0, 3500.0])
def test_idle_does_not_skip_without_a_later_deadline(deadline: float | None) -> None:
    assert pace().idle_skip(3600.0, deadline, 50000.0, float("inf")) is None


def test_idle_does_not_skip_without_skip_idle() -> None:
    assert pace(skip_idle=False).idle_skip(3600.0, 3700.0, 50000.0, float("inf")) is None


def test_idle_without_skips_runs_at_the_rate_or_busy_rate_when_a_mission_is_due() -> None:
    clock = pace(rate=10.0, busy_rate=1.0)
    inf = float("inf")
    assert clock.idle_step(100.2, 3600.0, mission_due=False, next_event_s=inf) == pytest.approx(2.0)
    assert clock.idle_step(100.2, 3600.0, mission_due=True, next_event_s=inf) == pytest.approx(0.2)
    assert clock.idle_step(110.0, 3600.0, False, inf) == IDLE_STEP_MAX_S
    assert clock.idle_step(110.0, 3600.0, False, next_event_s=3601.5) == pytest.approx(1.5), "up to the event"
    assert clock.idle_step(110.0, 3600.0, False, next_event_s=3600.0) == pytest.approx(1e-3), "an event due now"
    assert clock.idle_step(100.0, 3600.0, False, inf) == 0.0


def test_external_runs_in_real_time_whatever_the_rate() -> None:
    clock = pace(rate=60.0)
    assert clock.external_step(100.05, 3600.0) == 0.0, "less than a control step: wait"
    assert clock.external_step(100.5, 3600.0) == pytest.approx(0.5)
    assert clock.external_step(130.0, 3600.0) == EXTERNAL_STEP_MAX_S, "after a stall: one second at a time"


def test_reanchor_forgets_time_owed_in_another_mode() -> None:
    clock = pace(busy_rate=1.0)
    clock.reanchor(wall_now=200.0, sim_now=3600.0)
    assert clock.busy_step(200.0, 3600.0) == 0.0
