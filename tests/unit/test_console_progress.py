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
