"""The launcher's supervisor restarts crashed processes up to a limit and stops them all."""

from __future__ import annotations

import os
import signal
import time
from pathlib import Path

from tests.support import wait_until
from tools.system.restart_budget import RestartBudget
from tools.system.supervisor import ProgressWatch, Supervisor


def test_crashing_process_is_restarted_until_the_limit(tmp_path: Path) -> None:
    sup = Supervisor(tmp_path / "logs", dict(os.environ), restart_limit=2)
    sup.add("crasher", "tests.unit.crash_helper", ["--exit", "3"])
    sup.start_all()
    try:
        wait_until(lambda: bool(sup.poll()) or sup.processes["crasher"].restarts >= 2, 20, message="restarts")
        wait_until(lambda: (sup.poll() or True) and sup.given_up() == ["crasher"], 20, message="give up")
        assert sup.processes["crasher"].exit_codes == [3, 3, 3]
        assert any("restart limit 2 reached" in e for e in sup.events)
    finally:
        sup.stop_all(timeout_s=2)


def test_stop_all_terminates_long_running_processes(tmp_path: Path) -> None:
    sup = Supervisor(tmp_path / "logs", dict(os.environ), restart_limit=0)
    sup.add("sleeper", "tests.unit.crash_helper", ["--sleep", "60"])
    sup.start_all()
    time.sleep(0.2)
    assert sup.processes["sleeper"].alive
    sup.stop_all(timeout_s=5)
    assert not sup.processes["sleeper"].alive
    assert sup.poll() == []  # stopping: no restart


def test_progress_watch_gives_startup_time_then_a_bound_between_heartbeats() -> None:
    watch = ProgressWatch(hang_s=5.0, startup_s=30.0)
    watch.observe("agent", pid=100, stamp=None, now=0.0)
    assert watch.overdue("agent", 29.0) is None                       # still starting
    assert "wrote no heartbeat within 31.0 s of its start" in (watch.overdue("agent", 31.0) or "")
    watch.observe("agent", pid=100, stamp=(100, 1), now=31.5)
    assert watch.overdue("agent", 36.0) is None
    watch.observe("agent", pid=100, stamp=(100, 2), now=36.0)       # progress resets the bound
    watch.observe("agent", pid=100, stamp=(100, 2), now=40.0)       # the same stamp again is not progress
    reason = watch.overdue("agent", 41.5)
    assert reason is not None and "made no progress for 5.5 s" in reason and "heartbeat 2" in reason
    # A restarted agent (new pid) gets its startup time again; its predecessor's stamp does not count.
    watch.observe("agent", pid=200, stamp=(100, 2), now=42.0)
    assert watch.overdue("agent", 70.0) is None
    watch.observe("agent", pid=200, stamp=(200, 1), now=71.0)
    assert watch.overdue("agent", 75.0) is None and watch.overdue("agent", 76.5) is not None


def test_a_stuck_process_is_killed_restarted_and_logged(tmp_path: Path) -> None:
    sup = Supervisor(tmp_path / "logs", dict(os.environ), restart_limit=1)
    sup.add("sleeper", "tests.unit.crash_helper", ["--sleep", "60"])
    sup.start_all()
    try:
        first = sup.processes["sleeper"].pid
        assert first is not None
        os.kill(first, signal.SIGSTOP)                                  # alive, but frozen
        sup.restart_stuck("sleeper", "made no progress for 9 s")
        assert sup.poll() == ["sleeper"] and sup.processes["sleeper"].pid != first
        assert sup.events == ["sleeper made no progress for 9 s; killed; restart 1/1"]
        sup.restart_stuck("sleeper", "made no progress for 9 s")
        sup.poll()
        assert sup.given_up() == ["sleeper"] and sup.events[-1].endswith("restart limit 1 reached (1 per rolling hour)")
    finally:
        sup.stop_all(timeout_s=2)


class _Clock:
    """A monotonic clock the test moves by hand."""

    def __init__(self) -> None:
        self.now = 1000.0

    def __call__(self) -> float:
        return self.now


def test_the_restart_budget_is_per_rolling_hour_not_per_run() -> None:
    clock = _Clock()
    budget = RestartBudget(limit=3, clock=clock, wall_clock=lambda: 1.7e9)
    for minute in (0, 10, 20):                       # three crashes in 20 minutes: all restarted
        clock.now = 1000.0 + 60 * minute
        assert budget.allows("agenda")
        budget.take("agenda", f"exited with 1 at minute {minute}")
    clock.now = 1000.0 + 60 * 30
    assert not budget.allows("agenda") and budget.used("agenda") == 3   # a fourth within the hour: no
    assert budget.allows("executive")                                    # the budget is per agent
    clock.now = 1000.0 + 3600.0 + 1.0                # an hour after the first crash, it leaves the window
    assert budget.used("agenda") == 2 and budget.allows("agenda")
    budget.take("agenda", "made no progress for 61 s")
    clock.now += 7 * 24 * 3600.0                     # a week later: a fresh budget, the log keeps all
    assert budget.used("agenda") == 0
    assert [r.reason for r in budget.log][-1] == "made no progress for 61 s" and len(budget.log) == 4
    assert budget.log[0].as_json() == {"agent": "agenda", "reason": "exited with 1 at minute 0", "at_unix_s": 1.7e9}


def test_a_supervisor_restarts_again_once_its_hour_has_passed(tmp_path: Path) -> None:
    clock = _Clock()
    budget = RestartBudget(limit=1, clock=clock)
    sup = Supervisor(tmp_path / "logs", dict(os.environ), budget=budget)
    sup.add("crasher", "tests.unit.crash_helper", ["--exit", "3"])
    sup.start_all()
    try:
        wait_until(lambda: sup.poll() == ["crasher"], 20, message="first restart")
        clock.now += 3601.0                                      # the first restart leaves the window
        wait_until(lambda: sup.poll() == ["crasher"], 20, message="second restart, an hour later")
        wait_until(lambda: (sup.poll() or True) and sup.given_up() == ["crasher"], 20, message="give up")
        assert sup.processes["crasher"].restarts == 2
        assert [r.reason for r in budget.log] == ["exited with 3", "exited with 3"]
    finally:
        sup.stop_all(timeout_s=2)
