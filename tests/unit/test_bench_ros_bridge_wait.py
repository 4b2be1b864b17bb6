"""tools/bench/bench_ros_bridge.wait_for_bridge: the one wait (live and flood benchmarks) for a launch's
ros_bridge pid and its 'ROS 2 node' log line, on a fake run directory (no ROS, no processes)."""

from __future__ import annotations

import json
import threading
from pathlib import Path

import pytest

from tools.bench.bench_ros_bridge import BRIDGE_READY_LINE, wait_for_bridge


def _run(runs: Path, pids: dict[str, int] | None, log: str | None) -> Path:
    run = runs / "20260101-000000"
    (run / "logs").mkdir(parents=True)
    if pids is not None:
        (run / "pids.json").write_text(json.dumps(pids))
    if log is not None:
        (run / "logs" / "ros_bridge.log").write_text(log)
    return run


def test_returns_the_pids_once_the_bridge_logged_its_node(tmp_path: Path) -> None:
    run = _run(tmp_path, {"ros_bridge": 41, "sim_robot": 42}, "starting\n")

    def node_up() -> None:
        with (run / "logs" / "ros_bridge.log").open("a") as handle:
            handle.write(f"INFO {BRIDGE_READY_LINE} /chronav on domain 5 via tcp/127.0.0.1:7447: ok\n")

    threading.Timer(0.1, node_up).start()
    assert wait_for_bridge(tmp_path, timeout_s=10, poll_s=0.02) == {"ros_bridge": 41, "sim_robot": 42}


@pytest.mark.parametrize(("pids", "log", "missing"), [
    (None, None, "no ros_bridge pid"),
    ({"sim_robot": 42}, f"{BRIDGE_READY_LINE} up", "no ros_bridge pid"),
    ({"ros_bridge": 41}, None, "no 'ROS 2 node' line"),
    ({"ros_bridge": 41}, "starting\n", "no 'ROS 2 node' line"),
])
def test_a_bridge_that_does_not_come_up_is_a_timeout_naming_what_is_missing(
        tmp_path: Path, pids: dict[str, int] | None, log: str | None, missing: str) -> None:
    _run(tmp_path, pids, log)
    with pytest.raises(TimeoutError, match=missing):
        wait_for_bridge(tmp_path, timeout_s=0.1, poll_s=0.02)
