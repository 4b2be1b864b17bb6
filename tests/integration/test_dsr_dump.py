"""`chronav dsr dump`: one-shot JSON and table, and --follow in a separate process."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from dsr import ZenohSettings, join
from tests.integration.dsr_support import read_status, spawn_worker, start_router
from tests.support import wait_until
from tools.cli import app

pytestmark = pytest.mark.slow


@pytest.fixture
def world(procs, tmp_path):
    endpoint, _ = start_router(procs, tmp_path)
    _, status = spawn_worker(procs, endpoint, tmp_path, "a", "--world", "5")
    wait_until(lambda: (read_status(status) or {}).get("done", False), 30, message="world")
    return endpoint


def test_dump_json_and_table(world):
    runner = CliRunner()
    result = runner.invoke(app, ["dsr", "dump", "--json", "--connect", world])
    assert result.exit_code == 0, result.output
    document = json.loads(result.stdout)
    assert document["graph"] == "chronav" and len(document["nodes"]) == 5
    assert {n["name"] for n in document["nodes"]} == {f"a-w{i}" for i in range(5)}
    result = runner.invoke(app, ["dsr", "dump", "--connect", world])
    assert result.exit_code == 0 and "a-w3" in result.stdout and "5 nodes" in result.stdout


def test_dump_piped_at_80_columns_is_one_line_per_node_grouped_by_type(world):
    """Issue 39: piped, the dump is grouped by node type, one line per node, nothing folded."""
    result = CliRunner().invoke(app, ["dsr", "dump", "--connect", world], env={"COLUMNS": "80"})
    assert result.exit_code == 0, result.output
    lines = result.stdout.splitlines()
    assert lines[0].startswith("DSR graph 'chronav': 5 nodes, 0 edges")
    assert sorted(line.split()[0] for line in lines if line.startswith("  ")) == [f"a-w{i}" for i in range(5)]
    assert len(lines) <= 1 + 5 + 5 and all(len(line) <= 80 for line in lines), lines
    every = CliRunner().invoke(app, ["dsr", "dump", "--all", "--connect", world], env={"COLUMNS": "80"})
    assert every.exit_code == 0 and "a-w3 [" in every.stdout and "i=3" in every.stdout


def test_dump_reports_unreachable_router_on_stderr():
    result = CliRunner().invoke(app, ["dsr", "dump", "--json", "--connect", "tcp/127.0.0.1:1"])
    assert result.exit_code == 1 and "nothing listens at tcp/127.0.0.1:1" in result.stderr
    assert result.stdout == ""
    # In a user's words: no Rust source path, and the command that starts a system.
    assert ".rs:" not in result.stderr and "python -m dsr.router" not in result.stderr
    assert "chronav launch" in result.stderr and "--run latest" in result.stderr


@pytest.mark.parametrize(("args", "message"), [
    (["--connect", "garbage"], "--connect 'garbage' is not an endpoint; expected PROTOCOL/HOST:PORT, "
                               "e.g. tcp/127.0.0.1:7447"),
    (["--connect", "tcp/localhost"], "--connect 'tcp/localhost': expected tcp/HOST:PORT"),
    (["--graph", "a/b"], "--graph 'a/b': graph name 'a/b' must match"),
    (["--timeout", "0"], "--timeout 0: give a number of seconds greater than 0"),
    (["--timeout", "nan"], "--timeout nan: give a number of seconds greater than 0"),
])
def test_bad_options_get_one_line_naming_the_option(args, message):
    result = CliRunner().invoke(app, ["dsr", "dump", *args])
    assert result.exit_code == 2
    assert result.stderr.startswith(f"chronav dsr dump: {message}")
    assert len(result.stderr.strip().splitlines()) == 1, result.stderr


def test_wrong_or_missing_graph_is_an_error_naming_the_graphs_there(world):
    for args, asked in ((["--graph", "no_such_graph"], "no_such_graph"), ([], "chronav")):
        env = {"CHRONAV_GRAPH": "somewhere_else"} if not args else {}
        result = CliRunner().invoke(app, ["dsr", "dump", "--connect", world, *args], env=env)
        graph = "somewhere_else" if not args else asked
        assert result.exit_code == 1, result.output
        assert f"graph {graph!r}" in result.stderr and "nobody is there" in result.stderr
        assert "graphs with members there: chronav (use --graph NAME)" in result.stderr
        assert "0 nodes" not in result.stdout


def test_timeout_bounds_the_connection_to_a_listener_that_is_not_zenoh(tmp_path):
    """Zenoh's own handshake timeout is 10 s; --timeout 0.5 must end the attempt long before."""
    import socket
    import subprocess
    import sys
    import threading

    from tests.support import REPO_ROOT

    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(8)
    held: list[socket.socket] = []
    threading.Thread(target=lambda: [held.append(server.accept()[0]) for _ in range(8)], daemon=True).start()
    endpoint = f"tcp/127.0.0.1:{server.getsockname()[1]}"
    try:
        result = subprocess.run([sys.executable, "-m", "tools.cli", "dsr", "dump", "--connect", endpoint,
                                 "--timeout", "0.5"], cwd=REPO_ROOT, capture_output=True, text=True, timeout=8)
    finally:
        server.close()
        for conn in held:
            conn.close()
    assert result.returncode == 1, result.stderr
    assert f"something listens at {endpoint} but refused a chronav session: it is not a Zenoh router" \
        in result.stderr


