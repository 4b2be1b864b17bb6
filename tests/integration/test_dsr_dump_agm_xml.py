"""`chronav dsr dump --format agm-xml`: the live graph as RoboComp AGM world XML, read back by
chronav's AGM world reader (the one `chronav plan --world` uses)."""

from __future__ import annotations

import pytest
from typer.testing import CliRunner

from dsr import ZenohSettings, join
from grammar.agm_world import parse_agm_world
from tests.integration.dsr_support import read_status, spawn_worker, start_router
from tests.support import wait_until
from tools.cli import app

pytestmark = pytest.mark.slow


def test_dump_agm_xml_is_an_agm_world(procs, tmp_path):
    endpoint, _ = start_router(procs, tmp_path)
    _, status = spawn_worker(procs, endpoint, tmp_path, "a", "--world", "3")
    wait_until(lambda: (read_status(status) or {}).get("done", False), 30, message="world")
    with join("writer", settings=ZenohSettings(connect=[endpoint])) as graph:
        room = graph.insert_node("room", "kitchen", {"area": 12.5})
        robot = graph.insert_node("robot", "robot")
        graph.insert_or_assign_edge(robot.id, room.id, "in", attrs={"since": "09:00"})
        wait_until(lambda: len(graph) == 5, 20, message="writer sees the world")
        # the dump takes its snapshot from the replica that stays: it must hold the writer's nodes
        # before the writer leaves (a loaded machine once dumped the world without them)
        wait_until(lambda: (read_status(status) or {}).get("nodes") == 5, 20, message="the worker sees the writes")
    runner = CliRunner()
    result = runner.invoke(app, ["dsr", "dump", "--format", "agm-xml", "--connect", endpoint])
    assert result.exit_code == 0, result.output
    world = parse_agm_world(result.stdout, "dump.xml")
    assert world.symbols[str(room.id)].type == "room"
    assert world.symbols[str(room.id)].attrs == {"name": "kitchen", "area": "12.5"}
    assert [(l.src, l.dst, l.label, l.attrs) for l in world.links] == [
        (str(robot.id), str(room.id), "in", {"since": "09:00"})]
    refused = runner.invoke(app, ["dsr", "dump", "--format", "agm-xml", "--follow", "--connect", endpoint])
    assert refused.exit_code == 2 and "one snapshot" in refused.stderr
