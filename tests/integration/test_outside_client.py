"""docs/dsr_wire_format.md and docs/deployment.md are the contract: a client built from them
alone (outside_client.py: `zenoh` and the standard library) joins a live run with the run's
own `tool` login from its connect.json (router with per-run users and ACL, the shipped write
policy), mirrors it from deltas, answers state queries, writes and deletes a granted
`agenda_request`, and its mirror equals `chronav dsr dump --json` at every step.  Its two
forbidden writes are refused and counted where the doc says (the members' `policy` counter,
the router's ACL count); nothing else it sent is refused, and its state reply is valid."""

from __future__ import annotations

import ast
import json
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from tests.integration.fault_support import spawn_script, status_of
from tests.support import free_port, wait_until
from tools.cli import app

pytestmark = pytest.mark.slow

CLIENT = Path(__file__).with_name("outside_client.py")
AGENTS = ("sim_robot", "object_recognition", "agenda", "executive")
SIM = [{"op": "insert", "type": "world", "name": "world"},
       {"op": "insert", "type": "robot", "name": "robot", "attrs": {"pose_stamp": 0.0}},
       {"op": "edge", "src": "world", "dst": "robot", "type": "RT",
        "attrs": {"x": 1.0, "y": 1.0, "theta": 0.0}}]
OBJECTS = [{"op": "wait", "names": ["world"]},
           {"op": "insert", "type": "object", "name": "tv", "attrs": {"kind": "tv", "footprint_dims": [1.2, 0.4]}}]
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


def dump(run: Path) -> dict:
    result = CliRunner().invoke(app, ["dsr", "dump", "--json", "--run", str(run)])
    assert result.exit_code == 0, result.output
    document = json.loads(result.stdout)
    return {"nodes": document["nodes"], "edges": document["edges"]}


def start_run(procs, tmp_path: Path) -> tuple[Path, object]:
    """A run as `chronav launch` secures it: per-run users, ACL, connect.json (tools/system/runs.py)."""
    from tools.system.runs import prepare_run_security, write_connect_file
    run = tmp_path / "run"
    run.mkdir()
    security = prepare_run_security(run, "chronav", AGENTS)
    port = free_port()
    log = tmp_path / "router.log"
    procs.spawn(["-m", "dsr.router", "--listen", f"tcp/127.0.0.1:{port}",
                 *security.router_args()], log_path=log)
    wait_until(lambda: "dsr.router ready" in (log.read_text() if log.exists() else ""), 15,
               message="router ready")
    write_connect_file(run, run_id="outside", endpoint=f"tcp/127.0.0.1:{port}",
                       graph="chronav", security=security)
    return run, security


