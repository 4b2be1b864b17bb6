"""The bridge's receive path behind a real Zenoh router on 127.0.0.1 (issue 42): Hypothesis'
payloads (tests/unit/test_ros_fuzz.py) put on rmw_zenoh data keys by a plain Zenoh publisher
reach the bridge's subscriptions (wire.RosNode) and its inbox, which counts every one."""

from __future__ import annotations

import logging

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from tests.support import process_group, wait_until
from tests.unit.test_ros_fuzz import TOPICS, payloads

from agents.ros_bridge import validate as v
from agents.ros_bridge.inbox import TYPES, Inbox, ReceiveStats
from agents.ros_bridge.wire import Qos, RosNode, ros_session_config, topic_key
from tools.ports import free_port, wait_for_port

DOMAIN = 11
KEYS = {"/goal_pose": "goal_pose", "/odom": "odom", "/scan": "scan"}


def test_payloads_sent_over_zenoh_are_all_counted() -> None:
    import zenoh

    port = free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    stats = ReceiveStats(logging.getLogger("test.ros_receive"))
    inbox = Inbox(v.Limits((0.0, 0.0, 6.0, 4.0)), {k: t for t, k in KEYS.items()}, stats)
    sent: list[tuple[str, bytes]] = []

    @settings(max_examples=60, deadline=None, derandomize=True, database=None,
              suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
    @given(batch=st.lists(payloads(), min_size=1, max_size=5))
    def collect(batch: list[tuple[str, bytes]]) -> None:
        sent.extend(batch)

    collect()
    with process_group() as group:
        group.spawn(["-m", "dsr.router", "--listen", endpoint])
        assert wait_for_port(port, 15)
        bridge_side = zenoh.open(ros_session_config(endpoint))
        ros_side = zenoh.open(ros_session_config(endpoint))
        try:
            node = RosNode(bridge_side, "chronav", DOMAIN)
            for topic, key in KEYS.items():
                node.create_subscription(topic, TYPES[key], Qos(), lambda data, key=key: inbox.receive(key, data))
            pubs = {t: ros_side.declare_publisher(topic_key(DOMAIN, t, TOPICS[t]),
                                                  congestion_control=zenoh.CongestionControl.BLOCK) for t in TOPICS}
            wait_until(lambda: all(p.matching_status.matching for p in pubs.values()), 10, message="subscribers")
            for topic, data in sent:
                pubs[topic].put(data)
            counted = lambda: sum(stats.snapshot()["accepted"].values()) + sum(  # noqa: E731
                sum(r.values()) for r in stats.snapshot()["refused"].values()) + inbox.goals.qsize()
            wait_until(lambda: counted() == len(sent), 20, message=f"{len(sent)} payloads counted")
            node.close()
        finally:
            bridge_side.close()
            ros_side.close()
    assert stats.snapshot()["refused"]
