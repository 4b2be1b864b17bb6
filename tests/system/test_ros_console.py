"""`chronav launch --ros` with the ROS side unreachable: the progress line and the run's summary
say so, with the reason (issue 39: the run ended "OK: 4/4" and only logs/ros_bridge.log knew)."""

from __future__ import annotations

import json
import os
import signal
from pathlib import Path

import pytest

from tests.support import REPO_ROOT, ProcessGroup, free_port

pytestmark = pytest.mark.slow
SCENE = REPO_ROOT / "tests" / "data" / "agenda_live.yaml"     # one mission, done in ~20 s of sim time


def test_an_unreachable_ros_side_shows_on_the_progress_line_and_in_the_summary(procs: ProcessGroup,
                                                                              tmp_path: Path) -> None:
    endpoint = f"tcp/127.0.0.1:{free_port()}"           # no ROS router there
    runs, log = tmp_path / "runs", tmp_path / "launch.log"
    proc = procs.spawn(["-m", "tools.cli", "launch", str(SCENE), "--ros", "--no-record", "--timeout", "150"],
                       env={"CHRONAV_RUNS": str(runs), "CHRONAV_ROS_ENDPOINT": endpoint}, log_path=log)
    proc.wait(timeout=200)
    text = log.read_text()
    problem = f"ros_bridge: the ROS 2 side does not answer: no Zenoh router at {endpoint}"
    assert proc.returncode == 0, text[-3000:]            # the bridge is a window: the missions still run
    progress = [line for line in text.splitlines() if line.startswith("[chronav] sim ")]
    assert any(f"| {problem}" in line for line in progress), progress
    assert f"problem at the end of the run: {problem}" in text
    assert "OK: 1/1 mission done" in text and "but ros_bridge reported a problem (above)" in text
    (result_file,) = runs.glob("*/result.json")
    assert json.loads(result_file.read_text())["problems"]["ros_bridge"].startswith("the ROS 2 side does not answer")


def test_a_ros_robot_that_never_sends_odom_is_the_reason_in_the_summary(procs: ProcessGroup, tmp_path: Path) -> None:
    """`--robot ros` with the ROS side up but no robot on it: the robot never moves, and the progress
    line, the missions' reason and the summary say the robot sends no /odom (issue 39).  The run is
    ended with Ctrl-C as soon as the progress line says so (the bridge reports a silent robot 5 s
    after it joins, the line comes every 5 s): a fixed --timeout had to cover the agents' start on a
    loaded machine (20 s was too short there) and made the test wait 45 s; the summary of a run that
    timed out with a problem is tests/unit/test_ros_console.py's."""
    from tests.support import port_open, wait_until

    port = free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    procs.spawn(["-m", "dsr.router", "--listen", endpoint], log_path=tmp_path / "ros_router.log")   # rmw_zenohd's stand-in
    wait_until(lambda: port_open(port), 30, message="the ROS-side router")
    runs, log = tmp_path / "runs", tmp_path / "launch.log"
    proc = procs.spawn(["-m", "tools.cli", "launch", str(SCENE), "--robot", "ros", "--no-record", "--timeout", "150"],
                       env={"CHRONAV_RUNS": str(runs), "CHRONAV_ROS_ENDPOINT": endpoint}, log_path=log)
    problem = "ros_bridge: the ROS 2 robot sends no /odom"

    def said_on_the_progress_line() -> bool:
        return any(line.startswith("[chronav] sim ") and f"| {problem}" in line
                   for line in log.read_text().splitlines()) or proc.poll() is not None
    wait_until(said_on_the_progress_line, 120, interval=0.2, message="the progress line naming the silent robot")
    assert proc.poll() is None, log.read_text()[-3000:]
    os.killpg(proc.pid, signal.SIGINT)
    proc.wait(timeout=60)
    text = log.read_text()
    assert proc.returncode == 130, text[-3000:]
    assert f"problem at the end of the run: {problem}" in text and "see below: ros_bridge" in text
    assert "INTERRUPTED" in text and "but ros_bridge reported a problem (above)" in text