def test_outside_client_mirror_equals_the_dump(procs, tmp_path):
    run, security = start_run(procs, tmp_path)
    endpoint = json.loads((run / "connect.json").read_text())["endpoint"]

    def env(agent: str) -> dict[str, str]:
        return {"CHRONAV_ZENOH_LEASE_MS": "1000", **security.agent_env(agent)}

    paths = {}
    for agent, script in (("sim_robot", SIM), ("object_recognition", OBJECTS),
                          ("agenda", AGENDA)):
        _, paths[agent] = spawn_script(procs, tmp_path, agent, connect=endpoint,
                                       env=env(agent), script=script)
    wait_until(lambda: all(status_of(p).get("script_done") for p in paths.values())
               and len({status_of(p).get("digest") for p in paths.values()}) == 1, 30,
               message="a live graph")
    work = tmp_path / "client"
    work.mkdir()
    client = procs.spawn([str(CLIENT), "--run", str(run), "--agent",
                          "agenda_tool-outside", "--dir", str(work)],
                         log_path=tmp_path / "client.log")

    def step(name: str) -> dict:
        wait_until(lambda: (work / f"{name}.json").exists() or client.poll() is not None, 60,
                   message=f"client step {name}")
        assert client.poll() is None, (tmp_path / "client.log").read_text()
        return json.loads((work / f"{name}.json").read_text())

    joined = step("joined")
    assert {n["name"] for n in joined["nodes"]} >= {"world", "robot", "tv", "activity/game"}
    assert {"nodes": joined["nodes"], "edges": joined["edges"]} == dump(run)
    # more writes while the client is in: it must follow them from deltas alone
    _, later = spawn_script(procs, tmp_path, "executive", connect=endpoint,
                            env=env("executive"), script=LATER)
    wait_until(lambda: status_of(later).get("script_done"), 30, message="executive wrote")
    paths["executive"] = later
    (work / "joined.go").touch()
    inserted = step("inserted")
    assert inserted["received"] > 0
    names = {n["name"] for n in inserted["nodes"]}
    assert "mission/m1" in names and any(n.startswith("agenda_request/") for n in names)
    wait_until(lambda: all(any(n.startswith("agenda_request/") for n in status_of(p)["names"])
                           for p in paths.values()), 20, message="request accepted everywhere")
    assert {"nodes": inserted["nodes"], "edges": inserted["edges"]} == dump(run)
    # the client's state reply, as a member fetches it, is a valid state of its own writes
    reply = own_state(endpoint, security.reader)
    assert reply["clock"] > 0 and reply["seen"] == {reply["replica"]: reply["clock"]}
    assert reply["writers"] == {str(reply["replica"]): "agenda_tool-outside"}
    assert [n["id"] for n in reply["nodes"]] == [n["id"] for n in inserted["nodes"]
                                                 if n["name"].startswith("agenda_request/")]
    (work / "inserted.go").touch()
    refused = step("refused")
    wait_until(lambda: all(status_of(p)["stats"]["rejected_policy"] == 1
                           for p in paths.values()), 20, message="the forged request refused")
    assert {"nodes": refused["nodes"], "edges": refused["edges"]} == dump(run)
    (work / "refused.go").touch()
    deleted = step("deleted")
    assert not any(n["name"].startswith("agenda_request/") for n in deleted["nodes"])
    wait_until(lambda: not any(any(n.startswith("agenda_request/") for n in status_of(p)["names"])
                               for p in paths.values()), 20, message="delete applied everywhere")
    assert {"nodes": deleted["nodes"], "edges": deleted["edges"]} == dump(run)
    (work / "deleted.go").touch()
    for agent, path in paths.items():
        stats = status_of(path)["stats"]
        assert stats["rejected"] == 0 and stats["rejects"] == {"policy": 1}, (agent, stats)
        assert "may not create a 'agenda_request' node with 'state' = 'accepted'" in \
            stats["last_reject"], (agent, stats)
    result = CliRunner().invoke(app, ["dsr", "stats", "--json", "--run", str(run)])
    assert result.exit_code == 0, result.output
    document = json.loads(result.stdout)
    members = document["members"]
    assert {"sim_robot", "object_recognition", "agenda", "executive"} <= set(members)
    assert all(m["stats"]["rejected"] == 0 for m in members.values())
    assert members["sim_robot"]["stats"]["received"] > 0
    denied = {(d["user"], d["message"], d["key"]) for d in document["router"]["denials"]}
    assert ("agenda_tool", "put", "chronav/chronav/delta/sim_robot") in denied, document["router"]


def own_state(endpoint: str, reader) -> dict:
    """The client's state reply, fetched as a member does (here with the reader login)."""
    import zenoh

    from dsr import ZenohSettings, wire
    settings = ZenohSettings(connect=[endpoint], user=reader.user, password=reader.password)
    with zenoh.open(settings.to_zenoh_config()) as session:
        replies = [r.ok for r in session.get(wire.state_key("chronav", "agenda_tool-outside"),
                                             timeout=10) if r.ok is not None]
    assert len(replies) == 1
    payload = replies[0].payload.to_bytes()
    assert wire.decode(payload).kind == "state"      # valid for every member's decoder
    document = json.loads(payload)
    document["seen"] = {int(k): v for k, v in document["seen"].items()}
    return document
