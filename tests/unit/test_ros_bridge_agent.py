"""The ROS 2 bridge agent's receive path, stepped on a DSR without a ROS network (issue 42):
whatever /odom, /scan and /goal_pose hold, the bridge's loop goes on, refuses with a count per
topic and reason, shows the counts on /diagnostics, and turns only reachable goals into missions."""

from __future__ import annotations

import math

import numpy as np
import pytest
from tests.ros_bridge_harness import bridge
from tests.unit.test_ros_validate import goal, odom, scan

from agents.ros_bridge import messages as msgs
from agents.ros_bridge import validate as v
from agents.ros_bridge.types import serialize
from agents.ros_bridge.wire import MAX_RECEIVED_BYTES
from agents.world.vocabulary import WORLD, EdgeType, NodeType


def send(agent, topic: str, message: object, type_name: str) -> None:
    agent.node.handlers[topic](serialize(message, type_name))


def robot_pose(graph) -> tuple[float, float]:
    world, robot = graph.get_node_by_name(WORLD), graph.get_node_by_name("robot")
    edge = graph.get_edge(world.id, robot.id, EdgeType.RT)
    return edge.attrs["x"], edge.attrs["y"]


def missions(graph) -> list[str]:
    return [n.attrs["goal"] for n in graph.nodes_of_type(NodeType.MISSION)]


def test_a_nan_odometry_does_not_end_the_bridge_and_is_counted() -> None:
    agent, graph = bridge()
    before = robot_pose(graph)
    for _ in range(5):   # more than the supervisor's 3 restarts used to allow
        send(agent, "/odom", odom(x=math.nan), msgs.ODOMETRY)
        send(agent, "/odom", odom(x=1e308), msgs.ODOMETRY)
        agent.step()
    assert robot_pose(graph) == before
    assert agent.received.snapshot()["refused"]["/odom"] == {v.NOT_FINITE: 5, v.OUTSIDE_MAP: 5}
    send(agent, "/odom", odom(x=2.5, y=1.5), msgs.ODOMETRY)
    agent._robot_written = -math.inf
    agent.step()
    assert robot_pose(graph) == (2.5, 1.5)


def test_a_ros_scan_reaches_the_dsr_resampled_and_a_bad_one_does_not() -> None:
    agent, graph = bridge()
    robot = graph.get_node_by_name("robot")
    graph.update_node(robot.id, attrs={"laser_angles": [-1.0, 0.0, 1.0]})
    send(agent, "/scan", scan(angle_min=math.nan), msgs.LASER_SCAN)
    send(agent, "/scan", scan([3e38] * 91), msgs.LASER_SCAN)
    send(agent, "/odom", odom(), msgs.ODOMETRY)
    agent.step()
    assert "laser_ranges" not in graph.get_node_by_name("robot").attrs
    send(agent, "/scan", scan([1.5] * 91), msgs.LASER_SCAN)
    send(agent, "/odom", odom(), msgs.ODOMETRY)
    agent._robot_written = -math.inf
    agent.step()
    assert graph.get_node_by_name("robot").attrs["laser_ranges"] == pytest.approx([1.5, 1.5, 1.5])
    assert agent.received.snapshot()["refused"]["/scan"] == {v.NOT_FINITE: 1, v.BAD_RANGE: 1}


def test_only_goals_the_robot_can_reach_become_missions() -> None:
    agent, graph = bridge(robot="sim")
    cases = {"x=1e308": goal(x=1e308), "empty frame": goal(frame=""), "outside": goal(x=6.5, y=2.0),
             "in the wall": goal(x=0.1, y=2.0), "on the tv": goal(x=3.0, y=0.55), "good": goal(x=2.0, y=2.5)}
    for message in cases.values():
        send(agent, "/goal_pose", message, msgs.POSE_STAMPED)
    agent.step()
    assert missions(graph) == ["pose:2.000,2.500,0.5000"]
    counts = agent.received.snapshot()
    assert counts["accepted"] == {"/goal_pose": 1}
    assert counts["refused"]["/goal_pose"] == {v.OUTSIDE_MAP: 1, v.EMPTY_FRAME: 1, v.UNREACHABLE: 3}


