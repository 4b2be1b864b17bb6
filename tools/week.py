"""`chronav launch SCENE --days N`: a run that spans days, one day after the other.

Why one launch (or one in-process run) per day rather than one run that lives through the nights:
every part of chronav counts time from midnight of the scene's date (scenes/days.py says why),
and a care-home robot docks, charges and is restarted overnight anyway.  So each day is a run of
its own on that day's scene (scenes/days.py ``day_scene_data``): the agenda of that date
(``.ics`` recurrences, YAML ``weekdays``/``dates``), the missions given that day, the scripted
changes naming it.  The robot starts every day at its dock (the scene's robot pose), the people
arrive from their scene poses and follow their routines, with a crowd seed per day.  The night is
skipped: the next day starts at its own ``clock.start``.

What spans the days: one restart budget (N restarts per agent per rolling hour of wall time,
tools/system/restart_budget.py), the run folder with its ``index.json`` (one recording and one run
directory per day, tools/week_index.py) and ``result.json`` with per-day accounting: missions
and a metrics summary, each agent's RSS and CPU time, the DSR's node, edge and tombstone counts,
bytes written.  A day whose agenda cannot be loaded is refused with the reason, and the run goes
on with the next day; a disk that fills while the run rotates to the next day ends the run
cleanly with a clear error (every file is written to a temporary name and renamed).
"""

from __future__ import annotations

import csv
import datetime as dt
import math
import os
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from datetime import datetime
from pathlib import Path
from typing import Any

from scenes.days import MAX_DAYS, SECONDS_PER_DAY, day_scene_data, weekday_of
from tools.launch import LaunchError, RunResult, hourly_rotation, realtime_run
from tools.system.restart_budget import RestartBudget
from tools.week_index import (INDEX_KIND, INDEX_NAME, RotationError, apply_retention, tree_bytes, write_atomic,
                              write_json)

#: seconds of wall time between two samples of the agents' memory and CPU during a launched day
SAMPLE_EVERY_S = 5.0
#: wall seconds a launched day's end may wait for its last tombstones to be forgotten before the
#: day's DSR counts are read (tools/launch.py ``_settled_status``)
SETTLE_S = 3.0
MB = 1024.0 * 1024.0


@dataclass
class LongRunResult:
    """What a run of several days leaves: its folder, each day's record, how it ended."""

    scene: str
    run_dir: Path
    days: list[dict[str, Any]]
    wall_s: float
    planned_days: int
    interrupted: bool = False
    error: str | None = None
    restart_log: list[dict[str, object]] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return (self.error is None and not self.interrupted and len(self.days) == self.planned_days
                and all(d["status"] == "ok" for d in self.days))

    @property
    def outcome(self) -> str:
        if self.interrupted:
            return "interrupted"
        if self.error is not None:
            return "error"
        return "ok" if self.ok else "failed"


def scene_days(scene: str | Path) -> int:
    """How many days a scene says it spans (its ``clock.days``), read without validating the scene
    (every launch asks); 1 if it cannot be read or says nothing usable (the launch then says why)."""
    from scenes.loader import resolve_scene_path
    from scenes.yamlio import SourceError, load_located_file

    try:
        data = load_located_file(resolve_scene_path(scene)).data
    except SourceError:
        return 1
    clock = data.get("clock") if isinstance(data, dict) else None
    days = clock.get("days") if isinstance(clock, dict) else None
    return days if isinstance(days, int) and not isinstance(days, bool) and days > 1 else 1


def check_days(days: int | None, keep_days: int | None) -> None:
    if days is not None and not 1 <= days <= MAX_DAYS:
        raise LaunchError(f"--days {days}: give the number of days to run, 1 to {MAX_DAYS}")
    if keep_days is not None and keep_days < 1:
        raise LaunchError(f"--keep-days {keep_days}: give how many days of recordings and logs to keep, at least 1")


