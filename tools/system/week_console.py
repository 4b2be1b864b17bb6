"""What a person watching `chronav launch SCENE --days N` sees: one progress line per few seconds
naming the day, then one row per day, then how the run ended.

Why plain lines and no live table: a run of days is watched in a log (journald, a CI log, tmux
scrollback) far more than on a terminal, and a line per few seconds over a week is readable there.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.table import Table

from agents.world.vocabulary import MissionState
from scenes.clock import format_clock
from tools.plain import WHOLE_LINE

#: wall seconds between two progress lines
PROGRESS_EVERY_S = 5.0


class DayProgress:
    """``[chronav] day 2/7 tue 2026-12-01 sim 09:30 clock=idle missions done 1/3``, every few seconds."""

    def __init__(self, err: Console) -> None:
        self.err = err
        self.last_print = -PROGRESS_EVERY_S
        self.last_day: object = None

    def __call__(self, status: dict[str, Any]) -> None:
        new_day = status.get("day") != self.last_day
        if not new_day and time.monotonic() - self.last_print < PROGRESS_EVERY_S:
            return
        self.last_print, self.last_day = time.monotonic(), status.get("day")
        now = status.get("now_s")
        missions = status.get("missions", {})
        done = sum(1 for m in missions.values() if m.get("state") == MissionState.DONE)
        self.err.print(f"[chronav] day {status.get('day')}/{status.get('days')} {status.get('date')} "
                       f"sim {format_clock(now) if now is not None else '-'} clock={status.get('clock_mode')} "
                       f"missions done {done}/{len(missions)}", highlight=False, markup=False)


def run_days_with_progress(scene: str, *, days: int | None, keep_days: int | None, in_process: bool,
                           as_json: bool, **options: Any) -> int:
    """Run the days with progress lines; print the days and the result; the exit code.

    Exit codes as `chronav launch`: 0 every day ran and every mission was done; 1 otherwise (a day
    refused, a mission not done, a disk that filled); 2 the run could not start; 130 interrupted."""
    from dsr.errors import DSRError
    from scenes.yamlio import SourceError
    from tools.launch import LaunchError
    from tools.week import run_days

    err = Console(stderr=True)
    try:
        result = run_days(scene, days=days, keep_days=keep_days, in_process=in_process,
                          on_tick=None if as_json else DayProgress(err), **options)
    except (SourceError, LaunchError, DSRError) as exc:
        err.print(f"error: {exc}", highlight=False, markup=False, soft_wrap=True)
        return 2
    if as_json:
        summary = json.loads((result.run_dir / "result.json").read_text())
        print(json.dumps({**summary, "run_dir": str(result.run_dir),
                          "index": str(result.run_dir / "index.json")}))
    else:
        _print_days(result, Console())
    if result.error:
        sys.stderr.write(f"error: {result.error}\n")
    if result.interrupted:
        return 130
    return 0 if result.ok else 1


def _print_days(result: Any, out: Console) -> None:
    table = Table(title=f"Days of {result.scene}")
    for column in ("day", "date", "status", "missions done", "wall s", "rss MB (max agent)", "DSR nodes/edges/tomb"):
        table.add_column(column)
    for day in result.days:
        summary = day.get("missions_summary") or {}
        rss = max((a.get("rss_mb", 0.0) for a in (day.get("agents") or {}).values()), default=None)
        dsr = day.get("dsr") or {}
        table.add_row(str(day["day"]), f"{day['weekday']} {day['date']}", str(day["status"]),
                      f"{summary.get('done', 0)}/{summary.get('total', 0)}" if summary else "-",
                      f"{day.get('wall_s', 0):.1f}" if "wall_s" in day else "-",
                      f"{rss:.0f}" if rss is not None else "-",
                      f"{dsr.get('nodes', '-')}/{dsr.get('edges', '-')}/{dsr.get('tombstones', '-')}")
    out.print(table)
    line = WHOLE_LINE    # paths and messages stay whole
    for day in result.days:
        if day["status"] == "refused":
            out.print(f"day {day['day']} ({day['date']}) refused: {day['reason']}", **line)
    for restart in result.restart_log:
        out.print(f"[supervisor] restart of {restart['agent']}: {restart['reason']}", **line)
    out.print(f"run directory: {result.run_dir}", **line)
    out.print(f"index: {Path(result.run_dir) / 'index.json'}  (open with: rerun $(python -m tools.week_index "
              f"{Path(result.run_dir) / 'index.json'}))", **line)
    done = sum(1 for d in result.days if d["status"] == "ok")
    out.print(f"{result.outcome.upper()}: {done}/{result.planned_days} days ok in {result.wall_s:.1f} s wall", **line)
