"""Benchmark of a week at the centre: center_week's days one after the other (tools/week.py).

Prints ONE flat JSON object:

- ``week_wall_min``: wall minutes of the 7 days (goal: < 15 in-process on 2 cores); with
  ``--days N`` < 7 it is null and ``week_wall_min_projected`` is the N days' time scaled to 7;
  ``wall_min`` and ``wall_min_per_day_<d>`` are what was measured;
- ``rss_growth_day<N>_over_day1``: each agent's RSS at the end of the last day over the end of day 1,
  the largest over the agents (goal: <= 1.1 at day 7); in-process the agents are the one process,
  which lives the whole week, so this is where a leak across days shows;
- ``dsr_growth_day<N>_over_day1``: the DSR's node, edge and tombstone counts at the end of the last
  day over day 1, the largest of the three (a zero on day 1 counts as 1); each day starts a fresh
  graph, so this measures a day's state, not an accumulation;
- ``rrd_mb_per_day`` (goal: <= 20 for center_day's crowd), ``rrd_mb_max_day``,
  ``bytes_written_mb_per_day`` (recording, people.csv, trajectory, logs);
- ``dsr_<nodes|edges|tombstones>_growth_day<N>_over_day1``: each of the three;
- ``missions``, ``missions_done``, ``days_ok``;
- ``cpu_min`` (this process's CPU time: in-process, the week's work, whatever else loads the
  machine) and ``load_avg_1min_end``.

Run: ``.venv/bin/python tools/bench/bench_week.py [--days N] [--mode in-process|launch] [--keep DIR]``
(a full week takes minutes of both cores; ``--days 2`` is the short variant; ``--no-record``
separates chronav's RSS growth from the recording's).

``--soak-hours H`` runs the real-time soak instead (tools/soak.py): the scene's first day launched
as processes at rate 1 for H hours of wall time, each agent's RSS sampled every minute, and its
slope after a warm-up (``--soak-warmup-min``, default 10) fitted by least squares.  Its JSON:
``soak_hours``, ``soak_mem_slope_mb_per_h_max`` (goal: < 1 MB/h for every agent),
``soak_mem_slope_mb_per_h_<agent>``, ``restarts_total``, and the recording's size: ``soak_rrd_mb``
and ``soak_rrd_mb_per_h`` (the merged files), ``soak_rrd_parts_mb_peak`` (the agents' parts before
the merge, sampled with the memory).  The scene defaults to center_day there.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

MB = 1024.0 * 1024.0


def _ratio(last: float, first: float) -> float:
    return round(max(last, 1.0) / max(first, 1.0), 3)


def summarize(days: list[dict[str, Any]], wall_s: float, planned: int) -> dict[str, object]:
    """The flat report of a run's day records (result.json ``days``)."""
    ran = [d for d in days if "agents" in d]
    report: dict[str, object] = {"days": planned, "days_ok": sum(1 for d in days if d["status"] == "ok"),
                                 "wall_min": round(wall_s / 60.0, 2),
                                 "week_wall_min": round(wall_s / 60.0, 2) if planned == 7 else None,
                                 "week_wall_min_projected": round(wall_s / 60.0 * 7 / max(1, planned), 2)}
    report.update({f"wall_min_per_day_{d['day']}": round(d["wall_s"] / 60.0, 2) for d in ran})
    if len(ran) >= 2:
        first, last = ran[0], ran[-1]
        shared = set(first["agents"]) & set(last["agents"])
        rss = [_ratio(last["agents"][a]["rss_mb"], first["agents"][a]["rss_mb"]) for a in shared]
        report[f"rss_growth_day{last['day']}_over_day1"] = max(rss) if rss else None
        growth = {k: _ratio(last["dsr"].get(k, 0), first["dsr"].get(k, 0)) for k in ("nodes", "edges", "tombstones")}
        report[f"dsr_growth_day{last['day']}_over_day1"] = max(growth.values())
        report.update({f"dsr_{k}_growth_day{last['day']}_over_day1": v for k, v in growth.items()})
        report.update({f"rss_mb_day{d['day']}_max_agent": max(a["rss_mb"] for a in d["agents"].values())
                       for d in ran if d["agents"]})
        report.update({f"dsr_nodes_day{d['day']}": d["dsr"].get("nodes") for d in ran})
        report.update({f"dsr_tombstones_day{d['day']}": d["dsr"].get("tombstones") for d in ran})
    if ran:
        rrd = [d["rrd_bytes"] / MB for d in ran]
        report["rrd_mb_per_day"] = round(sum(rrd) / len(rrd), 2)
        report["rrd_mb_max_day"] = round(max(rrd), 2)
        report["bytes_written_mb_per_day"] = round(sum(d["bytes_written"] for d in ran) / MB / len(ran), 2)
    report["missions"] = sum(d["missions_summary"]["total"] for d in ran)
    report["missions_done"] = sum(d["missions_summary"]["done"] for d in ran)
    return report


def run(scene: str, days: int | None, mode: str, keep: Path | None, record: bool = True) -> dict[str, object]:
    from tools.week import run_days

    os.environ.setdefault("RERUN", "on")    # the recording's size per day is one of the numbers
    workdir = keep or Path(tempfile.mkdtemp(prefix="chronav-bench-week-"))
    workdir.mkdir(parents=True, exist_ok=True)
    started, cpu_started = time.perf_counter(), time.process_time()
    result = run_days(scene, days=days, in_process=mode == "in-process", runs_dir=workdir, timeout_s=3000.0,
                      record=record)
    wall, cpu = time.perf_counter() - started, time.process_time() - cpu_started
    report: dict[str, object] = {"scene": result.scene, "mode": mode, "outcome": result.outcome, "record": record,
                                 **summarize(result.days, wall, result.planned_days),
                                 "restarts_total": len(result.restart_log),
                                 # this process's CPU: in-process, the whole week's work, whatever else loads the machine
                                 "cpu_min": round(cpu / 60.0, 2), "load_avg_1min_end": round(os.getloadavg()[0], 2)}
    if result.error:
        report["error"] = result.error
    return report


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default=None, help="default: center_week, or center_day for --soak-hours")
    parser.add_argument("--days", type=int, default=None, help="run this many days (default: the scene's, 7)")
    parser.add_argument("--mode", choices=("in-process", "launch"), default="in-process")
    parser.add_argument("--keep", type=Path, default=None, help="run in this directory and keep the recordings")
    parser.add_argument("--no-record", action="store_true",
                        help="no recording: the RSS growth without the Rerun SDK's (docs/long_runs.md)")
    parser.add_argument("--soak-hours", type=float, default=None, help="run the real-time soak for this many hours")
    parser.add_argument("--soak-warmup-min", type=float, default=10.0, help="minutes of the soak not fitted")
    parser.add_argument("--soak-sample-s", type=float, default=60.0, help="seconds between two memory samples")
    args = parser.parse_args()
    if args.soak_hours is not None:
        from tools.soak import run_soak

        print(json.dumps(run_soak(args.scene or "center_day", args.soak_hours, warmup_s=args.soak_warmup_min * 60.0,
                                  sample_every_s=args.soak_sample_s, workdir=args.keep)))
        return
    print(json.dumps(run(args.scene or "center_week", args.days, args.mode, args.keep, record=not args.no_record)))


if __name__ == "__main__":
    main()
