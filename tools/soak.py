"""A real-time soak: a scene's agents launched as processes at rate 1, each one's memory watched
for hours, and the slope of its memory over time fitted (issue 41: under 1 MB per hour per agent).

Why a slope and not a ratio: in real time, a day's first hour and its last differ in what happens
(people, missions); what a months-long deployment cannot afford is memory that keeps climbing.  A
least-squares line through each agent's RSS, sampled every ``sample_every_s`` after a warm-up
(imports, maps, first plans, caches filling), measures that climb in MB per hour, robust to the
noise of single samples.  An agent restarted mid-soak starts a new series (its memory starts
over, which would fake a fall); its slope is fitted on its longest series.

The run is the week runner's (tools/week.py ``run_days``, one day at rate 1, so the recording
rotates every hour as a real-time run does); the scene is the given one with the clock at rate 1,
no idle skipping (the clock must run in real time) and an end after the soak, so only the
soak's own timeout ends it.
"""

from __future__ import annotations

import datetime as dt
import math
import os
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from scenes.clock import format_clock_minutes
from tools.week import MB, process_usage
from tools.week_index import tree_bytes

#: seconds of wall time between two samples of each agent's memory in the real soak
SAMPLE_EVERY_S = 60.0
#: goal of issue 41: memory slope under this, per agent
GOAL_MB_PER_H = 1.0


def fit_slope_per_hour(samples: list[tuple[float, float]]) -> float | None:
    """The least-squares slope of ``(seconds, MB)`` samples, in MB per hour; None under 3 samples
    or when they span no time."""
    if len(samples) < 3:
        return None
    n = len(samples)
    mean_t = sum(t for t, _ in samples) / n
    mean_m = sum(m for _, m in samples) / n
    var = sum((t - mean_t) ** 2 for t, _ in samples)
    if var <= 0.0:
        return None
    cov = sum((t - mean_t) * (m - mean_m) for t, m in samples)
    return cov / var * 3600.0


def private_mb(pid: int) -> float | None:
    """Process ``pid``'s private memory (USS: pages no other process maps, in MiB); None if it
    cannot be read.

    Why beside the RSS: two thirds of an agent's RSS are the shared libraries' code pages (numba's
    LLVM, Rerun, Zenoh: 350-390 MB of an agent's 530-620 MB, read in /proc/<pid>/smaps_rollup
    during a soak), which the kernel reads in as code paths first run and may drop at any time;
    they are bounded by the libraries' size.  A leak shows in the private memory."""
    import psutil

    try:
        return float(psutil.Process(pid).memory_full_info().uss) / MB
    except (psutil.NoSuchProcess, psutil.AccessDenied, psutil.ZombieProcess):
        return None


#: one sample: seconds since the soak began, RSS and private memory (MB; private None if unread)
Sample = tuple[float, float, float | None]


@dataclass
class MemorySeries:
    """Each agent's RSS and private memory over wall time, one series per process (a restart opens
    a new one)."""

    warmup_s: float
    sample_every_s: float = SAMPLE_EVERY_S
    clock: Callable[[], float] = time.monotonic
    #: every sample (warm-up included) is appended here as it is taken, so the curve behind a
    #: slope can be read afterwards, even of a soak that was cut short
    samples_csv: Path | None = None
    started: float | None = None
    series: dict[str, list[tuple[int, list[Sample]]]] = field(default_factory=dict)
    _last: float = -math.inf

    def add(self, name: str, pid: int, t_s: float, rss_mb: float, private: float | None = None) -> None:
        """One sample of agent ``name`` (process ``pid``) at ``t_s`` seconds since the soak began;
        samples inside the warm-up are not kept."""
        runs = self.series.setdefault(name, [])
        if not runs or runs[-1][0] != pid:
            runs.append((pid, []))
        if self.samples_csv is not None:
            new = not self.samples_csv.exists()
            with self.samples_csv.open("a", encoding="utf-8") as handle:
                if new:
                    handle.write("agent,pid,t_s,rss_mb,private_mb\n")
                handle.write(f"{name},{pid},{t_s:.1f},{rss_mb:.2f},{'' if private is None else f'{private:.2f}'}\n")
        if t_s >= self.warmup_s:
            runs[-1][1].append((t_s, rss_mb, private))

    def tick(self, pids: dict[str, int | None]) -> bool:
        """Sample every agent of ``pids`` (name -> pid) if ``sample_every_s`` has passed; True when it did."""
        now = self.clock()
        if self.started is None:
            self.started = now
        if now - self._last < self.sample_every_s:
            return False
        self._last = now
        for name, pid in pids.items():
            usage = process_usage(pid)
            if pid is None or usage is None:
                continue
            self.add(name, pid, now - self.started, usage[0], private_mb(pid))
        return True

    def slopes(self, private: bool = False) -> dict[str, float | None]:
        """Each agent's memory slope (MB/h, of its RSS or of its private memory) on its longest
        series after the warm-up."""
        out: dict[str, float | None] = {}
        for name, runs in self.series.items():
            longest = max((samples for _, samples in runs), key=len)
            points = [(t, p) for t, _, p in longest if p is not None] if private else [(t, r) for t, r, _ in longest]
            slope = fit_slope_per_hour(points)
            out[name] = None if slope is None else round(slope, 3)
        return out

    def report(self) -> dict[str, object]:
        """The flat part of the soak's JSON: the largest slope, each agent's, samples and processes;
        of the RSS (``soak_mem_*``) and of the private memory (``soak_private_*``)."""
        slopes, private = self.slopes(), self.slopes(private=True)
        flat: dict[str, object] = {"soak_mem_slope_goal_mb_per_h": GOAL_MB_PER_H}
        for key, found in (("mem", slopes), ("private", private)):
            known = [s for s in found.values() if s is not None]
            flat[f"soak_{key}_slope_mb_per_h_max"] = max(known) if known else None
            over = sorted(n for n, s in found.items() if s is not None and s >= GOAL_MB_PER_H)
            flat["soak_agents_over_goal" if key == "mem" else "soak_agents_over_goal_private"] = over
        for name, slope in sorted(slopes.items()):
            runs = self.series[name]
            last = runs[-1][1][-1] if runs[-1][1] else None
            flat[f"soak_mem_slope_mb_per_h_{name}"] = slope
            flat[f"soak_private_slope_mb_per_h_{name}"] = private.get(name)
            flat[f"soak_rss_mb_last_{name}"] = round(last[1], 2) if last else None
            flat[f"soak_private_mb_last_{name}"] = round(last[2], 2) if last and last[2] is not None else None
            flat[f"soak_processes_{name}"] = len(runs)
        flat["soak_samples"] = sum(len(s) for runs in self.series.values() for _, s in runs)
        return flat


