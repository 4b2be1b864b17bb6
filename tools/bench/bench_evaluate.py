"""Benchmark of `chronav evaluate`: runs per minute in each mode, a 1,000-run study, center_day.

Prints ONE flat JSON object (every figure measured in this same run: the machine is shared, so
compare figures of one run only; ``load_avg_1min_*`` says how busy it was):

- ``evaluate_runs_per_min_in_process`` (also ``evaluate_runs_per_min``, the goal key: >= 60 on 2
  cores) and ``evaluate_runs_per_min_launch``: runs per wall minute of the sweep (the runs only;
  the table, figures and report after them are ``report_s_*``) on the tiny scene
  (tests/data/eval_tiny.yaml) x 5 planners x seeds, ``--jobs`` at once, every run recorded as
  the report links it (``..._in_process_no_record``: with ``--no-record``); ``in_process_over_launch``
  their ratio; ``identical_metrics_tiny``: every metric of every run equal in both modes;
- ``study_1000_runs_min_extrapolated`` (goal < 30): a 1,000-run study (5 planners x 20 seeds x 10
  variants of the tiny scene) extrapolated from a sweep of the 10 variants x 5 planners x
  ``--study-seeds`` seeds in-process: that sweep's wall time per run x 1,000, plus its report time
  (``study_sample_runs``, ``study_sample_sweep_s``, ``study_report_s``);
- ``center_day_morning_launch_s`` (one launch, its own wall time), ``center_day_morning_in_process_s``
  (the second of two seeds run in-process by one worker: what a run of a study costs; the first,
  which pays the worker's imports and kernel loading, is ``..._first_run_s``),
  ``center_day_speedup`` (goal >= 3) and ``..._first_run``, ``identical_metrics_center_day``
  (seed 1 in both modes).  ``--no-center-day`` skips this part (minutes), ``--no-tiny`` the rest.

Run: ``.venv/bin/python tools/bench/bench_evaluate.py [--jobs 2] [--seeds 8] [--launch-seeds 1]``
"""

from __future__ import annotations

import argparse
import copy
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import yaml

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "tests" / "data" / "eval_tiny.yaml"

def _chronav_planners() -> str:
    """chronav's own planners (the registry's entries from the chronav package): the benchmark
    measures those, whatever else is installed."""
    from agents.lib.registry import extensions

    return ",".join(name for name, ext in extensions("planner").items() if ext.package == "chronav")


PLANNERS = _chronav_planners()
#: columns that say where and how fast a run ran, not what it computed
WHERE = {"run_dir", "rrd", "host", "run_wall_s", "trajectory_csv"}


def _chronav(args: list[str], cwd: Path) -> tuple[float, dict[str, Any]]:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(p for p in (str(ROOT), os.environ.get("PYTHONPATH")) if p),
           "CHRONAV_RUNS": str(cwd / "recordings")}
    started = time.monotonic()
    done = subprocess.run([sys.executable, "-m", "tools.cli", *args, "--json"], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=7200, check=False)
    if done.returncode not in (0, 1):
        raise SystemExit(f"chronav {' '.join(args)} failed ({done.returncode}):\n{done.stderr[-2000:]}")
    return time.monotonic() - started, json.loads(done.stdout.strip().splitlines()[-1])


def _evaluate(scenes: list[Path], out: Path, mode: str, seeds: int, jobs: int, planners: str = PLANNERS,
              *extra: str) -> dict[str, Any]:
    total_s, result = _chronav(["evaluate", *map(str, scenes), "--planners", planners, "--seeds", str(seeds),
                                "--jobs", str(jobs), "--mode", mode, "--out", str(out), *extra], out.parent)
    result["total_s"] = total_s
    return result


def _table(result: dict[str, Any]) -> dict[tuple[Any, ...], dict[str, Any]]:
    from tools.evaluate.table import read_table

    return {(r["scene"], r["planner"], r["seed"], r["mission"]): r for r in read_table(Path(result["table"]["parquet"]))}


def _identical(a: dict[str, Any], b: dict[str, Any]) -> bool:
    """Every metric of every mission the same in both sweeps (on the runs ``a`` has, all of which
    ``b`` must have)."""
    rows_a, rows_b = _table(a), _table(b)
    if not rows_a or not rows_a.keys() <= rows_b.keys():
        return False
    for key, row in rows_a.items():
        for column in set(row) - WHERE:
            x, y = row[column], rows_b[key].get(column)
            if not (x == y or (isinstance(x, float) and isinstance(y, float) and math.isnan(x) and math.isnan(y))):
                return False
    return True


def _run_walls_s(result: dict[str, Any]) -> list[float]:
    """The wall time of each of the sweep's runs in the order they ended, from its ledger."""
    lines = (Path(result["out"]) / "runs.jsonl").read_text().splitlines()
    return [float(json.loads(line)["wall_s"]) for line in lines]


def tiny_variants(directory: Path, count: int = 10) -> list[Path]:
    """``count`` variants of the tiny scene: the resident stands elsewhere in front of the TV and the
    mission's goal moves, so the planners' paths differ from variant to variant."""
    data = yaml.safe_load(SCENE.read_text())
    paths = []
    for k in range(count):
        variant = copy.deepcopy(data)
        variant["name"] = f"eval_tiny_v{k}"
        variant["people"][0]["pose"] = [2.4 + 0.15 * k, 1.3 + 0.05 * (k % 4), -1.5708]
        variant["missions"][0]["goal"]["pose"] = [5.2, 1.0 + 0.2 * (k % 5), 0]
        path = directory / f"eval_tiny_v{k}.yaml"
        path.write_text(yaml.safe_dump(variant, sort_keys=False))
        paths.append(path)
    return paths