def test_garbage_and_oversized_payloads_are_counted() -> None:
    agent, _graph = bridge()
    handler = agent.node.handlers["/goal_pose"]
    handler(b"\x00\x01\x00\x00garbage")
    handler(b"")
    handler(b"\x00" * (MAX_RECEIVED_BYTES + 1))
    agent.node.handlers["/odom"](serialize(goal(), msgs.POSE_STAMPED)[:20])
    agent.step()
    refused = agent.received.snapshot()["refused"]
    assert refused == {"/goal_pose": {v.UNDECODABLE: 2, v.TOO_LARGE: 1}, "/odom": {v.UNDECODABLE: 1}}


def test_an_unexpected_error_while_using_a_message_is_counted_not_raised() -> None:
    agent, graph = bridge()
    send(agent, "/odom", odom(), msgs.ODOMETRY)

    def broken(*_args: object, **_kwargs: object) -> None:
        raise RuntimeError("the DSR refused it")

    graph.update_node = broken   # type: ignore[method-assign]
    agent.step()
    assert agent.received.snapshot()["refused"]["/odom"] == {v.INTERNAL: 1}


def test_diagnostics_and_filter_info_are_published_in_the_scenes_time() -> None:
    agent, _graph = bridge()
    send(agent, "/odom", odom(x=math.nan), msgs.ODOMETRY)
    agent._last.pop("diagnostics", None)
    agent.step()
    arrays = agent.node.publishers["/diagnostics"].sent
    status = {s.name: s for s in arrays[-1].status}
    odom_status = status["chronav: received /odom"]
    assert odom_status.level == msgs.DIAGNOSTIC_WARN
    assert {kv.key: kv.value for kv in odom_status.values}["refused.not_finite"] == "1"
    assert status["chronav: received /goal_pose"].level == msgs.DIAGNOSTIC_OK
    expected = msgs.ros_time(36_000.0, agent.epoch_s)   # 10:00 of the scene's day
    info = agent.node.publishers["/costmap_filter_info"].sent[0]
    assert (info.header.stamp.sec, info.header.stamp.nanosec) == (expected.sec, expected.nanosec)
    assert np.isclose(info.base, agent.scale.base)


def test_a_pose_is_written_once_and_a_silent_odometry_stops_the_robot() -> None:
    """A roboticist's expectation: the navigation never steers by a frozen pose. Each /odom is
    written into the DSR once; after ODOM_TIMEOUT_S without a valid one (silence, or only refused
    ones) the bridge sends a zero /cmd_vel and holds the navigation's commands until it returns."""
    import time

    from agents.ros_bridge.agent import ODOM_TIMEOUT_S

    agent, graph = bridge()
    cmd_vel = agent.node.publishers["/cmd_vel"].sent
    agent.step()
    assert agent._halted and cmd_vel[-1].linear.x == 0.0            # no /odom yet: stopped
    send(agent, "/odom", odom(), msgs.ODOMETRY)
    agent.step()
    robot = graph.get_node_by_name("robot")
    stamp = robot.attrs["pose_stamp"]
    assert not agent._halted
    clock = graph.get_node_by_name("clock")
    graph.update_node(clock.id, attrs={"now_s": clock.attrs["now_s"] + 1.0})
    agent._robot_written = -math.inf
    agent.step()
    assert graph.get_node_by_name("robot").attrs["pose_stamp"] == stamp   # no new odometry: not rewritten
    graph.update_node(robot.id, attrs={"cmd_stamp": 1.0, "cmd_vx": 0.4, "cmd_vy": 0.0, "cmd_omega": 0.0})
    graph.dispatch()   # the DSR signal the bridge reacts to
    assert cmd_vel[-1].linear.x == pytest.approx(0.4)                     # forwarded at once
    agent.inbox.odom_at = time.monotonic() - ODOM_TIMEOUT_S - 0.1         # odometry went silent
    for _ in range(3):
        send(agent, "/odom", odom(x=math.nan), msgs.ODOMETRY)             # refused ones do not count
    agent.step()
    assert agent._halted and cmd_vel[-1].linear.x == 0.0
    graph.update_node(robot.id, attrs={"cmd_stamp": 2.0, "cmd_vx": 0.5, "cmd_vy": 0.0, "cmd_omega": 0.0})
    graph.dispatch()   # the DSR signal the bridge reacts to
    assert cmd_vel[-1].linear.x == 0.0                                    # held while silent
    send(agent, "/odom", odom(), msgs.ODOMETRY)
    agent.step()
    graph.update_node(robot.id, attrs={"cmd_stamp": 3.0, "cmd_vx": 0.3, "cmd_vy": 0.0, "cmd_omega": 0.0})
    graph.dispatch()   # the DSR signal the bridge reacts to
    assert not agent._halted and cmd_vel[-1].linear.x == pytest.approx(0.3)


