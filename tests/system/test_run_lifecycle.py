"""The life of a run, through `chronav launch` as a user types it (issues 11 and 12).

- bad --rate / --timeout are refused at once, naming the option, before anything starts;
- a run goes to ./recordings of the current directory (never into the source tree);
- however a run ends (a mission the agents fail before the robot moves, Ctrl-C in the first
  seconds), the missions table is printed, the agents' recordings are merged, result.json is
  written, and no traceback appears; after Ctrl-C the run says it was interrupted;
- a live run: its connect file is the owner's only, `--run latest` tools join with its
  credentials, a session without them is refused; an agent that stops making progress (frozen
  with SIGSTOP: alive, but its heartbeat stops) is detected, killed and restarted, and logged.
"""

from __future__ import annotations

import contextlib
import json
import os
import signal
import stat
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

from tests.support import REPO_ROOT, ProcessGroup, wait_until
from tools.cli import app

pytestmark = pytest.mark.slow

LIVE_SCENE = REPO_ROOT / "tests" / "data" / "agenda_live.yaml"
UNREACHABLE = REPO_ROOT / "tests" / "data" / "hostile" / "unreachable_goal.yaml"


def chronav(args: list[str], runs: Path, timeout_s: float = 60) -> subprocess.CompletedProcess[str]:
    """A short-lived `chronav` command (tools against a live run)."""
    return subprocess.run([sys.executable, "-m", "tools.cli", *args], cwd=REPO_ROOT, capture_output=True, text=True,
                          timeout=timeout_s, env={**os.environ, "CHRONAV_RUNS": str(runs), "RERUN": "off"})


def the_run(runs: Path) -> Path:
    (connect,) = runs.glob("*/connect.json")
    return connect.parent


def finished(proc: subprocess.Popen[bytes], log: Path, timeout_s: float) -> str:
    try:
        proc.wait(timeout=timeout_s)
    except subprocess.TimeoutExpired:
        pytest.fail(f"the launcher did not finish; log:\n{log.read_text()[-3000:]}")
    return log.read_text()


@pytest.mark.parametrize(("args", "option"), [
    (["--rate", "nan"], "--rate"), (["--rate", "inf"], "--rate"), (["--rate", "-1"], "--rate"),
    (["--rate", "0"], "--rate"), (["--timeout", "0"], "--timeout"), (["--timeout", "-5"], "--timeout"),
    (["--hang-timeout", "0"], "--hang-timeout"),
])
def test_bad_rate_and_timeout_are_refused_at_once(args: list[str], option: str, tmp_path: Path) -> None:
    result = CliRunner().invoke(app, ["launch", str(LIVE_SCENE), *args], env={"CHRONAV_RUNS": str(tmp_path)})
    assert result.exit_code == 2
    text = " ".join(result.output.replace("│", " ").split())     # typer draws the message in a box
    assert f"Invalid value for '{option}'" in text and "greater than 0" in text
    assert not any(tmp_path.iterdir()), "nothing may start"


def test_a_runs_directory_that_cannot_be_created_is_one_line() -> None:
    result = CliRunner().invoke(app, ["launch", str(LIVE_SCENE)], env={"CHRONAV_RUNS": "/proc/chronav-runs"})
    assert result.exit_code == 2
    assert result.stderr.startswith("error: cannot create the run directory /proc/chronav-runs/agenda_live-")
    assert "set CHRONAV_RUNS" in result.stderr and "Traceback" not in result.output


def test_failed_mission_before_the_robot_moves_still_gives_table_recording_and_result(
        procs: ProcessGroup, tmp_path: Path) -> None:
    log = tmp_path / "launch.log"
    before = set((REPO_ROOT / "recordings").glob("*")) if (REPO_ROOT / "recordings").exists() else set()
    proc = procs.spawn(["-m", "tools.cli", "launch", str(UNREACHABLE), "--timeout", "120"],
                       env={"RERUN": "on", "CHRONAV_RUNS": ""}, log_path=log, cwd=tmp_path)
    text = finished(proc, log, 150)
    assert proc.returncode == 1, text
    assert "Traceback" not in text
    assert "Missions of unreachable_goal" in text and "m0905" in text and "failed" in text
    assert "FAILED: 0/1 mission done" in text
    run_dir = the_run(tmp_path / "recordings")        # ./recordings of the current directory
    result = json.loads((run_dir / "result.json").read_text())
    assert result["missions"]["m0905"]["state"] == "failed" and not result["ok"]
    assert result["rrd"] == str(tmp_path / "recordings" / f"{run_dir.name}.rrd") and Path(result["rrd"]).stat().st_size
    after = set((REPO_ROOT / "recordings").glob("*")) if (REPO_ROOT / "recordings").exists() else set()
    assert after == before, "nothing written into the source tree"