def center_day_morning(directory: Path, end: str = "11:00") -> Path:
    """center_day as shipped up to ``end`` (the morning tests/system/test_center_day.py runs)."""
    from agents.world.scene_world import load_world
    from scenes.clock import parse_clock

    world = load_world("center_day")
    data = yaml.safe_load(world.path.read_text())
    end_s = parse_clock(end)
    data["clock"]["end"] = end
    data["missions"] = [m for m in data["missions"] if parse_clock(m["time"]) < end_s]
    data["agenda_changes"] = [c for c in data.get("agenda_changes", []) if parse_clock(c["at"]) < end_s]
    if data.get("agenda_file"):
        data["agenda_file"] = str((world.path.parent / data["agenda_file"]).resolve())
    path = directory / "center_day_morning.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def main() -> None:
    sys.path.insert(0, str(ROOT))
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--seeds", type=int, default=8, help="seeds of the in-process tiny sweep (x 5 planners)")
    parser.add_argument("--launch-seeds", type=int, default=1, help="seeds of the launch tiny sweep (x 5 planners)")
    parser.add_argument("--study-seeds", type=int, default=2, help="seeds of the 10-variant sample of the study")
    parser.add_argument("--no-center-day", action="store_true")
    parser.add_argument("--no-tiny", action="store_true", help="only the center_day part")
    args = parser.parse_args()
    out: dict[str, Any] = {"cores": os.cpu_count(), "jobs": args.jobs, "load_avg_1min_start": round(os.getloadavg()[0], 2)}
    with tempfile.TemporaryDirectory(prefix="bench_evaluate_") as tmp:
        work = Path(tmp)
        if not args.no_tiny:
            _tiny(args, work, out)
        if not args.no_center_day:
            _center_day(work, out)
    out["load_avg_1min_end"] = round(os.getloadavg()[0], 2)
    print(json.dumps(out))


def _tiny(args: argparse.Namespace, work: Path, out: dict[str, Any]) -> None:
    """Both modes on the tiny scene, then the sample of the 1,000-run study."""
    inproc = _evaluate([SCENE], work / "tiny_in_process", "in-process", args.seeds, args.jobs)
    bare = _evaluate([SCENE], work / "tiny_no_record", "in-process", args.seeds, args.jobs, PLANNERS,
                     "--no-record")
    launch = _evaluate([SCENE], work / "tiny_launch", "launch", args.launch_seeds, args.jobs)
    out.update({
        "evaluate_runs_per_min": inproc["runs_per_min"],
        "evaluate_runs_per_min_in_process": inproc["runs_per_min"],
        "evaluate_runs_per_min_in_process_no_record": bare["runs_per_min"],
        "evaluate_runs_per_min_launch": launch["runs_per_min"],
        "in_process_over_launch": round(inproc["runs_per_min"] / launch["runs_per_min"], 2),
        "runs_in_process": inproc["launched"], "runs_launch": launch["launched"],
        "sweep_s_in_process": inproc["sweep_wall_s"], "sweep_s_launch": launch["sweep_wall_s"],
        "report_s_in_process": round(inproc["total_s"] - inproc["sweep_wall_s"], 2),
        "report_s_launch": round(launch["total_s"] - launch["sweep_wall_s"], 2),
        "identical_metrics_tiny": _identical(launch, inproc),
    })
    variants = tiny_variants(work)
    study = _evaluate(variants, work / "study", "in-process", args.study_seeds, args.jobs)
    per_run_s = study["sweep_wall_s"] / study["launched"]
    report_s = study["total_s"] - study["sweep_wall_s"]
    out.update({
        "study_sample_runs": study["launched"], "study_sample_ok": study["ok"],
        "study_sample_sweep_s": study["sweep_wall_s"], "study_report_s": round(report_s, 2),
        "study_1000_runs_min_extrapolated": round((1000 * per_run_s + report_s) / 60.0, 2),
        "load_avg_1min_after_tiny": round(os.getloadavg()[0], 2),
    })


def _center_day(work: Path, out: dict[str, Any]) -> None:
    """One launch of the morning, and two in-process runs in one worker: the first pays the worker's
    imports and kernel loading, the second is what each run of a study costs."""
    morning = center_day_morning(work)
    day_launch = _evaluate([morning], work / "day_launch", "launch", 1, 1, "social")
    day_inproc = _evaluate([morning], work / "day_in_process", "in-process", 2, 1, "social")
    launch_s = _run_walls_s(day_launch)[0]
    cold_s, warm_s = _run_walls_s(day_inproc)
    out.update({
        "center_day_morning_launch_s": round(launch_s, 2),
        "center_day_morning_in_process_s": round(warm_s, 2),
        "center_day_morning_in_process_first_run_s": round(cold_s, 2),
        "center_day_speedup": round(launch_s / warm_s, 2),
        "center_day_speedup_first_run": round(launch_s / cold_s, 2),
        "center_day_missions_ok": [day_launch["ok"], day_inproc["ok"]],
        "identical_metrics_center_day": _identical(day_launch, day_inproc),
    })


if __name__ == "__main__":
    main()
