"""Benchmark of `chronav evaluate`: how many full runs a sweep completes per minute on this machine.

Prints ONE flat JSON object:
- ``evaluate_runs_per_min``: launched runs per wall minute of the sweep (runs only: the table,
  figures and report after it are ``report_s``), the tiny scene (tests/data/eval_tiny.yaml: one
  room, one mission) x 2 planners x ``--seeds`` seeds with ``--jobs`` runs at once (default 2,
  the 2-core target);
- ``single_launch_s``: one `chronav launch` of the same scene measured in the same run, the
  reference: ``evaluate_runs_per_min`` x ``single_launch_s`` / 60 is the parallel gain (1.0: none);
- ``evaluate_total_s``: the whole command (interpreter start, sweep, table, figures, report).
Benchmarks on a shared machine are noisy: compare only figures of the same run.

Run: ``.venv/bin/python tools/bench_evaluate.py [--seeds 2] [--jobs 2]``
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "tests" / "data" / "eval_tiny.yaml"


def _chronav(args: list[str], cwd: Path) -> tuple[float, str]:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(p for p in (str(ROOT), os.environ.get("PYTHONPATH")) if p),
           "CHRONAV_RUNS": str(cwd / "recordings")}
    started = time.monotonic()
    done = subprocess.run([sys.executable, "-m", "tools.cli", *args], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=3600, check=False)
    if done.returncode != 0:
        raise SystemExit(f"chronav {' '.join(args)} failed ({done.returncode}):\n{done.stderr[-2000:]}")
    return time.monotonic() - started, done.stdout


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=2)
    parser.add_argument("--jobs", type=int, default=2)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench_evaluate_") as tmp:
        work = Path(tmp)
        single_s, _ = _chronav(["launch", str(SCENE), "--json"], work)
        total_s, out = _chronav(["evaluate", str(SCENE), "--planners", "social,baseline", "--seeds", str(args.seeds),
                                 "--jobs", str(args.jobs), "--out", str(work / "study"), "--json"], work)
    result = json.loads(out)
    print(json.dumps({
        "evaluate_runs_per_min": result["runs_per_min"],
        "runs": result["launched"],
        "jobs": args.jobs,
        "cores": os.cpu_count(),
        "sweep_s": result["sweep_wall_s"],
        "report_s": round(total_s - result["sweep_wall_s"], 2),
        "evaluate_total_s": round(total_s, 2),
        "single_launch_s": round(single_s, 2),
        "load_avg_1min": round(os.getloadavg()[0], 2),
    }))


if __name__ == "__main__":
    main()
