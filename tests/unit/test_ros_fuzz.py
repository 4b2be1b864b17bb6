"""Property-based fuzz of the ROS 2 bridge's receive path (issue 42): Hypothesis sends valid-typed
/goal_pose, /odom and /scan messages with extreme values (NaN, infinities, 1e308, float32's
extremes, empty and odd frames, broken stamps), truncated messages and random bytes, through the
same handler Zenoh calls for every sample (tests/ros_bridge_harness.py), then steps the bridge.
The bridge never raises (so it is never restarted), every message is counted exactly once as taken
or refused, and what reaches the DSR is finite and inside the scene."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from tests.ros_bridge_harness import bridge

from agents.ros_bridge import messages as msgs
from agents.ros_bridge.types import msg_class, serialize
from agents.world.vocabulary import WORLD, EdgeType, NodeType

TOPICS = {"/goal_pose": msgs.POSE_STAMPED, "/odom": msgs.ODOMETRY, "/scan": msgs.LASER_SCAN}
EXTREMES = [0.0, -0.0, 1e308, -1e308, 5e-324, math.nan, math.inf, -math.inf, 3e38, 1e-45]


def mostly(good: st.SearchStrategy, bad: st.SearchStrategy) -> st.SearchStrategy:
    """``good`` three times in four: messages valid but for one or two fields reach every check."""
    return st.sampled_from((good, good, good, bad)).flatmap(lambda chosen: chosen)


f64 = mostly(st.floats(-1.0, 1.0), st.floats() | st.sampled_from(EXTREMES))
f32_any = st.floats(width=32) | st.sampled_from([math.nan, math.inf, -math.inf, 3e38, -3e38, 1e-45])
odd_frames = st.sampled_from(["", "MAP", "map ", "/map", "\x00", "é" * 50]) | st.text(max_size=8)
stamps = mostly(st.builds(lambda sec, ns: msg_class("builtin_interfaces/msg/Time")(sec=sec, nanosec=ns),
                          st.integers(0, 2**31 - 1), st.integers(0, 999_999_999)),
                st.builds(lambda sec, ns: msg_class("builtin_interfaces/msg/Time")(sec=sec, nanosec=ns),
                          st.integers(-(2**31), -1), st.integers(0, 2**32 - 1)))
T = msg_class


def header(frame: str) -> st.SearchStrategy:
    return st.builds(lambda stamp, frame: T("std_msgs/msg/Header")(stamp=stamp, frame_id=frame), stamps,
                     mostly(st.just(frame), odd_frames))


def vec(cls: str) -> st.SearchStrategy:
    return st.builds(lambda x, y, z: T(cls)(x=x, y=y, z=z), f64, f64, f64)


quaternions = mostly(st.floats(-10, 10).map(lambda yaw: msgs.quaternion(yaw)), st.builds(
    lambda x, y, z, w: T("geometry_msgs/msg/Quaternion")(x=x, y=y, z=z, w=w), f64, f64, f64, f64))
points = mostly(st.tuples(st.floats(1.0, 5.0), st.floats(1.5, 3.0)).map(lambda xy: msgs.point(*xy)),   # reachable
                st.tuples(st.floats(-6, 12), st.floats(-6, 10)).map(lambda xy: msgs.point(*xy))
                | vec("geometry_msgs/msg/Point"))
poses = st.builds(lambda p, q: T("geometry_msgs/msg/Pose")(position=p, orientation=q), points, quaternions)
goals = st.builds(lambda h, p: T(msgs.POSE_STAMPED)(header=h, pose=p), header("map"), poses)
covariance = st.just(np.zeros(36)) | st.lists(f64, min_size=36, max_size=36).map(np.array)
odoms = st.builds(
    lambda h, child, p, c1, lin, ang, c2: T(msgs.ODOMETRY)(
        header=h, child_frame_id=child, pose=T("geometry_msgs/msg/PoseWithCovariance")(pose=p, covariance=c1),
        twist=T("geometry_msgs/msg/TwistWithCovariance")(twist=T(msgs.TWIST)(linear=lin, angular=ang), covariance=c2)),
    header("odom"), mostly(st.just("base_link"), odd_frames), poses, covariance, vec("geometry_msgs/msg/Vector3"),
    vec("geometry_msgs/msg/Vector3"), covariance)


def _scan(h, geometry, ranges, inten):
    a0, a1, inc, ti, st_, r0, r1 = geometry
    return T(msgs.LASER_SCAN)(header=h, angle_min=a0, angle_max=a1, angle_increment=inc, time_increment=ti,
                              scan_time=st_, range_min=r0, range_max=r1, ranges=np.asarray(ranges, dtype=np.float32),
                              intensities=np.asarray(inten, dtype=np.float32))


good_geometry = st.just((-1.57, 1.57, 3.14 / 90, 0.0, 0.1, 0.05, 5.0))
scans = st.builds(_scan, header("base_link"),
                  mostly(good_geometry, st.tuples(*[mostly(st.floats(-7, 7, width=32), f32_any)] * 7)),
                  st.lists(mostly(st.floats(0, 6, width=32), f32_any), max_size=400),
                  st.lists(f32_any, max_size=20))
MESSAGES = {"/goal_pose": goals, "/odom": odoms, "/scan": scans}


@st.composite
def payloads(draw: st.DrawFn) -> tuple[str, bytes]:
    """(topic, bytes): a serialized message, that message cut or with a byte flipped, or random bytes."""
    topic = draw(st.sampled_from(sorted(TOPICS)))
    kind = draw(st.sampled_from(["message", "message", "cut", "flipped", "random"]))
    if kind == "random":
        return topic, draw(st.binary(max_size=300))
    data = bytearray(serialize(draw(MESSAGES[topic]), TOPICS[topic]))
    if kind == "cut":
        return topic, bytes(data[:draw(st.integers(0, len(data)))])
    if kind == "flipped":
        index = draw(st.integers(0, len(data) - 1))
        data[index] ^= draw(st.integers(1, 255))
    return topic, bytes(data)


@pytest.fixture(scope="module")
def agent_graph():
    return bridge(robot="ros")


@settings(max_examples=200, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.function_scoped_fixture,
                                                                  HealthCheck.too_slow, HealthCheck.data_too_large])
@given(batch=st.lists(payloads(), min_size=1, max_size=12))
def test_whatever_ros_sends_the_bridge_stays_up_and_counts_it(agent_graph, batch: list[tuple[str, bytes]]) -> None:
    agent, graph = agent_graph
    before = _total(agent)
    for topic, data in batch:
        agent.node.handlers[topic](data)
    agent._robot_written = -math.inf
    agent.step()   # raises nothing: an exception here is what used to end (and restart) the bridge
    assert _total(agent) - before == len(batch), "every message is counted once, taken or refused"
    assert agent.graph.refused == 0, agent.graph.last_refusal      # nothing written outside the vocabulary
    world, robot = graph.get_node_by_name(WORLD), graph.get_node_by_name("robot")
    pose = graph.get_edge(world.id, robot.id, EdgeType.RT).attrs
    assert all(math.isfinite(pose[k]) for k in ("x", "y", "theta")) and -5.0 <= pose["x"] <= 11.0
    assert all(math.isfinite(robot.attrs.get(k, 0.0)) for k in ("v", "vy", "omega"))
    for mission in graph.nodes_of_type(NodeType.MISSION):
        x, y, _yaw = (float(v) for v in mission.attrs["goal"].removeprefix("pose:").split(","))
        assert 0.0 < x < 6.0 and 0.0 < y < 4.0      # inside the lounge: a goal the robot can reach


def _total(agent) -> int:
    counts = agent.received.snapshot()
    return sum(counts["accepted"].values()) + sum(sum(r.values()) for r in counts["refused"].values())


def test_the_fuzz_found_refusals_of_several_kinds(agent_graph) -> None:
    """After the fuzz (same module fixture), the counters hold many reasons: the strategies reach
    the checks, not only the decoder."""
    agent, _graph = agent_graph
    reasons = {r for per_topic in agent.received.snapshot()["refused"].values() for r in per_topic}
    assert {"undecodable", "not_finite", "empty_frame", "wrong_frame", "bad_stamp", "unreachable"} <= reasons, reasons
    assert set(agent.received.snapshot()["accepted"]) == {"/goal_pose", "/odom", "/scan"}   # and valid ones pass


