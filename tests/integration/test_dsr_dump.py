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


def test_dump_reports_unreachable_router_on_stderr():
    result = CliRunner().invoke(app, ["dsr", "dump", "--json", "--connect", "tcp/127.0.0.1:1"])
    assert result.exit_code == 1 and "cannot open Zenoh session" in result.stderr
    assert result.stdout == ""


def test_stats_without_a_running_graph_says_so_on_stderr(world):
    result = CliRunner().invoke(app, ["dsr", "stats", "--json", "--connect", "tcp/127.0.0.1:1"])
    assert result.exit_code == 1 and "cannot open Zenoh session" in result.stderr
    assert result.stdout == ""
    result = CliRunner().invoke(app, ["dsr", "stats", "--connect", world, "--graph", "nope",
                                      "--timeout", "1"])
    assert result.exit_code == 1 and "no member of graph 'nope'" in result.stderr
    result = CliRunner().invoke(app, ["dsr", "stats", "--connect", world])
    assert result.exit_code == 0 and "1 members" in result.stdout


def test_dump_follow_prints_changes(world, procs, tmp_path):
    out = tmp_path / "follow.jsonl"
    proc = procs.spawn(["-m", "tools.cli", "dsr", "dump", "--follow", "--json", "--connect",
                        world, "--duration", "20"], log_path=out)

    def lines() -> list[dict]:
        return [json.loads(line) for line in out.read_text().splitlines() if line.startswith("{")]
    wait_until(lambda: out.exists() and len(lines()) >= 1, 20, message="initial dump")
    assert len(lines()[0]["nodes"]) == 5
    with join("writer", settings=ZenohSettings(connect=[world])) as graph:
        node = graph.insert_node("person", "zoe", {"age": 80})
        graph.update_node(node.id, {"age": 81})
        wait_until(lambda: any(e.get("signal") == "node_updated" for e in lines()), 20,
                   message="followed update")
    events = lines()[1:]
    assert events[0] == {"signal": "node_added", "node": {"id": node.id, "type": "person",
                                                          "name": "zoe", "attrs": {"age": 80}}}
    assert events[1]["changed"] == ["age"] and events[1]["node"]["attrs"]["age"] == 81
    assert proc.poll() is None
