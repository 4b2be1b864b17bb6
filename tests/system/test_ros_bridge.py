"""chronav as a ROS 2 node over Zenoh, checked by an independent client (tests/integration/ros2_client.py).

The paths a user takes: a ROS-side Zenoh router (here `python -m dsr.router`, standing in for
rmw_zenohd), then `chronav launch SCENE` and, alone against that running system,
`chronav ros bridge SCENE --run RUN --ros-domain 7 --ros-endpoint ...` (first test), or
`chronav launch SCENE --robot ros --ros-domain 7` with CHRONAV_ROS_ENDPOINT (second test).  The client sees chronav's node and topics in the ROS graph (liveliness tokens), receives
/map late (TRANSIENT_LOCAL), /people where the DSR has the people, and sends a /goal_pose: the
robot plans (the /plan ends at the goal, the DSR has the pose mission) and drives there (/odom).
"""

from __future__ import annotations

import datetime as dt
import json
import math
import os
import signal
import subprocess
import sys
from pathlib import Path
from typing import Any
from zoneinfo import ZoneInfo

import pytest

from tests.integration.ros2_client import STORE, Ros2Client, data_key, dds, read_back
from tests.support import REPO_ROOT, ProcessGroup, free_port, wait_until

pytestmark = pytest.mark.slow
SCENE = REPO_ROOT / "tests" / "data" / "ros_lounge.yaml"
DOMAIN = 7
GOAL = (4.8, 3.0, 0.0)


def _dsr(run_dir: Path) -> dict:
    out = subprocess.run([sys.executable, "-m", "tools.cli", "dsr", "dump", "--run", str(run_dir), "--json"],
                         capture_output=True, text=True, timeout=60, cwd=REPO_ROOT, check=False)
    assert out.returncode == 0, out.stderr[-2000:]
    return json.loads(out.stdout)


def _pose_of(doc: dict, name: str) -> tuple[float, float]:
    node = next(n for n in doc["nodes"] if n["name"] == name)
    edge = next(e for e in doc["edges"] if e["dst"] == node["id"] and e["type"] == "RT")
    return edge["attrs"]["x"], edge["attrs"]["y"]


