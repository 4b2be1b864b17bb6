"""Runs belong to the user who started them: where they go, which `--run latest` picks, who may join.

The run directories here are made with the launcher's own functions (tools/system/runs.py); the
launcher "process" of a live run is this test process (alive, with its real start time).
Commands are run through the CLI, as a user types them; they fail before any network access.
"""

from __future__ import annotations

import json
import os
import stat
import subprocess
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from tools.system import runs
from tools.cli import app
from tools.system.connection import ConnectionProblem, resolve_target

runner = CliRunner()
NOBODY = 65534


def make_run(directory: Path, name: str, *, mtime: float, finished: bool = False,
             launcher_pid: int | None = None, launcher_started: float | None = None) -> Path:
    run_dir = directory / name
    security = runs.prepare_run_security(run_dir, name, ("agenda",))
    path = runs.write_connect_file(run_dir, run_id=name, endpoint="tcp/127.0.0.1:7001", graph=name,
                                   security=security)
    if launcher_pid is not None or launcher_started is not None:
        data = json.loads(path.read_text())
        data["launcher_pid"] = launcher_pid if launcher_pid is not None else data["launcher_pid"]
        data["launcher_started"] = launcher_started if launcher_started is not None else data["launcher_started"]
        path.write_text(json.dumps(data))
    if finished:
        (run_dir / "result.json").write_text("{}")
    os.utime(path, (mtime, mtime))
    return run_dir


def dead_pid() -> int:
    child = subprocess.Popen([sys.executable, "-c", "pass"])
    child.wait()
    return child.pid


def test_runs_directory_is_the_current_directory_or_chronav_runs(tmp_path: Path,
                                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    assert runs.runs_dir({}) == tmp_path / "recordings"
    assert runs.runs_dir({"CHRONAV_RUNS": str(tmp_path / "elsewhere")}) == tmp_path / "elsewhere"
    assert runs.runs_dir({"CHRONAV_RUNS": "  "}) == tmp_path / "recordings"


def test_connect_file_is_private_and_carries_the_tool_and_reader_identities(tmp_path: Path) -> None:
    run_dir = make_run(tmp_path, "r1", mtime=1000)
    path = run_dir / runs.CONNECT_FILE
    assert stat.S_IMODE(path.stat().st_mode) == 0o600
    info = runs.read_connect_file(run_dir)
    assert (info.endpoint, info.graph, info.launcher_pid) == ("tcp/127.0.0.1:7001", "r1", os.getpid())
    assert info.identity("tool").user == "agenda_tool" and info.identity("reader").user == "reader"
    assert runs.run_is_alive(run_dir)
    os.chmod(path, 0o644)
    with pytest.raises(runs.RunError, match=r"readable by other users \(mode 644\)"):
        runs.read_connect_file(run_dir)


def test_latest_is_the_newest_live_run_of_this_user(tmp_path: Path) -> None:
    mine = make_run(tmp_path, "mine", mtime=1000)
    make_run(tmp_path, "finished", mtime=2000, finished=True)
    make_run(tmp_path, "dead_launcher", mtime=3000, launcher_pid=dead_pid())
    make_run(tmp_path, "recycled_pid", mtime=4000, launcher_started=12345.0)   # same pid, another process
    assert runs.latest_live_run(tmp_path) == mine
    assert not runs.run_is_alive(tmp_path / "recycled_pid")
    with pytest.raises(runs.RunError, match="is no longer running"):
        runs.open_run("dead_launcher", tmp_path)
    with pytest.raises(runs.RunError, match="has finished|no longer running"):
        runs.open_run("finished", tmp_path)


@pytest.mark.skipif(os.geteuid() != 0, reason="making a file of another user needs root")
def test_other_users_runs_are_never_picked_nor_joined(tmp_path: Path) -> None:
    directory = tmp_path / "recordings"
    theirs = make_run(directory, "theirs", mtime=5000)
    os.chown(theirs / runs.CONNECT_FILE, NOBODY, NOBODY)
    env = {"CHRONAV_RUNS": str(directory)}

    latest = runner.invoke(app, ["agenda", "list", "--run", "latest"], env=env)
    assert latest.exit_code == 2
    assert "no live run of yours under" in latest.stderr and "1 of other users skipped" in latest.stderr
    assert "chronav launch" in latest.stderr

    for args in (["agenda", "cancel", "x", "--run", str(theirs)], ["dsr", "dump", "--run", "theirs"]):
        result = runner.invoke(app, args, env=env)
        assert result.exit_code == 2, result.output
        assert f"run {theirs} belongs to nobody, not to you" in result.stderr

    mine = make_run(directory, "mine", mtime=1000)    # older, but the only one of this user
    assert runs.latest_live_run(directory) == mine


def test_target_precedence(tmp_path: Path) -> None:
    make_run(tmp_path, "run1", mtime=1000)
    env = {"CHRONAV_ZENOH_CONNECT": "tcp/127.0.0.1:7002", "CHRONAV_GRAPH": "envgraph"}
    nothing = tmp_path / "no_runs"
    default = resolve_target(None, None, None, role="reader", environ={}, runs=nothing)
    assert default.connect == ("tcp/127.0.0.1:7447",) and default.graph == "chronav" and default.identity is None
    assert f"no live run of yours under {nothing}" in default.origin
    assert "CHRONAV_ZENOH_CONNECT is not set" in default.origin
    # with no option and no environment: the newest live run (what `chronav launch` just started)
    newest = resolve_target(None, None, None, role="tool", environ={}, runs=tmp_path)
    assert (newest.connect, newest.graph, newest.identity.user) == (("tcp/127.0.0.1:7001",), "run1", "agenda_tool")
    assert newest.origin == "run run1, your newest live run"
    make_run(tmp_path, "ended", mtime=2000, finished=True)       # newer, but over: not picked
    assert resolve_target(None, None, None, role="reader", environ={}, runs=tmp_path).graph == "run1"
    from_env = resolve_target(None, None, None, role="reader", environ=env, runs=tmp_path)
    assert (from_env.connect, from_env.graph) == (("tcp/127.0.0.1:7002",), "envgraph")
    only_graph = resolve_target(None, "g4", None, role="reader", environ={}, runs=tmp_path)
    assert (only_graph.connect, only_graph.graph) == (("tcp/127.0.0.1:7447",), "g4")
    from_run = resolve_target(None, None, "latest", role="tool", environ=env, runs=tmp_path)
    assert (from_run.connect, from_run.graph, from_run.identity.user) == (("tcp/127.0.0.1:7001",), "run1",
                                                                          "agenda_tool")
    explicit = resolve_target(["tcp/127.0.0.1:7003"], "g3", "latest", role="reader", environ=env, runs=tmp_path)
    assert (explicit.connect, explicit.graph, explicit.identity.user) == (("tcp/127.0.0.1:7003",), "g3", "reader")
    with pytest.raises(ConnectionProblem, match=r"^--connect 'garbage' is not an endpoint; expected "
                                                r"PROTOCOL/HOST:PORT"):
        resolve_target(["garbage"], None, None, role="reader", environ=env)
    with pytest.raises(ConnectionProblem, match=r"--graph 'a/b'"):
        resolve_target(None, "a/b", None, role="reader", environ=env)