def soak_scene(scene: str | Path, hours: float, out: Path) -> Path:
    """SCENE's first day as a scene of its own at rate 1, without idle skipping, whose clock runs
    past the soak (so only the soak's timeout ends the run); written to ``out``."""
    import yaml

    from scenes.days import SECONDS_PER_DAY, day_scene_data
    from scenes.loader import load_scene
    from tools.week_index import write_atomic

    loaded = load_scene(scene)
    data = day_scene_data(loaded.located.data, 1, loaded.path.parent.resolve(), first=loaded.scene.clock.date)
    clock = dict(data["clock"])
    start = loaded.scene.clock.start_s
    end = min(start + hours * 3600.0 + 1800.0, SECONDS_PER_DAY - 60.0)
    clock.update(rate=1, skip_idle=False, end=format_clock_minutes(end))
    data["clock"] = clock
    write_atomic(out, yaml.safe_dump(data, sort_keys=False, allow_unicode=True))
    return out



def run_soak(scene: str, hours: float, *, warmup_s: float = 600.0, sample_every_s: float = SAMPLE_EVERY_S,
             workdir: Path | None = None) -> dict[str, object]:
    """Launch SCENE's agents as processes at rate 1 for ``hours`` of wall time, sampling each
    agent's RSS; the soak's flat report (every process is stopped when it returns)."""
    from tools.week import run_days

    if not hours > 0:
        raise ValueError(f"--soak-hours {hours}: give the soak's length in hours, more than 0")
    workdir = workdir or Path(tempfile.mkdtemp(prefix="chronav-soak-"))
    workdir.mkdir(parents=True, exist_ok=True)
    scene_file = soak_scene(scene, hours, workdir / "soak_scene.yaml")
    memory = MemorySeries(warmup_s=warmup_s, sample_every_s=sample_every_s,
                          samples_csv=workdir / "soak_samples.csv")

    parts_peak = 0

    def tick(status: dict[str, Any]) -> None:
        nonlocal parts_peak
        pids, run = status.get("pids"), status.get("run")
        if isinstance(pids, dict) and memory.tick(pids) and isinstance(run, dict):
            # with the memory: the agents' parts, what a real-time day holds on disk until its hours are merged
            parts_peak = max(parts_peak, tree_bytes(Path(str(run["run_dir"])) / "rrd"))

    started = time.monotonic()
    os.environ.setdefault("RERUN", "on")   # a deployment records, and rotates its recording every hour
    started_utc = dt.datetime.now(dt.UTC).isoformat(timespec="seconds")
    result = run_days(scene_file, days=1, in_process=False, runs_dir=workdir, timeout_s=hours * 3600.0,
                      on_tick=tick, rate=1.0)
    wall = time.monotonic() - started
    day = result.days[0] if result.days else {}
    report: dict[str, object] = {
        "scene": scene, "soak_hours": round(wall / 3600.0, 3), "soak_hours_planned": hours,
        "soak_warmup_min": round(warmup_s / 60.0, 2), "soak_sample_every_s": sample_every_s,
        # the soak's own timeout ends the day: that is the soak going as planned
        "soak_ok": result.error is None and not result.interrupted and day.get("status") == "timed_out",
        "day_status": day.get("status"),
        **memory.report(),
        # the recording: its merged files, and the largest its parts grew before the merge (per wall hour)
        "soak_rrd_mb": round(float(day.get("rrd_bytes") or 0) / MB, 2),
        "soak_rrd_mb_per_h": round(float(day.get("rrd_bytes") or 0) / MB / (wall / 3600.0), 2),
        "soak_rrd_parts_mb_peak": round(parts_peak / MB, 2),
        "restarts_total": len(result.restart_log),
        "restart_reasons": sorted({str(r.get("reason")) for r in result.restart_log}),
        "run_dir": str(result.run_dir), "samples_csv": str(memory.samples_csv), "started_utc": started_utc,
    }
    if result.error:
        report["error"] = result.error
    return report