def test_ros_client_sees_the_run_and_drives_the_robot_to_a_goal_pose(tmp_path: Path) -> None:
    port = free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    env = {k: v for k, v in os.environ.items() if not k.startswith("CHRONAV_")}
    group = ProcessGroup()
    client = None
    try:
        launcher = group.spawn(["-m", "tools.cli", "launch", str(SCENE), "--no-record", "--timeout", "240"],
                               env={"CHRONAV_RUNS": str(tmp_path / "runs")}, log_path=tmp_path / "launch.log")
        wait_until(lambda: any((tmp_path / "runs").glob("*/connect.json")), 60, message="the run's connect file")
        run_dir = next((tmp_path / "runs").glob("*/connect.json")).parent
        bridge = group.spawn(["-m", "tools.cli", "ros", "bridge", str(SCENE), "--run", str(run_dir),
                              "--ros-domain", str(DOMAIN), "--ros-endpoint", endpoint],
                             env={"CHRONAV_RUNS": str(tmp_path / "runs")}, log_path=tmp_path / "bridge.log")
        # the ROS side's router comes after the bridge: the bridge waits for it, the run goes on
        wait_until(lambda: "does not answer" in (tmp_path / "bridge.log").read_text(), 180, interval=0.5,
                   message="the bridge noticing the ROS router is missing")
        group.spawn(["-m", "dsr.router", "--listen", endpoint], env=env, log_path=tmp_path / "ros_router.log")
        wait_until(lambda: _listening(port), 30, message="the ROS-side router")
        client = Ros2Client(endpoint, DOMAIN)
        people = client.subscribe("/people", "people_msgs/msg/People")
        plan = client.subscribe("/plan", "nav_msgs/msg/Path")
        odom = client.subscribe("/odom", "nav_msgs/msg/Odometry")
        tf = client.subscribe("/tf", "tf2_msgs/msg/TFMessage")
        scan = client.subscribe("/scan", "sensor_msgs/msg/LaserScan")
        social = client.subscribe("/social_costmap", "nav_msgs/msg/OccupancyGrid", transient_local=True)

        # the ROS graph: chronav's node and its publishers, with type, hash and QoS as rmw_zenoh writes them
        def tokens() -> list[str]:
            return [t for t in client.graph() if t.split("/")[5] in ("NN", "MP", "MS") and
                    t.split("/")[8] == "chronav"]
        wait_until(lambda: any("/MS/" in t and "%goal_pose/" in t for t in tokens()), 180, interval=0.5,
                   message="chronav's publishers and /goal_pose subscription in the ROS graph")
        graph = tokens()
        assert any(t.split("/")[5] == "NN" for t in graph), graph
        map_token = next(t for t in graph if "/MP/" in t and t.split("/")[9] == "%map")
        assert map_token.split("/")[10:] == [dds("nav_msgs/msg/OccupancyGrid"),
                                             STORE.hash_rihs01("nav_msgs/msg/OccupancyGrid"), ":1:,1:,:,:,,"]
        sub_token = next(t for t in graph if "/MS/" in t and t.split("/")[9] == "%goal_pose")
        assert sub_token.split("/")[10] == dds("geometry_msgs/msg/PoseStamped")

        # a late subscriber still gets the map (TRANSIENT_LOCAL): the scene's 6 x 4 m at 0.05 m
        the_map = client.subscribe("/map", "nav_msgs/msg/OccupancyGrid", transient_local=True).wait(timeout=30)
        assert (the_map.info.width, the_map.info.height) == (120, 80)
        assert the_map.info.resolution == pytest.approx(0.05) and the_map.header.frame_id == "map"
        assert len(the_map.data) == 120 * 80 and set(the_map.data.tolist()) <= {0, 100}
        grid = social.wait(timeout=30)
        assert (grid.info.width, grid.info.height) == (120, 80) and max(grid.data) == 100
        assert min(grid.data) >= 0
        info = client.subscribe("/costmap_filter_info", "nav2_msgs/msg/CostmapFilterInfo",
                                transient_local=True).wait(timeout=30)
        assert info.type == 0 and info.filter_mask_topic == "/keepout_filter_mask"
        # stamped with the scene's time of day (10:00 and a little), as every topic (issue 42)
        ten_o_clock = dt.datetime(2026, 11, 25, 10, tzinfo=ZoneInfo("Europe/Madrid")).timestamp()
        assert ten_o_clock <= info.header.stamp.sec <= ten_o_clock + 600, info.header.stamp

        # people where the DSR has them
        msg = people.wait(lambda m: len(m.people) == 2, timeout=60)
        doc = _dsr(run_dir)
        for person in msg.people:
            x, y = _pose_of(doc, person.name)
            assert math.hypot(person.position.x - x, person.position.y - y) < 0.3, person.name
        frames = {t.child_frame_id for t in tf.wait(lambda m: len(m.transforms) >= 4, timeout=30).transforms}
        assert {"odom", "base_link", "person/ana", "person/ben"} <= frames
        laser = scan.wait(timeout=30)
        assert len(laser.ranges) == 91 and laser.header.frame_id == "base_link"

        # a goal from ROS: a pose mission in the DSR, a plan ending at the goal, the robot arriving
        publish_goal = client.publisher("/goal_pose", "geometry_msgs/msg/PoseStamped")
        T = STORE.types
        goal = T["geometry_msgs/msg/PoseStamped"](
            header=T["std_msgs/msg/Header"](stamp=T["builtin_interfaces/msg/Time"](sec=0, nanosec=0), frame_id="map"),
            pose=T["geometry_msgs/msg/Pose"](position=T["geometry_msgs/msg/Point"](x=GOAL[0], y=GOAL[1], z=0.0),
                                             orientation=T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0,
                                                                                           w=1.0)))
        wait_until(publish_goal.matched, 30, message="chronav's /goal_pose subscription matching")
        # bad input first: bytes that are no PoseStamped, a goal in another frame; neither makes a mission
        client.session.put(data_key(DOMAIN, "/goal_pose", "geometry_msgs/msg/PoseStamped"), b"\x00\x01\x00\x00junk")
        wrong = STORE.types["geometry_msgs/msg/PoseStamped"](header=T["std_msgs/msg/Header"](
            stamp=T["builtin_interfaces/msg/Time"](sec=0, nanosec=0), frame_id="odom"), pose=goal.pose)
        publish_goal(wrong)
        publish_goal(goal)
        path = plan.wait(lambda m: len(m.poses) > 1, timeout=60)
        end = path.poses[-1].pose.position
        assert math.hypot(end.x - GOAL[0], end.y - GOAL[1]) < 0.1
        missions = [n for n in _dsr(run_dir)["nodes"] if n["type"] == "mission"]
        assert len(missions) == 1 and missions[0]["attrs"]["goal"].startswith("pose:4.800,3.000")
        odom.wait(lambda m: math.hypot(m.pose.pose.position.x - GOAL[0], m.pose.pose.position.y - GOAL[1]) < 0.3,
                  timeout=120)
        wait_until(lambda: any(n["type"] == "mission" and n["attrs"].get("state") == "done"
                               for n in _dsr(run_dir)["nodes"]), 60, interval=1.0, message="the mission done")
        assert not (people.errors or plan.errors or odom.errors or tf.errors or scan.errors)
        seqs = [a[0] for a in odom.attachments]
        assert seqs == sorted(seqs) and len({a[2] for a in odom.attachments}) == 1
        assert all(len(a[2]) == 16 for a in odom.attachments)

        log = (tmp_path / "bridge.log").read_text()
        assert "[undecodable]" in log and "not a valid geometry_msgs/msg/PoseStamped" in log
        assert "[wrong_frame]" in log and "frame_id 'odom' is not 'map'" in log

        os.killpg(bridge.pid, signal.SIGINT)
        bridge.wait(timeout=60)
        assert not [t for t in client.graph() if t.split("/")[8] == "chronav"], "tokens left after the bridge"
        os.killpg(launcher.pid, signal.SIGINT)
        launcher.wait(timeout=60)

        # the run as a bag: the drive and the people, every message decoding with rosbags and mcap
        bag = tmp_path / "run.mcap"
        done = subprocess.run([sys.executable, "-m", "tools.cli", "export", str(run_dir), "--out", str(bag)],
                              capture_output=True, text=True, timeout=120, cwd=REPO_ROOT, check=False)
        assert done.returncode == 0, done.stderr
        topics = read_back(bag)
        last = topics["/odom"][-1][1].pose.pose.position
        assert math.hypot(last.x - GOAL[0], last.y - GOAL[1]) < 0.3
        assert {p.name for p in topics["/people"][0][1].people} == {"ana", "ben"}
        end = topics["/plan"][-1][1].poses[-1].pose.position   # the plans the navigation adopted
        assert math.hypot(end.x - GOAL[0], end.y - GOAL[1]) < 0.1
    finally:
        if client is not None:
            client.close()
        group.close()


