"""docs/dsr_wire_format.md is the contract: a client built from it alone (outside_client.py:
`zenoh` and the standard library) joins a live graph guarded by the shipped write policy,
mirrors it from deltas, writes and deletes a granted `agenda_request`, and its mirror equals
`chronav dsr dump --json` at every step; no member refuses anything it sent."""

from __future__ import annotations

import ast
import json
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from tests.integration.dsr_support import start_router
from tests.integration.fault_support import spawn_script, status_of
from tests.support import wait_until
from tools.cli import app

pytestmark = pytest.mark.slow

CLIENT = Path(__file__).with_name("outside_client.py")
SIM = [{"op": "insert", "type": "world", "name": "world"},
       {"op": "insert", "type": "robot", "name": "robot", "attrs": {"pose_stamp": 0.0}},
       {"op": "edge", "src": "world", "dst": "robot", "type": "RT",
        "attrs": {"x": 1.0, "y": 1.0, "theta": 0.0}}]
OBJECTS = [{"op": "wait", "names": ["world"]},
           {"op": "insert", "type": "object", "name": "tv", "attrs": {"kind": "tv", "n": 3}}]
AGENDA = [{"op": "wait", "names": ["tv"]},
          {"op": "insert", "type": "activity", "name": "activity/game",
           "attrs": {"state": "scheduled", "participants": ["ana", "ben"]}},
          {"op": "update", "name": "tv", "attrs": {"R": 0.5}},
          {"op": "edge", "src": "activity/game", "dst": "tv", "type": "has"}]
LATER = [{"op": "insert", "type": "mission", "name": "mission/m1", "attrs": {"state": "pending"}},
         {"op": "update", "name": "mission/m1", "attrs": {"state": "active", "started_s": 1.5}}]


def test_client_imports_only_zenoh_and_the_standard_library():
    tree = ast.parse(CLIENT.read_text())
    imported = {alias.name.split(".")[0] for node in ast.walk(tree)
                if isinstance(node, ast.Import) for alias in node.names}
    imported |= {node.module.split(".")[0] for node in ast.walk(tree)
                 if isinstance(node, ast.ImportFrom) and node.module}
    assert imported - {"__future__"} <= set(sys.stdlib_module_names) | {"zenoh"}, imported


def dump(endpoint: str) -> dict:
    result = CliRunner().invoke(app, ["dsr", "dump", "--json", "--connect", endpoint])
    assert result.exit_code == 0, result.output
    document = json.loads(result.stdout)
    return {"nodes": document["nodes"], "edges": document["edges"]}


def test_outside_client_mirror_equals_the_dump(procs, tmp_path):
    endpoint, _ = start_router(procs, tmp_path)
    env = {"CHRONAV_ZENOH_LEASE_MS": "1000"}       # the shipped write policy
    paths = {}
    for agent, script in (("sim_robot", SIM), ("object_recognition", OBJECTS),
                          ("agenda", AGENDA)):
        _, paths[agent] = spawn_script(procs, tmp_path, agent, connect=endpoint, env=env,
                                       script=script)
    wait_until(lambda: all(status_of(p).get("script_done") for p in paths.values())
               and len({status_of(p).get("digest") for p in paths.values()}) == 1, 30,
               message="a live graph")
    work = tmp_path / "client"
    work.mkdir()
    client = procs.spawn([str(CLIENT), "--connect", endpoint, "--agent",
                          "agenda_tool-outside", "--dir", str(work)],
                         log_path=tmp_path / "client.log")

    def step(name: str) -> dict:
        wait_until(lambda: (work / f"{name}.json").exists() or client.poll() is not None, 60,
                   message=f"client step {name}")
        assert client.poll() is None, (tmp_path / "client.log").read_text()
        return json.loads((work / f"{name}.json").read_text())

    joined = step("joined")
    assert {n["name"] for n in joined["nodes"]} >= {"world", "robot", "tv", "activity/game"}
    assert {"nodes": joined["nodes"], "edges": joined["edges"]} == dump(endpoint)
    # more writes while the client is in: it must follow them from deltas alone
    _, later = spawn_script(procs, tmp_path, "executive", connect=endpoint, env=env, script=LATER)
    wait_until(lambda: status_of(later).get("script_done"), 30, message="executive wrote")
    (work / "joined.go").touch()
    inserted = step("inserted")
    assert inserted["received"] > 0
    names = {n["name"] for n in inserted["nodes"]}
    assert "mission/m1" in names and any(n.startswith("agenda_request/") for n in names)
    wait_until(lambda: all(any(n.startswith("agenda_request/") for n in status_of(p)["names"])
                           for p in paths.values()), 20, message="request accepted everywhere")
    assert {"nodes": inserted["nodes"], "edges": inserted["edges"]} == dump(endpoint)
    (work / "inserted.go").touch()
    deleted = step("deleted")
    assert not any(n["name"].startswith("agenda_request/") for n in deleted["nodes"])
    wait_until(lambda: not any(any(n.startswith("agenda_request/") for n in status_of(p)["names"])
                               for p in paths.values()), 20, message="delete applied everywhere")
    assert {"nodes": deleted["nodes"], "edges": deleted["edges"]} == dump(endpoint)
    (work / "deleted.go").touch()
    for agent, path in paths.items():
        stats = status_of(path)["stats"]
        assert stats["rejected"] == 0 and stats["rejected_policy"] == 0, (agent, stats)
    result = CliRunner().invoke(app, ["dsr", "stats", "--json", "--connect", endpoint])
    assert result.exit_code == 0, result.output
    members = json.loads(result.stdout)["members"]
    assert {"sim_robot", "object_recognition", "agenda", "executive"} <= set(members)
    assert all(m["stats"]["rejected"] == 0 for m in members.values())
    assert members["sim_robot"]["stats"]["received"] > 0
