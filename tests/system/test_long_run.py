"""Issue 41 (multi-process): a run of two days launched as processes, one day after the other.

Each day is a launch of its own (router, six agents, supervision) on that day's scene; the run's
result.json holds each agent process's RSS and CPU time per day, the DSR's counts, the bytes
written, and the index one recording per day; each day has its own logs."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.system.launch_helpers import launch_json
from tools.launch import agent_names

pytestmark = pytest.mark.slow
WEEK = Path(__file__).resolve().parents[1] / "data" / "week_tiny.yaml"


def test_two_days_launched_as_processes_rotate_and_account_per_day(tmp_path: Path) -> None:
    result = launch_json(str(WEEK), tmp_path / "launch.log", timeout_s=300, extra=["--keep-days", "5"])
    assert result["returncode"] == 0 and result["ok"], result
    assert [d["status"] for d in result["days"]] == ["ok", "ok"] and result["restarts_total"] == 0
    run_dir = Path(result["run_dir"])
    index = json.loads((run_dir / "index.json").read_text())
    for day, entry in zip(result["days"], index["entries"], strict=True):
        assert set(agent_names()) <= set(day["agents"]), day["agents"]
        assert all(a["rss_mb"] > 0 and a["cpu_s"] > 0 for a in day["agents"].values())
        assert day["dsr"]["nodes"] > 0 and day["bytes_written"] > day["rrd_bytes"] > 0
        assert (run_dir / entry["rrd"]).is_file() and entry["rrd"] == day["rrd"]
        logs = run_dir / entry["run_dir"] / "logs"
        assert {f"{name}.log" for name in agent_names()} <= {p.name for p in logs.iterdir()}
        assert json.loads((run_dir / entry["run_dir"] / "result.json").read_text())["restart_log"] == []


def test_short_real_time_soak_samples_every_agent_and_fits_its_memory_slope(tmp_path: Path) -> None:
    """The 2-hour soak's short variant (`tools/bench/bench_week.py --soak-hours`, tools/soak.py): ~25 s of
    week_tiny's first day as processes at rate 1; every agent sampled, a slope each, the run ended
    by the soak's own timeout and every process stopped.  (25 s: after the 6 s warm-up, a sample every
    2 s leaves each agent at least 3 samples, the fewest a slope needs, even when the launcher's first
    status comes 10 s into the run; the 40 s this ran before measured the same things 15 s later.)"""
    import psutil

    from tests.support import ProcessGroup

    group = ProcessGroup()
    log = tmp_path / "soak.log"
    try:
        proc = group.spawn(["tools/bench/bench_week.py", "--scene", str(WEEK), "--soak-hours", "0.007",
                            "--soak-warmup-min", "0.1", "--soak-sample-s", "2", "--keep", str(tmp_path / "soak")],
                           env={"RERUN": "on", "CHRONAV_LOG_ROTATE_S": "5"},   # recording, as a deployment does;
                           log_path=log)                          # logs cut every 5 s instead of hourly
        proc.wait(timeout=240)
    finally:
        group.close()
    line = next((ln for ln in reversed(log.read_text().splitlines()) if ln.startswith("{")), None)
    assert proc.returncode == 0 and line is not None, log.read_text()[-3000:]
    report = json.loads(line)
    assert report["soak_ok"] and report["day_status"] == "timed_out" and report["restarts_total"] == 0, report
    assert report["soak_hours"] >= 0.007
    assert 0 < report["soak_rrd_mb"] and 0 < report["soak_rrd_parts_mb_peak"], report   # what it wrote, and held
    for name in agent_names():
        assert isinstance(report[f"soak_mem_slope_mb_per_h_{name}"], float), (name, report)
        assert isinstance(report[f"soak_private_slope_mb_per_h_{name}"], float), (name, report)
        assert 0 < report[f"soak_private_mb_last_{name}"] < report[f"soak_rss_mb_last_{name}"]
        assert report[f"soak_processes_{name}"] == 1
    assert report["soak_mem_slope_mb_per_h_max"] == max(
        v for k, v in report.items() if k.startswith("soak_mem_slope_mb_per_h_") and k[24:] in (*agent_names(), "router"))
    # A real-time run's processes cut their own logs (dsr/log_rotation.py): earlier parts beside the
    # current <name>.log, each continuing the one before, the agent's first line in the first part.
    logs = next(Path(report["run_dir"]).rglob("logs"))
    for name in (*agent_names(), "router"):
        parts = sorted(logs.glob(f"{name}-*.log"))
        assert parts and (logs / f"{name}.log").is_file(), sorted(p.name for p in logs.iterdir())
        assert (logs / f"{name}.log").read_text().splitlines()[0].endswith(f"log continued from {parts[-1].name}")
        first_lines = parts[0].read_text()
        assert ("joined graph" in first_lines) if name != "router" else ("dsr.router ready" in first_lines), name
    pids = json.loads(next(Path(report["run_dir"]).rglob("pids.json")).read_text())
    assert set(agent_names()) <= set(pids) and not any(psutil.pid_exists(p) for p in pids.values() if p), pids