class FakeUnicycle:
    """A ROS 2 robot written with the independent client: integrates /cmd_vel (unicycle), publishes
    /odom (pose in the map frame) and an empty /scan at 20 Hz."""

    def __init__(self, client: Ros2Client, pose: tuple[float, float, float]) -> None:
        import threading

        self.x, self.y, self.theta = pose
        self.cmd = client.subscribe("/cmd_vel", "geometry_msgs/msg/Twist")
        self.odom = client.publisher("/odom", "nav_msgs/msg/Odometry")
        self.scan = client.publisher("/scan", "sensor_msgs/msg/LaserScan")
        self.travelled = 0.0
        self.glitch = threading.Event()   # set: the next two /odom have x = NaN and x = 1e308
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self.run, daemon=True)
        self.thread.start()

    def run(self) -> None:
        import time

        T = STORE.types
        dt = 0.05
        while not self.stop.is_set():
            last = self.cmd.last()
            v, w = (last.linear.x, last.angular.z) if last is not None else (0.0, 0.0)
            self.x += v * math.cos(self.theta) * dt
            self.y += v * math.sin(self.theta) * dt
            self.theta += w * dt
            self.travelled += abs(v) * dt
            now = time.time_ns()
            stamp = T["builtin_interfaces/msg/Time"](sec=now // 10**9, nanosec=now % 10**9)
            header = T["std_msgs/msg/Header"](stamp=stamp, frame_id="odom")
            vec = T["geometry_msgs/msg/Vector3"]
            pose = T["geometry_msgs/msg/Pose"](
                position=T["geometry_msgs/msg/Point"](x=self.x, y=self.y, z=0.0),
                orientation=T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=math.sin(self.theta / 2),
                                                              w=math.cos(self.theta / 2)))
            import numpy as np

            twist = T["geometry_msgs/msg/TwistWithCovariance"](
                twist=T["geometry_msgs/msg/Twist"](linear=vec(x=v, y=0.0, z=0.0), angular=vec(x=0.0, y=0.0, z=w)),
                covariance=np.zeros(36))

            def odometry(pose: Any, header: Any = header, twist: Any = twist) -> Any:
                return T["nav_msgs/msg/Odometry"](
                    header=header, child_frame_id="base_link", twist=twist,
                    pose=T["geometry_msgs/msg/PoseWithCovariance"](pose=pose, covariance=np.zeros(36)))

            if self.glitch.is_set():
                for bad_x in (math.nan, 1e308):
                    self.odom(odometry(T["geometry_msgs/msg/Pose"](
                        position=T["geometry_msgs/msg/Point"](x=bad_x, y=self.y, z=0.0),
                        orientation=pose.orientation)))
                self.glitch.clear()
            self.odom(odometry(pose))
            self.scan(T["sensor_msgs/msg/LaserScan"](
                header=T["std_msgs/msg/Header"](stamp=stamp, frame_id="base_link"), angle_min=-1.57,
                angle_max=1.57, angle_increment=3.14 / 90, time_increment=0.0, scan_time=0.05, range_min=0.05,
                range_max=5.0, ranges=np.full(91, np.inf, dtype=np.float32), intensities=np.zeros(0, np.float32)))
            time.sleep(dt)


