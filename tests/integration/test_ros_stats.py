"""`chronav ros stats` reads the bridge's refusal counts from ROS 2's /diagnostics, over a real
Zenoh router on 127.0.0.1 (issue 42): the path a user takes, against the DiagnosticArray the
bridge builds (agents/ros_bridge/messages.py) published as the bridge publishes it (wire.py)."""

from __future__ import annotations

import json
import subprocess
import sys
import threading

from agents.ros_bridge import messages as msgs
from agents.ros_bridge.wire import Qos, RosNode, ros_session_config
from tests.support import REPO_ROOT, process_group
from tools.ports import free_port, wait_for_port

DOMAIN = 9


def _stats(endpoint: str, *extra: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "tools.cli", "ros", "stats", "--ros-endpoint", endpoint,
                           "--ros-domain", str(DOMAIN), *extra], capture_output=True, text=True, timeout=60,
                          cwd=REPO_ROOT, check=False)


def test_ros_stats_shows_the_bridges_counts() -> None:
    import zenoh

    port = free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    received = {"accepted": {"/odom": 40, "/goal_pose": 1},
                "refused": {"/odom": {"not_finite": 3, "outside_map": 2}, "/goal_pose": {"unreachable": 1}}}
    with process_group() as group:
        group.spawn(["-m", "dsr.router", "--listen", endpoint])
        assert wait_for_port(port, 15)
        session = zenoh.open(ros_session_config(endpoint))
        stop = threading.Event()
        try:
            node = RosNode(session, "chronav", DOMAIN)
            pub = node.create_publisher("/diagnostics", msgs.DIAGNOSTIC_ARRAY, Qos(depth=10))
            array = msgs.diagnostics("chronav", received, {}, ["/goal_pose", "/odom", "/scan"],
                                     msgs.ros_time(36_000.0))

            def publish() -> None:
                while not stop.wait(0.2):
                    pub.publish(array)

            thread = threading.Thread(target=publish, daemon=True)
            thread.start()
            done = _stats(endpoint, "--json", "--timeout", "20")
            table = _stats(endpoint, "--timeout", "20")
        finally:
            stop.set()
            session.close()
    assert done.returncode == 0, done.stderr
    document = json.loads(done.stdout)
    assert document["topics"]["/odom"] == {"taken": 40, "refused": 5, "level": 1,
                                           "reasons": {"not_finite": 3, "outside_map": 2}}
    assert document["topics"]["/scan"] == {"taken": 0, "refused": 0, "level": 0, "reasons": {}}
    assert table.returncode == 0 and "not_finite=3" in table.stdout


def test_ros_stats_without_a_bridge_says_what_to_check() -> None:
    port = free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    with process_group() as group:
        group.spawn(["-m", "dsr.router", "--listen", endpoint])
        assert wait_for_port(port, 15)
        done = _stats(endpoint, "--timeout", "1")
    assert done.returncode == 1 and "is the bridge running" in done.stderr and "Traceback" not in done.stderr