def test_the_counts_are_kept_in_the_run_directory(tmp_path) -> None:
    import json

    from agents.ros_bridge.agent import RECEIVED_FILE

    agent, _graph = bridge()
    agent.config = agent.config.model_copy(update={"run_dir": tmp_path})
    send(agent, "/goal_pose", goal(frame=""), msgs.POSE_STAMPED)
    agent._last.pop("diagnostics", None)
    agent.step()
    kept = json.loads((tmp_path / RECEIVED_FILE).read_text())
    assert kept["refused"] == {"/goal_pose": {v.EMPTY_FRAME: 1}} and kept["node"] == "chronav"
    send(agent, "/odom", odom(), msgs.ODOMETRY)
    agent.teardown()
    assert json.loads((tmp_path / RECEIVED_FILE).read_text())["accepted"] == {"/odom": 1}


def test_a_too_close_ray_is_an_obstacle_not_free_space() -> None:
    """REP-117: -inf means "too close to measure"; +inf and NaN mean no return."""
    from agents.ros_bridge.agent import resample_scan

    taken = v.check_scan(scan([-math.inf, math.inf, math.nan] + [2.0] * 88), v.Limits((0.0, 0.0, 6.0, 4.0)))
    first_three = [float(a) for a in np.linspace(-1.57, 1.57, 91)[:3]]
    assert resample_scan(taken, first_three, 5.0) == [pytest.approx(0.05), 5.0, 5.0]


def test_ros_stats_reads_what_a_run_kept(tmp_path) -> None:
    import json

    from typer.testing import CliRunner

    from agents.ros_bridge.agent import RECEIVED_FILE
    from tools.cli import app

    agent, _graph = bridge()
    agent.config = agent.config.model_copy(update={"run_dir": tmp_path})
    send(agent, "/odom", odom(x=math.nan), msgs.ODOMETRY)
    send(agent, "/odom", odom(), msgs.ODOMETRY)
    agent.teardown()
    done = CliRunner().invoke(app, ["ros", "stats", "--run", str(tmp_path), "--json"])
    assert done.exit_code == 0, done.output
    assert json.loads(done.stdout)["topics"] == {"/odom": {"taken": 1, "refused": 1, "reasons": {v.NOT_FINITE: 1}}}
    (tmp_path / RECEIVED_FILE).write_text('{"accepted": [1], "refused": 3}')
    done = CliRunner().invoke(app, ["ros", "stats", "--run", str(tmp_path)])
    assert done.exit_code == 1 and RECEIVED_FILE in done.stderr and "Traceback" not in done.output
    done = CliRunner().invoke(app, ["ros", "stats", "--run", str(tmp_path / "nothing")])
    assert done.exit_code == 1 and "no run" in done.stderr