def test_stats_without_a_running_graph_says_so_on_stderr(world):
    result = CliRunner().invoke(app, ["dsr", "stats", "--json", "--connect", "tcp/127.0.0.1:1"])
    assert result.exit_code == 1 and "cannot reach a chronav system" in result.stderr
    assert result.stdout == ""
    result = CliRunner().invoke(app, ["dsr", "stats", "--connect", world, "--graph", "nope",
                                      "--timeout", "1"])
    assert result.exit_code == 1 and "no member of graph 'nope'" in result.stderr
    result = CliRunner().invoke(app, ["dsr", "stats", "--connect", world])
    assert result.exit_code == 0 and "1 member\n" in result.stdout


def test_dump_follow_prints_changes(world, procs, tmp_path):
    out = tmp_path / "follow.jsonl"
    proc = procs.spawn(["-m", "tools.cli", "dsr", "dump", "--follow", "--json", "--connect",
                        world, "--duration", "20"], log_path=out)

    def lines() -> list[dict]:
        return [json.loads(line) for line in out.read_text().splitlines() if line.startswith("{")]
    wait_until(lambda: out.exists() and len(lines()) >= 1, 20, message="initial dump")
    assert len(lines()[0]["nodes"]) == 5
    # One change at a time: the dump syncs with a member that appears (dsr/transport.py), and a
    # state merge that already holds the update reports only the final node (a state-based CRDT
    # may skip intermediate states), so the update is written once the insert has been seen.
    with join("writer", settings=ZenohSettings(connect=[world])) as graph:
        node = graph.insert_node("person", "zoe", {"age": 80})
        _wait_for_signal(lines, "node_added", out, proc)
        graph.update_node(node.id, {"age": 81})
        _wait_for_signal(lines, "node_updated", out, proc)
    events = lines()[1:]
    assert events[0] == {"signal": "node_added", "node": {"id": node.id, "type": "person",
                                                          "name": "zoe", "attrs": {"age": 80}}}
    assert events[1]["changed"] == ["age"] and events[1]["node"]["attrs"]["age"] == 81
    assert proc.poll() is None


def _wait_for_signal(lines, signal: str, out, proc) -> None:
    """Wait for a followed signal; on failure say what the dump printed and whether it lives."""
    try:
        wait_until(lambda: any(e.get("signal") == signal for e in lines()), 20, message=signal)
    except AssertionError:
        raise AssertionError(f"no {signal} followed (dump exit code {proc.poll()}); it printed:\n"
                             f"{out.read_text()[-4000:]}") from None
