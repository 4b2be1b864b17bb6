"""The progress line `chronav launch` prints when stderr is not a terminal (CI logs, pipes)."""

from __future__ import annotations

import io

from rich.console import Console

from tools.system.console import _PlainProgress


def test_the_plain_progress_line_keeps_its_chronav_prefix():
    # Regression: rich read "[chronav]" as a style tag and dropped it, so CI logs showed " sim 09:30 ...".
    out = io.StringIO()
    progress = _PlainProgress(Console(file=out, width=200, force_terminal=False))
    progress({"now_s": 9 * 3600 + 30 * 60, "clock_mode": "driving",
              "missions": {"m1": {"state": "done"}, "m2": {"state": "pending"}}})
    assert out.getvalue().splitlines() == ["[chronav] sim 09:30:00 clock=driving missions done 1/2"]


def test_the_first_progress_line_says_starting_not_none():
    """Issue 39: before the simulator's clock exists the line read ``sim - clock=None``."""
    out = io.StringIO()
    progress = _PlainProgress(Console(file=out, width=200, force_terminal=False))
    progress({"now_s": None, "clock_mode": None, "missions": {}})
    assert out.getvalue().splitlines() == ["[chronav] sim --:--:-- clock=starting missions done 0/0"]


def test_the_closing_line_counts_one_mission_in_the_singular():
    from types import SimpleNamespace

    from tools.system.console import print_result

    out = io.StringIO()
    result = SimpleNamespace(scene="s", missions={"m1": {"state": "done", "time_s": 0.0}}, events=[], error=None,
                             run_dir="r", rrd_path=None, hours=[], missions_done=1, wall_s=1.0, interrupted=False,
                             timed_out=False, ok=True)
    print_result(result, Console(file=out, width=200, force_terminal=False))
    assert out.getvalue().splitlines()[-1] == "OK: 1/1 mission done in 1.0 s wall"


def test_the_missions_table_at_80_columns_keeps_ids_and_times_whole():
    from types import SimpleNamespace

    from tools.system.console import print_result

    reason = "no way to the goal now: every path crosses an activity's interaction space " * 2
    missions = {f"m_wait_walking_therapy_{i}": {"state": "failed", "time_s": 36_000.0 + i, "started_s": 36_000.0,
                                                 "finished_s": 36_100.0, "reason": reason} for i in range(3)}
    result = SimpleNamespace(scene="center_day", missions=missions, events=[], error=None, run_dir="r",
                             rrd_path=None, hours=[], missions_done=0, wall_s=1.0, interrupted=False, timed_out=False, ok=False)
    out = io.StringIO()
    print_result(result, Console(file=out, width=80, force_terminal=False))
    text = out.getvalue()
    assert all(f"m_wait_walking_therapy_{i}" in text for i in range(3)) and "10:00:00" in text
    assert all(len(line) <= 80 for line in text.splitlines())