class ResourceSampler:
    """Each agent's RSS and CPU time, and the DSR's counts, as last seen during a day.

    Launched: every agent process by its pid (sampled every SAMPLE_EVERY_S from the status the
    launcher hands ``on_tick``); in-process: the one process, sampled at the day's end."""

    def __init__(self, in_process: bool) -> None:
        self.in_process = in_process
        self.agents: dict[str, dict[str, float]] = {}
        self.dsr: dict[str, int] = {}
        self._last = -math.inf

    def tick(self, status: dict[str, Any]) -> None:
        if isinstance(status.get("dsr"), dict):
            self.dsr = dict(status["dsr"])
        now = time.monotonic()
        if self.in_process or now - self._last < SAMPLE_EVERY_S:
            return
        self._last = now
        for name, pid in (status.get("pids") or {}).items():
            sample = _process_sample(pid)
            if sample is not None:
                self.agents[name] = sample

    def finish(self) -> None:
        if self.in_process:
            sample = _process_sample(os.getpid())
            if sample is not None:
                self.agents = {"in_process": sample}


def process_usage(pid: int | None) -> tuple[float, float] | None:
    """(RSS in MB, CPU seconds user + system) of process ``pid``; None when there is no such
    process (any more) or it may not be read.  The one reading of an agent's memory and CPU: the
    per-day accounting and the real-time soak (tools/soak.py)."""
    import psutil

    if pid is None:
        return None
    try:
        process = psutil.Process(pid)
        with process.oneshot():
            cpu = process.cpu_times()
            return process.memory_info().rss / MB, cpu.user + cpu.system
    except (psutil.NoSuchProcess, psutil.AccessDenied, psutil.ZombieProcess):
        return None


def _process_sample(pid: int | None) -> dict[str, float] | None:
    usage = process_usage(pid)
    if usage is None:
        return None
    return {"rss_mb": round(usage[0], 2), "cpu_s": round(usage[1], 2)}


def _path_length_m(trajectory: Path) -> float | None:
    """Distance the robot drove that day (trajectory.csv: t,x,y,theta)."""
    if not trajectory.is_file():
        return None
    total, last = 0.0, None
    with trajectory.open(newline="") as handle:
        for row in csv.DictReader(handle):
            try:
                point = (float(row["x"]), float(row["y"]))
            except (KeyError, TypeError, ValueError):
                continue
            if last is not None:
                total += math.dist(last, point)
            last = point
    return round(total, 2)


def mission_summary(result: RunResult) -> dict[str, Any]:
    """How the day's missions went, and how long they took (sim s)."""
    from agents.world.vocabulary import MissionState

    states = [str(m.get("state")) for m in result.missions.values()]
    from dsr.attr_values import as_float

    durations = [as_float(m["finished_s"]) - as_float(m["started_s"]) for m in result.missions.values()
                 if "finished_s" in m and "started_s" in m]
    return {"total": len(states), "done": states.count(MissionState.DONE),
            "failed": states.count(MissionState.FAILED),
            "not_done": len(states) - states.count(MissionState.DONE) - states.count(MissionState.FAILED),
            "duration_mean_s": round(sum(durations) / len(durations), 1) if durations else None,
            "duration_max_s": round(max(durations), 1) if durations else None}


def _outcome(result: RunResult) -> str:
    from tools.system.console import outcome

    return outcome(result)