def test_ctrl_c_in_the_first_seconds_says_interrupted_and_still_merges(procs: ProcessGroup, tmp_path: Path) -> None:
    runs, log = tmp_path / "recordings", tmp_path / "launch.log"
    proc = procs.spawn(["-m", "tools.cli", "launch", str(LIVE_SCENE)], env={"RERUN": "on", "CHRONAV_RUNS": str(runs)},
                       log_path=log)
    wait_until(lambda: any(runs.glob("*/connect.json")) or proc.poll() is not None, 60, message="the run started")
    os.killpg(proc.pid, signal.SIGINT)
    text = finished(proc, log, 60)
    assert proc.returncode == 130, text
    assert "Traceback" not in text
    assert "INTERRUPTED (Ctrl-C or SIGTERM)" in text and "0/1 mission done" in text
    assert "Missions of agenda_live" in text and "m0905" in text
    run_dir = the_run(runs)
    result = json.loads((run_dir / "result.json").read_text())
    assert result["interrupted"] and not result["ok"] and result["missions"]["m0905"]["state"] != "done"
    assert result["rrd"] and Path(result["rrd"]).exists()


def _heartbeats(runs: Path) -> dict[str, dict[str, Any]]:
    """heartbeat/<agent> attributes, as `chronav dsr dump --run latest --json` shows them ({} while
    no agent has joined yet: the dump then says so and exits 1)."""
    result = chronav(["dsr", "dump", "--run", "latest", "--json"], runs)
    if result.returncode != 0:
        assert "no agent has joined its graph yet" in result.stderr, result.stderr
        return {}
    return {n["name"]: n["attrs"] for n in json.loads(result.stdout)["nodes"] if n["type"] == "heartbeat"}


def test_live_run_is_its_owners_and_a_frozen_agent_is_restarted(procs: ProcessGroup, tmp_path: Path) -> None:
    runs, log = tmp_path / "recordings", tmp_path / "launch.log"
    launcher = procs.spawn(["-m", "tools.cli", "launch", str(LIVE_SCENE), "--rate", "0.3", "--hang-timeout", "3",
                            "--timeout", "150", "--json"], env={"CHRONAV_RUNS": str(runs)}, log_path=log)
    wait_until(lambda: any(runs.glob("*/connect.json")) or launcher.poll() is not None, 60, message="the run")
    run_dir = the_run(runs)
    connect = run_dir / "connect.json"
    assert stat.S_IMODE(connect.stat().st_mode) == 0o600
    info = json.loads(connect.read_text())

    # The owner's tools join with the run's credentials; a session without them is refused.
    wait_until(lambda: "heartbeat/object_recognition" in _heartbeats(runs), 90, interval=0.5,
               message="object_recognition's first heartbeat")
    listed = chronav(["agenda", "list", "--run", "latest", "--json"], runs)
    assert listed.returncode == 0 and json.loads(listed.stdout)["graph"] == info["graph"], listed.stderr
    bare = chronav(["dsr", "dump", "--connect", info["endpoint"], "--graph", info["graph"]], runs)
    assert bare.returncode == 1 and "requires credentials" in bare.stderr, bare.stderr

    # Freeze an agent: its process is alive, its heartbeat stops; the launcher restarts it.
    pids = json.loads((run_dir / "pids.json").read_text())
    frozen = pids["object_recognition"]
    os.kill(frozen, signal.SIGSTOP)
    try:
        wait_until(lambda: json.loads((run_dir / "pids.json").read_text())["object_recognition"] != frozen, 30,
                   interval=0.2, message="object_recognition restarted")
    finally:        # never leave a stopped process behind, whatever happened
        with contextlib.suppress(ProcessLookupError):
            os.killpg(frozen, signal.SIGKILL)
    wait_until(lambda: _heartbeats(runs).get("heartbeat/object_recognition", {}).get("pid") not in (None, frozen),
               90, interval=0.5, message="the restarted agent's heartbeat")

    os.killpg(launcher.pid, signal.SIGINT)
    text = finished(launcher, log, 60)
    summary = json.loads(next(line for line in reversed(text.splitlines()) if line.startswith("{")))
    assert launcher.returncode == 130 and summary["outcome"] == "interrupted", text[-2000:]
    assert summary["restarts"]["object_recognition"] == 1
    (event,) = [e for e in summary["events"] if e.startswith("object_recognition")]
    assert "made no progress for" in event and "limit 3 s" in event and "restart 1/3" in event
    assert json.loads((run_dir / "result.json").read_text())["events"] == summary["events"]
    # every restart with its reason (issue 41: a long life counts them per rolling hour)
    assert [(r["agent"], "made no progress for" in r["reason"]) for r in summary["restart_log"]] == [
        ("object_recognition", True)]
    assert json.loads((run_dir / "result.json").read_text())["restart_log"] == summary["restart_log"]
    assert "Traceback" not in text