def test_a_ros2_robot_is_driven_to_a_goal_pose(tmp_path: Path) -> None:
    port = free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    env = {k: v for k, v in os.environ.items() if not k.startswith("CHRONAV_")}
    group = ProcessGroup()
    client = robot = None
    try:
        group.spawn(["-m", "dsr.router", "--listen", endpoint], env=env, log_path=tmp_path / "ros_router.log")
        wait_until(lambda: _listening(port), 30, message="the ROS-side router")
        client = Ros2Client(endpoint, DOMAIN, node="fake_robot")
        robot = FakeUnicycle(client, (0.8, 1.2, 0.0))
        group.spawn(["-m", "tools.cli", "launch", str(SCENE), "--robot", "ros", "--ros-domain", str(DOMAIN),
                     "--no-record", "--timeout", "240"],
                    env={"CHRONAV_ROS_ENDPOINT": endpoint, "CHRONAV_RUNS": str(tmp_path / "runs")},
                    log_path=tmp_path / "launch.log")
        wait_until(lambda: any((tmp_path / "runs").glob("*/connect.json")), 60, message="the run's connect file")
        run_dir = next((tmp_path / "runs").glob("*/connect.json")).parent
        goal_pub = client.publisher("/goal_pose", "geometry_msgs/msg/PoseStamped")
        wait_until(goal_pub.matched, 180, interval=0.2, message="chronav's /goal_pose subscription")
        info = client.subscribe("/costmap_filter_info", "nav2_msgs/msg/CostmapFilterInfo",
                                transient_local=True).wait(timeout=30)
        ten_o_clock = dt.datetime(2026, 11, 25, 10, tzinfo=ZoneInfo("Europe/Madrid")).timestamp()
        assert ten_o_clock <= info.header.stamp.sec <= ten_o_clock + 600, info.header.stamp   # the scene's time
        # chronav does not publish the robot's own topics in this mode
        assert not [t for t in client.graph() if t.split("/")[8] == "chronav" and "/MP/" in t
                    and t.split("/")[9] in ("%odom", "%scan")]
        T = STORE.types
        bridge_pid = json.loads((run_dir / "pids.json").read_text())["ros_bridge"]

        def goal(x: float, y: float, frame: str = "map") -> Any:
            return T["geometry_msgs/msg/PoseStamped"](
                header=T["std_msgs/msg/Header"](stamp=T["builtin_interfaces/msg/Time"](sec=0, nanosec=0),
                                                frame_id=frame),
                pose=T["geometry_msgs/msg/Pose"](position=T["geometry_msgs/msg/Point"](x=x, y=y, z=0.0),
                                                 orientation=T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0,
                                                                                               w=1.0)))

        # issue 42: what a ROS network may send is refused and counted, and the bridge stays up
        robot.glitch.set()                       # /odom with x = NaN, then x = 1e308, between good ones
        for bad in (goal(1e308, 2.0), goal(2.0, 2.0, frame=""), goal(7.5, 2.0), goal(0.05, 2.0)):
            goal_pub(bad)
        wait_until(lambda: not robot.glitch.is_set(), 10, message="the odometry glitches sent")
        goal_pub(goal(GOAL[0], GOAL[1]))
        wait_until(lambda: any(n["type"] == "mission" and n["attrs"].get("state") in ("done", "failed")
                               for n in _dsr(run_dir)["nodes"]), 150, interval=1.0, message="the mission's end")
        mission = next(n for n in _dsr(run_dir)["nodes"] if n["type"] == "mission")
        assert mission["attrs"]["state"] == "done", mission
        assert math.hypot(robot.x - GOAL[0], robot.y - GOAL[1]) < 0.35, (robot.x, robot.y)
        assert robot.travelled > 3.0 and len(robot.cmd.messages) > 20 and not robot.cmd.errors
        # the DSR holds the ROS robot's pose (the bridge wrote it), not a simulated one
        x, y = _pose_of(_dsr(run_dir), "robot")
        assert math.hypot(x - robot.x, y - robot.y) < 0.3
        assert [n for n in _dsr(run_dir)["nodes"] if n["type"] == "mission"] == [mission]   # refused: no mission
        assert json.loads((run_dir / "pids.json").read_text())["ros_bridge"] == bridge_pid   # never restarted
        stats = subprocess.run([sys.executable, "-m", "tools.cli", "ros", "stats", "--ros-endpoint", endpoint,
                                "--ros-domain", str(DOMAIN), "--json", "--timeout", "20"], capture_output=True,
                               text=True, timeout=60, cwd=REPO_ROOT, check=False)
        assert stats.returncode == 0, stats.stderr
        counts = json.loads(stats.stdout)["topics"]
        assert counts["/goal_pose"]["reasons"] == {"outside_map": 1, "empty_frame": 1, "unreachable": 2}
        assert counts["/goal_pose"]["taken"] == 1
        assert counts["/odom"]["reasons"] == {"not_finite": 1, "outside_map": 1} and counts["/odom"]["taken"] > 100
        kept = subprocess.run([sys.executable, "-m", "tools.cli", "ros", "stats", "--run", str(run_dir), "--json"],
                              capture_output=True, text=True, timeout=60, cwd=REPO_ROOT, check=False)
        assert kept.returncode == 0, kept.stderr       # the run keeps them too (ros_received.json)
        assert json.loads(kept.stdout)["topics"]["/goal_pose"]["reasons"] == counts["/goal_pose"]["reasons"]
    finally:
        if robot is not None:
            robot.stop.set()
            robot.thread.join(timeout=5)
        if client is not None:
            client.close()
        group.close()


def _listening(port: int) -> bool:
    import socket

    with socket.socket() as sock:
        return sock.connect_ex(("127.0.0.1", port)) == 0