@dataclass
class _LongRun:
    """The run's folder and what it has written so far (index entries and day records)."""

    scene_name: str
    scene_path: Path
    run_dir: Path
    first: dt.date
    planned: int
    keep_days: int | None
    started: float
    budget: RestartBudget
    entries: list[dict[str, Any]] = field(default_factory=list)
    days: list[dict[str, Any]] = field(default_factory=list)

    def write(self, result: LongRunResult | None = None) -> None:
        """index.json and result.json, each whole or not at all (RotationError)."""
        removed = set(apply_retention(self.entries, self.run_dir, self.keep_days))
        for record in self.days:
            if record["day"] in removed:
                record.update(rrd=None, run_dir=None, removed=True)
        write_json(self.run_dir / INDEX_NAME, {
            "kind": INDEX_KIND, "version": 1, "scene": self.scene_name, "first_date": self.first.isoformat(),
            "days": self.planned, "time": "week seconds: seconds since local midnight of first_date; "
                                          "a day's offset_s plus its own clock seconds",
            "entries": self.entries})
        write_json(self.run_dir / "result.json", {
            "scene": self.scene_name, "scene_path": str(self.scene_path.resolve()), "long_run": True,
            "ok": result.ok if result else False, "outcome": result.outcome if result else "running",
            "error": result.error if result else None, "interrupted": bool(result and result.interrupted),
            "days_planned": self.planned, "first_date": self.first.isoformat(),
            "wall_s": round(time.monotonic() - self.started, 2),
            "restart_budget": self.budget.describe(),
            "restarts_total": len(self.budget.log), "restart_log": [r.as_json() for r in self.budget.log],
            "days": self.days})


def run_days(scene: str | Path, *, days: int | None = None, keep_days: int | None = None,
             in_process: bool = False, runs_dir: Path | None = None, timeout_s: float = 900.0,
             record: bool = True, restart_limit: int = 3,
             on_tick: Callable[[dict[str, object]], None] | None = None,
             stop: threading.Event | None = None, **launch_options: Any) -> LongRunResult:
    """Run SCENE's days one after the other (``days`` overrides ``clock.days``); ``timeout_s`` per day.

    ``launch_options`` go to each day's ``run_system`` (rate, hang and startup timeouts, ROS); an
    in-process run takes ``rate`` and ``agent_options`` only."""
    from agents.lib.agenda import AgendaError
    from agents.world.scene_world import resolve_world
    from dsr import DSRError
    from dsr.collector import release_free_memory
    from scenes.loader import load_scene
    from scenes.yamlio import SourceError
    from tools.launch import _make_run_dir
    from tools.system.runs import runs_dir as default_runs_dir

    check_days(days, keep_days)
    loaded = load_scene(scene)
    spec = loaded.scene
    planned = days or spec.clock.days
    realtime = realtime_run(launch_options.get("rate"), spec.clock.rate, launch_options.get("robot") or "sim")
    run_id = f"{spec.name}-{datetime.now().strftime('%Y%m%d-%H%M%S')}-{os.getpid()}"
    run_dir = _make_run_dir(runs_dir or default_runs_dir(), run_id)
    (run_dir / "days").mkdir(exist_ok=True)
    budget = RestartBudget(limit=restart_limit)
    run = _LongRun(scene_name=spec.name, scene_path=loaded.path, run_dir=run_dir, first=spec.clock.date,
                   planned=planned, keep_days=keep_days, started=time.monotonic(), budget=budget)
    result = LongRunResult(scene=spec.name, run_dir=run_dir, days=run.days, wall_s=0.0, planned_days=planned)
    try:
        for number in range(1, planned + 1):
            date = spec.clock.date + dt.timedelta(days=number - 1)
            entry: dict[str, Any] = {"day": number, "date": date.isoformat(), "weekday": weekday_of(date),
                                     "offset_s": (number - 1) * SECONDS_PER_DAY, "rrd": None, "run_dir": None}
            run.entries.append(entry)
            try:
                resolve_world(loaded, number)   # that date's agenda, missions and changes, checked
            except (SourceError, AgendaError) as exc:
                entry.update(status="refused", reason=str(exc))
                run.days.append({**entry, "status": "refused", "reason": str(exc)})
                run.write()
                continue
            day_file = run_dir / "days" / f"day{number}.yaml"
            write_day_scene(day_file, loaded, number)
            sampler = ResourceSampler(in_process)
            try:
                with hourly_rotation(realtime):
                    day_result = _run_one_day(day_file, number, planned, date, sampler, in_process=in_process,
                                              runs_dir=run_dir, timeout_s=timeout_s, record=record, budget=budget,
                                              on_tick=on_tick, stop=stop, launch_options=launch_options)
            except (LaunchError, DSRError) as exc:
                if number == 1:
                    raise          # bad options or environment: the run could not start (exit 2)
                entry.update(status="error", reason=str(exc))   # a later day that could not start
                run.days.append({**entry})
                run.write()
                continue
            # The day's agents are gone (launched) or torn down (in-process): what they freed goes
            # back to the system before the next day, so the run's memory does not creep up.
            release_free_memory()
            sampler.finish()
            entry.update(status=_outcome(day_result), rrd=_rel(day_result.rrd_path, run_dir),
                         run_dir=_rel(day_result.run_dir, run_dir))
            recordings = [day_result.rrd_path]
            if day_result.hours:    # a real-time day: its recording is one file per hour
                entry.update(rrd=None, hours=[{**h, "rrd": _rel(h["rrd"], run_dir)} for h in day_result.hours])
                recordings = [h["rrd"] for h in day_result.hours]
            run.days.append(_day_record(entry, day_result, sampler, day_file, recordings))
            run.write()
            if day_result.interrupted or (stop is not None and stop.is_set()):
                result.interrupted = True
                break
    except RotationError as exc:
        result.error = str(exc)
    except KeyboardInterrupt:
        result.interrupted = True
    result.wall_s = time.monotonic() - run.started
    result.restart_log = [r.as_json() for r in budget.log]
    try:
        run.write(result)
    except RotationError as exc:
        result.error = result.error or str(exc)
    return result


