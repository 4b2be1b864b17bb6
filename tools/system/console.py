"""What a person watching `chronav launch` / `chronav demo` sees: live progress, then a summary.

Why rich Live only on a terminal: in CI logs and pipes a redrawing display turns into thousands
of lines, so there we print one plain status line every few seconds instead.
"""

from __future__ import annotations

import json
import sys
import time
from typing import TYPE_CHECKING, Any

from rich.console import Console
from rich.live import Live
from rich.table import Table

from agents.world.vocabulary import MissionState
from scenes.clock import format_clock
from tools.plain import WHOLE_LINE, plural

if TYPE_CHECKING:
    from tools.launch import RunResult


def _status_table(status: dict[str, Any]) -> Table:
    table = Table(title="chronav", show_header=True, expand=False)
    table.add_column("sim time")
    table.add_column("clock")
    table.add_column("missions")
    table.add_column("agents")
    now = status.get("now_s")
    missions = status.get("missions", {})
    mission_text = " ".join(f"{mid}:{m.get('state', '?')}" for mid, m in sorted(missions.items())) or "-"
    agents = " ".join(f"{name}{'' if up == 'up' else '!'}{'' if not r else f'(r{r})'}"
                      for name, (up, r) in status.get("agents", {}).items())
    table.add_row(format_clock(now) if now is not None else "-", str(status.get("clock_mode") or "starting"),
                  mission_text, agents)
    problems = problems_text(status.get("problems") or {})
    if problems:
        table.caption = problems
    return table


def problems_text(problems: dict[str, str]) -> str:
    """``ros_bridge: the ROS 2 side does not answer ...``: what agents report as keeping them from
    their job (agents/runtime/heartbeat.py), for the progress line and the run's summary."""
    return "; ".join(f"{agent}: {problem}" for agent, problem in sorted(problems.items()))


def run_with_progress(scene: str, *, rate: float | None, timeout_s: float, record: bool, restart_limit: int,
                      as_json: bool, with_report: bool, hang_timeout_s: float | None = None,
                      startup_timeout_s: float | None = None, ros_domain: int | None = None,
                      robot: str = "sim", in_process: bool = False, controller: str | None = None,
                      agent_options: dict[str, list[str]] | None = None) -> int:
    """Run the system with a progress display; print the result (and the metrics report); exit code.
    ``controller`` names the navigation's local controller (checked by the caller).

    Exit codes: 0 every mission done; 1 a mission not done, a timeout or an agent given up;
    2 the run could not start (bad scene, option or environment); 130 interrupted (Ctrl-C)."""
    from dsr.errors import DSRError
    from scenes.yamlio import SourceError
    from tools.launch import LaunchError, run_system

    if in_process:   # every agent in this process, in lockstep (tools/inprocess.py): no supervision limits
        from tools.inprocess import run_in_process as run_system  # type: ignore[assignment]

        restart_limit = 0
    err = Console(stderr=True)
    interactive = sys.stderr.isatty() and not as_json
    limits: dict[str, Any] = {k: v for k, v in (("hang_timeout_s", hang_timeout_s), ("startup_timeout_s",
                                                                                     startup_timeout_s),
                                                ("ros_domain", ros_domain), ("robot", robot))
                              if v is not None and not in_process}
    options = {name: list(values) for name, values in (agent_options or {}).items()}   # e.g. launch --model
    if controller is not None:
        options.setdefault("social_navigation", []).append(f"controller={controller}")
    if options:
        limits["agent_options"] = options
    plain_tick = _PlainProgress(err)
    try:
        if interactive:
            with Live(_status_table({}), console=err, refresh_per_second=4) as live:
                result = run_system(scene, rate=rate, timeout_s=timeout_s, record=record,
                                    on_tick=lambda s: live.update(_status_table(s)),
                                    **limits, **_supervision(restart_limit, in_process))
        else:
            result = run_system(scene, rate=rate, timeout_s=timeout_s, record=record,
                                on_tick=None if as_json else plain_tick, **limits,
                                **_supervision(restart_limit, in_process))
    except (SourceError, LaunchError, DSRError) as exc:
        err.print(f"error: {exc}", highlight=False, markup=False, soft_wrap=True)
        return 2
    except KeyboardInterrupt:
        err.print("interrupted before the run started; nothing was launched", highlight=False, soft_wrap=True)
        return 130

    report = _metrics_report(result, as_json) if with_report and not result.interrupted else None
    if as_json:
        print(json.dumps({"scene": result.scene, "ok": result.ok, "outcome": outcome(result),
                          "missions": result.missions, "events": result.events, "restarts": result.restarts,
                          "restart_log": result.restart_log,
                          "wall_s": round(result.wall_s, 2), "interrupted": result.interrupted,
                          "timed_out": result.timed_out, "error": result.error, "problems": result.problems,
                          "run_dir": str(result.run_dir),
                          "rrd": str(result.rrd_path) if result.rrd_path else None,
                          "hours": [{**h, "rrd": str(h["rrd"])} for h in result.hours],
                          **({"report": report} if report is not None else {})}))
    else:
        print_result(result, Console())
    if result.interrupted:
        return 130
    return 0 if result.ok else 1


