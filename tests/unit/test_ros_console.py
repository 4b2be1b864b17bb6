"""ROS trouble shows on the console (issue 39, point 4): the bridge says what keeps it from its job
(the ROS side's router does not answer; a --robot ros robot sends no /odom) on its heartbeat, and
the launcher's progress line and summary print it, where before only logs/ros_bridge.log had it."""

from __future__ import annotations

import io
import re
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from rich.console import Console

import agents.ros_bridge.agent as bridge_module
from agents.ros_bridge.agent import RosBridgeAgent
from agents.runtime.config import AgentConfig
from agents.runtime.heartbeat import Heartbeat, read_problem
from agents.runtime.recording import Recorder
from dsr import DSRGraph
from tests.support import REPO_ROOT, free_port
from tools.launch import RunResult
from tools.system.console import _PlainProgress, print_result

SCENE = REPO_ROOT / "tests" / "data" / "ros_lounge.yaml"


def _bridge(endpoint: str, **options: str) -> tuple[RosBridgeAgent, DSRGraph]:
    agent = RosBridgeAgent(AgentConfig(name="ros_bridge", scene=SCENE, options={"ros_endpoint": endpoint,
                                                                                 **options}))
    graph = DSRGraph("ros_bridge")
    graph.insert_node(type="world", name="world")
    graph.insert_node(type="clock", name="clock", attrs={"now_s": 36_000.0})
    agent.setup(graph, Recorder("ros_bridge", None, None))
    return agent, graph


@pytest.fixture
def ros_router() -> Iterator[str]:
    """A Zenoh router standing in for the ROS side's rmw_zenohd (nobody publishes /odom on it)."""
    import zenoh

    from agents.ros_bridge.wire import ros_session_config

    endpoint = f"tcp/127.0.0.1:{free_port()}"
    config = ros_session_config(endpoint, "router")
    config.insert_json5("listen/endpoints", f'["{endpoint}"]')
    config.insert_json5("connect/endpoints", "[]")
    session = zenoh.open(config)
    try:
        yield endpoint
    finally:
        session.close()


def test_an_unreachable_ros_side_is_the_bridges_problem_on_its_heartbeat() -> None:
    endpoint = f"tcp/127.0.0.1:{free_port()}"            # nothing listens there
    agent, graph = _bridge(endpoint)
    try:
        assert agent.problem.startswith(f"the ROS 2 side does not answer: no Zenoh router at {endpoint}")
        Heartbeat(graph, "ros_bridge").maybe_beat(agent.problem)
        assert read_problem(graph, "ros_bridge") == agent.problem
    finally:
        agent.teardown()


def test_a_ros_robot_that_sends_no_odom_is_reported_until_it_does(ros_router: str,
                                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(bridge_module, "ODOM_WAIT_S", 0.0)
    agent, graph = _bridge(ros_router, robot="ros")
    try:
        assert agent.problem == "" and agent.node is not None, "the ROS side answered"
        agent.step()
        # the wait is the time since the bridge started: 0 s, or more on a loaded machine
        assert re.match(rf"the ROS 2 robot sends no /odom \(waited \d+ s on ROS domain 0 via {re.escape(ros_router)}\)",
                        agent.problem), agent.problem
        heartbeat = Heartbeat(graph, "ros_bridge", period_s=0.0)
        heartbeat.maybe_beat(agent.problem)
        assert "sends no /odom" in read_problem(graph, "ros_bridge")
        agent.inbox.odom = object()                         # type: ignore[assignment]  # the first odometry arrived
        agent._check_odom(time.monotonic())
        heartbeat.maybe_beat(agent.problem)
        assert agent.problem == "" and read_problem(graph, "ros_bridge") == ""
    finally:
        agent.teardown()


PROBLEM = "the ROS 2 side does not answer: no Zenoh router at tcp/127.0.0.1:9 (start it)"


def test_progress_line_and_summary_show_the_problem(tmp_path: Path) -> None:
    out = io.StringIO()
    _PlainProgress(Console(file=out, width=300, force_terminal=False))(
        {"now_s": 36_000.0, "clock_mode": "driving", "missions": {}, "problems": {"ros_bridge": PROBLEM}})
    assert out.getvalue().strip() == f"[chronav] sim 10:00:00 clock=driving missions done 0/0 | ros_bridge: {PROBLEM}"
    result = RunResult(scene="ros_lounge", run_dir=tmp_path, rrd_path=None, events=[], restarts={}, wall_s=3.0,
                       missions={"m1": {"state": "pending", "time_s": 36_000.0}}, timed_out=True,
                       problems={"ros_bridge": PROBLEM})
    out = io.StringIO()
    print_result(result, Console(file=out, width=300, force_terminal=False))
    text: Any = out.getvalue()
    assert f"problem at the end of the run: ros_bridge: {PROBLEM}" in text
    assert "see below: ros_bridge" in text, "the missions table gives the likely reason"
    assert text.splitlines()[-1].startswith("TIMED OUT after 3.0 s wall (--timeout): 0/1 mission done")
    assert text.splitlines()[-1].endswith("but ros_bridge reported a problem (above)")


def test_the_live_table_carries_the_problem_as_its_caption() -> None:
    from tools.system.console import _status_table

    table = _status_table({"now_s": None, "clock_mode": None, "missions": {}, "agents": {},
                           "problems": {"ros_bridge": PROBLEM}})
    assert table.caption == f"ros_bridge: {PROBLEM}"
    out = io.StringIO()
    Console(file=out, width=300, force_terminal=False).print(table)
    assert "starting" in out.getvalue() and "None" not in out.getvalue()