def write_day_scene(day_file: Path, loaded: Any, number: int) -> None:
    """Day ``number``'s single-day scene, written whole or not at all."""
    import yaml

    data = day_scene_data(loaded.located.data, number, loaded.path.parent.resolve(), first=loaded.scene.clock.date,
                          seed_offset=number - 1)
    write_atomic(day_file, yaml.safe_dump(data, sort_keys=False, allow_unicode=True))


def _run_one_day(day_file: Path, number: int, planned: int, date: dt.date, sampler: ResourceSampler, *,
                 in_process: bool, runs_dir: Path, timeout_s: float, record: bool, budget: RestartBudget,
                 on_tick: Callable[[dict[str, object]], None] | None, stop: threading.Event | None,
                 launch_options: dict[str, Any]) -> RunResult:
    def tick(status: dict[str, Any]) -> None:
        sampler.tick(status)
        if on_tick is not None:
            now = status.get("now_s")
            on_tick({**status, "day": number, "days": planned, "date": date.isoformat(),
                     "week_s": None if now is None else (number - 1) * SECONDS_PER_DAY + float(now)})

    if in_process:
        from tools.inprocess import run_in_process

        options = {k: v for k, v in launch_options.items() if k in ("rate", "agent_options")}
        return run_in_process(day_file, runs_dir=runs_dir, timeout_s=timeout_s, record=record, on_tick=tick,
                              stop=stop, **options)
    from tools.launch import run_system

    return run_system(day_file, runs_dir=runs_dir, timeout_s=timeout_s, record=record, on_tick=tick,
                      restart_budget=budget, restart_limit=budget.limit, metrics_report=False, settle_s=SETTLE_S,
                      **launch_options)


def _rel(path: Path | None, base: Path) -> str | None:
    return None if path is None else os.path.relpath(path, base)


def _day_record(entry: dict[str, Any], result: RunResult, sampler: ResourceSampler, day_file: Path,
                recordings: list[Path | None]) -> dict[str, Any]:
    """One day of result.json: missions, a metrics summary, resources, DSR counts, bytes, restarts."""
    return {**entry, "reason": result.error, "wall_s": round(result.wall_s, 2),
            "missions": result.missions, "missions_summary": mission_summary(result),
            "metrics": {"path_length_m": _path_length_m(result.run_dir / "trajectory.csv"), **result.metrics},
            "agents": sampler.agents, "dsr": sampler.dsr,
            "bytes_written": tree_bytes(result.run_dir, day_file, *recordings),
            "rrd_bytes": tree_bytes(*recordings),
            "restarts": result.restarts, "restart_log": result.restart_log, "events": result.events}