class _PlainProgress:
    """The progress of a run on a terminal that is not interactive: one line every 5 s at most."""

    def __init__(self, err: Console) -> None:
        self.err = err
        self.last_print = 0.0

    def __call__(self, status: dict[str, Any]) -> None:
        if time.monotonic() - self.last_print >= 5.0:
            self.last_print = time.monotonic()
            now = status.get("now_s")
            missions = status.get("missions", {})
            done = sum(1 for m in missions.values() if m.get("state") == MissionState.DONE)
            mode = status.get("clock_mode") or "starting"    # no clock node yet: the agents are starting
            when = f"sim {format_clock(now) if now is not None else '--:--:--'}"
            problems = problems_text(status.get("problems") or {})
            self.err.print(f"[chronav] {when} clock={mode} missions done {done}/{len(missions)}"
                           + (f" | {problems}" if problems else ""), highlight=False, soft_wrap=True,
                           markup=False)   # "[chronav]" is text, not a rich style tag; one line per tick


def _metrics_report(result: RunResult, as_json: bool) -> dict[str, Any]:
    """The run's metrics report: the one logged during the run, else built now; shown unless JSON."""
    from tools.system.report import build_report, render_report

    report = result.metrics or build_report(result.scene_path or result.scene, result.run_dir, result.missions)
    if not as_json:
        render_report(report, Console())
    return report


def _supervision(restart_limit: int, in_process: bool) -> dict[str, Any]:
    """A launch supervises its processes (restarts); an in-process run has none to restart."""
    return {} if in_process else {"restart_limit": restart_limit}


def outcome(result: Any) -> str:
    """One word for how the run ended: ok, interrupted, timed_out, error or failed."""
    if result.interrupted:
        return "interrupted"
    if result.timed_out:
        return "timed_out"
    if result.error is not None:
        return "error"
    return "ok" if result.ok else "failed"


def print_result(result: Any, out: Console) -> None:
    """The missions table (every mission of the scene, started or not), supervisor events, where
    the run and its recording are, and one closing line saying how the run ended."""
    table = Table(title=f"Missions of {result.scene}")
    for column in ("mission", "state", "started", "finished", "reason"):
        table.add_column(column, no_wrap=column != "reason")   # ids and times stay whole; reasons wrap
    problems = problems_text(getattr(result, "problems", None) or {})
    for mid, m in sorted(result.missions.items(), key=lambda kv: float(kv[1].get("time_s", 0))):
        # A mission that did not end, while an agent reports a problem: the problem is the likely reason.
        reason = str(m.get("reason", "")) or (f"see below: {', '.join(sorted(result.problems))}"
                                              if problems and m.get("state") != MissionState.DONE else "")
        table.add_row(mid, str(m.get("state")),
                      format_clock(float(m["started_s"])) if "started_s" in m else "-",
                      format_clock(float(m["finished_s"])) if "finished_s" in m else "-", reason)
    out.print(table)
    line = WHOLE_LINE    # paths and messages stay whole
    for event in result.events:
        out.print(f"[supervisor] {event}", **line)
    if result.error:
        out.print(f"error: {result.error}", **line)
    if problems:
        out.print(f"problem at the end of the run: {problems}", **line)
    out.print(f"run directory: {result.run_dir}", **line)
    if result.rrd_path:
        out.print(f"recording: {result.rrd_path}  (open with: rerun {result.rrd_path})", **line)
    if result.hours:       # a real-time run: one file per hour
        files = " ".join(str(h["rrd"]) for h in result.hours)
        out.print(f"recording, one file per hour ({', '.join(h['hour'] for h in result.hours)}): "
                  f"open with: rerun {files}", **line)
    done = f"{result.missions_done}/{plural(len(result.missions), 'mission')} done"
    wall = f"{result.wall_s:.1f} s wall"
    closing = {
        "interrupted": f"INTERRUPTED (Ctrl-C or SIGTERM) after {wall}: {done}; agents stopped",
        "timed_out": f"TIMED OUT after {wall} (--timeout): {done}",
        "error": f"FAILED: {done} in {wall}",
        "ok": f"OK: {done} in {wall}",
        "failed": f"FAILED: {done} in {wall}",
    }[outcome(result)]
    warned = f"; but {', '.join(sorted(result.problems))} reported a problem (above)" if problems else ""
    out.print(closing + warned, **line)
