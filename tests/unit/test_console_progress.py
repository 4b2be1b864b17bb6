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
                             run_dir="r", rrd_path=None, missions_done=1, wall_s=1.0, interrupted=False,
                             timed_out=False, ok=True)
    print_result(result, Console(file=out, width=200, force_terminal=False))
    assert out.getvalue().splitlines()[-1] == "OK: 1/1 mission done in 1.0 s wall"
