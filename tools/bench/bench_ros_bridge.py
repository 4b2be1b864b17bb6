"""ROS 2 bridge benchmark: prints ONE flat JSON object.

Two measurements, each with a reference taken in the same run (the machine is shared and noisy):

1. **Publishing overhead** (the issue's goal: < 10 % of one core).  This process publishes, as
   the bridge does (agents/ros_bridge: keepout scale, OccupancyGrid, CDR, rmw_zenoh put with
   attachment), a 1000 x 600 social costmap at 5 Hz and 30 people at 10 Hz for ``--seconds``,
   through a Python Zenoh router to a subscriber process that decodes every message;
   ``bridge_publish_cpu_share`` is this process's CPU time over wall time during that phase,
   ``idle_loop_cpu_share`` the same loop with nothing published (reference).
   ``social_map_build_ms_1000x600``: building a social map of that size with 30 people from a
   DSR (NavigationMaps.build, what the live bridge does before publishing, and what the
   navigation agent does anyway) - said separately because it is the navigation's computation,
   not the bridge's publishing.
2. **/cmd_vel latency** (goal: p50 < 5 ms).  A DSR router, the bridge as its own process in
   ``--robot ros`` mode, and this process as the controller (it writes the robot's ``cmd_*`` in
   the DSR, as the navigation agent does) and as the fake robot (a ROS-side Zenoh session
   subscribing ``/cmd_vel``, decoding with rosbags): latency = Twist decoded here minus command
   written here, same clock.  ``zenoh_oneway_p50_ms``: a bare put between two Zenoh sessions of
   this process through the same router (reference).
3. **The live bridge in a run** (``--live-seconds``, 0 skips it): ``chronav launch center_day --ros``
   (26 people, 520 x 200 grid) towards an otherwise idle ROS router; after a warm-up, the CPU
   share of the ros_bridge process over that time, beside the social_navigation agent's
   (reference: the agent that builds the same maps to plan), from the processes' CPU times.
4. **A flood of bad messages** (``--flood-s``, default 60, 0 skips; ``--only-flood`` runs this
   alone): ``chronav launch ros_lounge --robot ros`` with a fake ROS robot here (integrates
   /cmd_vel, publishes /odom and /scan at 20 Hz), while this process puts ``--flood-rate``
   (10,000) bad messages a second on /odom, /scan and /goal_pose (NaN and 1e308 poses, NaN scan
   angles, ranges of 3e38, empty frames, cut CDR, random bytes).  ``flood_cpu_share``: the
   ros_bridge process's CPU time over the flood's wall time; ``flood_bridge_restarts``: its pid
   changes (0 expected); ``flood_refused``: the refusals its /diagnostics counted meanwhile; then
   a valid /goal_pose: ``flood_goal_completed`` (the fake robot within 0.35 m of it) and
   ``flood_goal_s`` (wall seconds to get there).
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import statistics
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np

REPO = Path(__file__).resolve().parents[2]
SCENE = REPO / "scenes" / "icra_usecase.yaml"


def _router(port: int) -> subprocess.Popen[bytes]:
    env = {k: v for k, v in os.environ.items() if not k.startswith("CHRONAV_")}
    proc = subprocess.Popen([sys.executable, "-m", "dsr.router", "--listen", f"tcp/127.0.0.1:{port}"], cwd=REPO,
                            env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    from tools.ports import wait_for_port

    if not wait_for_port(port, 15):
        proc.kill()
        raise SystemExit("bench_ros_bridge: the Zenoh router did not start")
    return proc


def _stop(proc: subprocess.Popen[bytes]) -> None:
    if proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(timeout=10)


def stop_launcher(launcher: subprocess.Popen[bytes], grace_s: float = 120.0) -> None:
    """Stop a `chronav launch` started in its own session: Ctrl-C first (it stops its agents and
    merges the run), its whole process group killed if it has not ended within ``grace_s``."""
    if launcher.poll() is None:
        os.killpg(launcher.pid, signal.SIGINT)
        try:
            launcher.wait(timeout=grace_s)
        except subprocess.TimeoutExpired:
            os.killpg(launcher.pid, signal.SIGKILL)
            launcher.wait(timeout=10)


def _session(endpoint: str) -> Any:
    from agents.ros_bridge.wire import ros_session_config
    import zenoh

    return zenoh.open(ros_session_config(endpoint))


# ------------------------------------------------------------------ 1. publishing overhead
def subscriber_main(endpoint: str, domain: int, seconds: float) -> None:
    """The fake RViz: decodes every costmap and people message, prints the counts."""
    from agents.ros_bridge.types import deserialize
    from agents.ros_bridge.wire import topic_key

    counts = {"costmap": 0, "people": 0}
    session = _session(endpoint)
    try:
        def on(kind: str, type_name: str) -> Any:
            def cb(sample: Any) -> None:
                deserialize(sample.payload.to_bytes(), type_name)
                counts[kind] += 1
            return cb
        session.declare_subscriber(topic_key(domain, "/social_costmap", "nav_msgs/msg/OccupancyGrid"),
                                   on("costmap", "nav_msgs/msg/OccupancyGrid"))
        session.declare_subscriber(topic_key(domain, "/people", "people_msgs/msg/People"),
                                   on("people", "people_msgs/msg/People"))
        print("ready", flush=True)
        time.sleep(seconds)
    finally:
        session.close()
    print(json.dumps(counts), flush=True)


def _people(n: int, rng: np.random.Generator) -> list[Any]:
    from types import SimpleNamespace

    return [SimpleNamespace(name=f"p{i}", role="resident", x=float(rng.uniform(0, 50)), y=float(rng.uniform(0, 30)),
                            theta=0.0, vx=0.3, vy=0.0, interacting_with=()) for i in range(n)]


def publishing(endpoint: str, seconds: float, publish: bool) -> dict[str, float]:
    from agents.lib.socialmap.nav2 import MaskScale, keepout_values
    from agents.lib.socialmap.social_map import SocialMapParams
    from agents.ros_bridge import messages as msgs
    from agents.ros_bridge.config import Topics
    from agents.ros_bridge.wire import RosNode

    rng = np.random.default_rng(1)
    costs = rng.choice([1.0, 1.5, 2.5, 4.0, np.inf], size=(600, 1000), p=[0.7, 0.1, 0.1, 0.05, 0.05])
    people = _people(30, rng)
    scale = MaskScale.for_params(SocialMapParams())
    topics = Topics()
    session = _session(endpoint)
    node = RosNode(session, "bench", domain=3)
    grid_pub = node.create_publisher("/social_costmap", msgs.OCCUPANCY_GRID, topics.social_costmap.qos.qos())
    people_pub = node.create_publisher("/people", msgs.PEOPLE, topics.people.qos.qos())
    time.sleep(1.0)   # let the subscriber's declarations arrive
    sent = {"costmap": 0, "people": 0}
    start_wall, start_cpu = time.monotonic(), time.process_time()
    next_grid = next_people = start_wall
    t = 0.0
    try:
        while (now := time.monotonic()) - start_wall < seconds:
            stamp = msgs.ros_time(t)
            if now >= next_grid:
                next_grid += 0.2
                if publish:
                    grid_pub.publish(msgs.occupancy_grid(keepout_values(costs, scale), (0.0, 0.0), 0.05, stamp, "map"))
                    sent["costmap"] += 1
            if now >= next_people:
                next_people += 0.1
                if publish:
                    people_pub.publish(msgs.people(people, stamp, "map"))
                    sent["people"] += 1
            t += 0.01
            time.sleep(max(0.0, min(next_grid, next_people) - time.monotonic()))
        wall, cpu = time.monotonic() - start_wall, time.process_time() - start_cpu
    finally:
        node.close()
        session.close()
    return {"cpu_share": cpu / wall, **{f"sent_{k}": v for k, v in sent.items()}}


def social_map_build_ms() -> float:
    """A 1000 x 600 social map with 30 people built from a DSR, as the bridge does each 0.2 s."""
    from agents.world.navigation import NavigationMaps
    from agents.world.offline import graph_at
    from agents.world.vocabulary import EdgeType, NodeType
    from agents.world.scene_world import load_world
    from dsr import DSRGraph

    world = load_world(SCENE)
    scene = world.scene.model_copy(update={"walls": [[[0, 0], [50, 0], [50, 30], [0, 30], [0, 0]]],
                                           "rooms": [world.scene.rooms[0].model_copy(
                                               update={"polygon": [[0, 0], [50, 0], [50, 30], [0, 30]]})],
                                           "resolution": 0.05})
    maps = NavigationMaps.for_scene(scene)
    graph: DSRGraph = graph_at(world, world.scene.clock.start_s)
    rng = np.random.default_rng(2)
    world_node = graph.require_node("world")
    for i in range(30):
        node = graph.insert_node(NodeType.PERSON, f"bench_{i}", {"role": "resident", "vx": 0.2, "vy": 0.0})
        graph.insert_or_assign_edge(world_node.id, node.id, EdgeType.RT, {"x": float(rng.uniform(2, 48)),
                                                                  "y": float(rng.uniform(2, 28)), "theta": 0.0})
    t_s = world.scene.clock.start_s
    _ = maps.build(graph, t_s).cost   # warm-up: numba compilation, static map
    times = []
    for _ in range(5):
        started = time.perf_counter()
        smap = maps.build(graph, t_s)
        _ = smap.cost   # the lazy cost grid is what the bridge publishes: time it too
        times.append((time.perf_counter() - started) * 1000)
    assert smap.spec.shape == (600, 1000), smap.spec.shape
    return statistics.median(times)


# ------------------------------------------------------------------ 2. /cmd_vel latency
def latency(endpoint: str, samples: int) -> dict[str, float]:
    from agents.ros_bridge.types import deserialize
    from agents.ros_bridge.wire import topic_key
    from agents.world.dsr_writers import write_building, write_clock, write_robot
    from agents.world.scene_world import load_world
    from dsr import ZenohSettings, join

    world = load_world(SCENE)
    scene = world.scene
    graph_name = "bench_ros"
    settings = ZenohSettings(connect=[endpoint])
    env = {k: v for k, v in os.environ.items() if not k.startswith("CHRONAV_")}
    env.update({"CHRONAV_ZENOH_CONNECT": endpoint, "CHRONAV_ZENOH_MODE": "client", "CHRONAV_GRAPH": graph_name,
                "CHRONAV_WRITE_POLICY": "allow-all", "RERUN": "off", "CHRONAV_ROS_ENDPOINT": endpoint})
    received: dict[int, float] = {}
    got = threading.Condition()

    def on_twist(sample: Any) -> None:
        msg = deserialize(sample.payload.to_bytes(), "geometry_msgs/msg/Twist")
        with got:
            received[int(round(msg.linear.x * 1e4))] = time.perf_counter()
            got.notify_all()

    ros = _session(endpoint)
    bridge = None
    try:
        ros.declare_subscriber(topic_key(0, "/cmd_vel", "geometry_msgs/msg/Twist"), on_twist)
        # reference: a bare put between two sessions of this process through the same router
        probe_times: dict[int, float] = {}
        ev = threading.Event()

        def on_probe(sample: Any) -> None:
            probe_times[int(sample.payload.to_string())] = time.perf_counter()
            ev.set()
        ros.declare_subscriber("bench/probe", on_probe)
        other = _session(endpoint)
        pub = other.declare_publisher("bench/probe", express=True)
        time.sleep(0.5)
        bare = []
        for i in range(samples):
            ev.clear()
            sent = time.perf_counter()
            pub.put(str(i))
            ev.wait(2)
            if i in probe_times:
                bare.append((probe_times[i] - sent) * 1000)
            time.sleep(0.01)
        other.close()
        with join("bench_controller", graph=graph_name, settings=settings) as graph:
            write_building(graph, scene, {})
            write_clock(graph, scene, scene.clock.start_s, 1.0)
            robot = write_robot(graph, scene.robot, (scene.robot.pose.x, scene.robot.pose.y, 0.0), None, [0.0])
            bridge = subprocess.Popen([sys.executable, "-m", "agents.ros_bridge", "--scene", str(SCENE),
                                       "--graph", graph_name, "-o", "robot=ros", "-o", "ros_domain=0"], cwd=REPO,
                                      env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                                      start_new_session=True)
            lat: list[float] = []
            deadline = time.monotonic() + 120
            i = 0
            while len(lat) < samples and time.monotonic() < deadline:
                i += 1
                sent = time.perf_counter()
                graph.update_node(robot.id, {"cmd_vx": i * 1e-4, "cmd_vy": 0.0, "cmd_omega": 0.0,
                                             "cmd_stamp": float(i)})
                with got:
                    got.wait_for(lambda: i in received, timeout=1.0)  # noqa: B023 - called within this iteration
                if i in received:
                    lat.append((received[i] - sent) * 1000)
                graph.dispatch(timeout=0.02)
            if not lat:
                raise SystemExit("bench_ros_bridge: no /cmd_vel arrived; bridge stderr:\n"
                                 + (bridge.stderr.read().decode()[-2000:] if bridge.poll() is not None and bridge.stderr else ""))
    finally:
        if bridge is not None:
            _stop(bridge)
        ros.close()
    lat.sort()
    bare.sort()
    return {"cmd_vel_latency_p50_ms": statistics.median(lat), "cmd_vel_latency_p90_ms": lat[int(0.9 * len(lat))],
            "cmd_vel_samples": len(lat), "zenoh_oneway_p50_ms": statistics.median(bare)}


BRIDGE_READY_LINE = "ROS 2 node"   # what the ros_bridge logs once its node is declared on the ROS side


def wait_for_bridge(runs: Path, timeout_s: float, poll_s: float = 1.0) -> dict[str, int]:
    """The pids of a launch under ``runs`` (``<run>/pids.json``, agent name -> pid) once the
    ros_bridge has one and its log (``<run>/logs/ros_bridge.log``) says its ROS 2 node is up.
    TimeoutError, naming what was missing, if that takes more than ``timeout_s``."""
    deadline = time.monotonic() + timeout_s
    pids: dict[str, int] = {}
    while True:
        for path in runs.glob("*/pids.json"):   # written whole (tools/launch.write_pids renames it in place)
            pids = json.loads(path.read_text())
        log = next(runs.glob("*/logs/ros_bridge.log"), None)
        if pids.get("ros_bridge") and log is not None and BRIDGE_READY_LINE in log.read_text(errors="replace"):
            return pids
        if time.monotonic() >= deadline:
            missing = ("no ros_bridge pid in a pids.json" if not pids.get("ros_bridge") else
                       f"no {BRIDGE_READY_LINE!r} line in ros_bridge.log")
            raise TimeoutError(f"bench_ros_bridge: the launch under {runs} did not start its bridge within "
                               f"{timeout_s:g} s ({missing})")
        time.sleep(poll_s)


def live(endpoint: str, seconds: float, scene: str = "center_day") -> dict[str, float]:
    import tempfile

    import psutil

    with tempfile.TemporaryDirectory() as runs:
        env = {k: v for k, v in os.environ.items() if not k.startswith("CHRONAV_")}
        env.update({"CHRONAV_ROS_ENDPOINT": endpoint, "CHRONAV_RUNS": runs, "RERUN": "off"})
        launcher = subprocess.Popen([sys.executable, "-m", "tools.cli", "launch", scene, "--ros", "--ros-domain", "5",
                                     "--no-record", "--timeout", str(seconds + 240)], cwd=REPO, env=env,
                                    stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
        try:
            pids = wait_for_bridge(Path(runs), timeout_s=180)
            time.sleep(10.0)   # warm-up: numba compilation, first maps
            procs = {name: psutil.Process(pids[name]) for name in ("ros_bridge", "social_navigation")}
            before = {name: sum(p.cpu_times()[:2]) for name, p in procs.items()}
            started = time.monotonic()
            time.sleep(seconds)
            wall = time.monotonic() - started
            after = {name: sum(p.cpu_times()[:2]) for name, p in procs.items()}
        finally:
            stop_launcher(launcher)
    return {f"live_{name}_cpu_share_{scene}": round((after[name] - before[name]) / wall, 4) for name in procs}


# ------------------------------------------------------------------ 4. flood of bad messages
FLOOD_SCENE = REPO / "tests" / "data" / "ros_lounge.yaml"
FLOOD_GOAL = (4.8, 3.0)


def _bad_payloads(count: int) -> list[tuple[str, bytes]]:
    """(topic, CDR) of bad messages of every kind the bridge refuses, built once (the flood must
    cost this process little)."""
    import math

    from agents.ros_bridge import messages as msgs
    from agents.ros_bridge.types import msg_class, serialize

    rng = np.random.default_rng(3)
    stamp = msgs.ros_time(time.time())
    angles = list(np.linspace(-1.57, 1.57, 91))
    out: list[tuple[str, bytes]] = []
    for i in range(count):
        kind = i % 8
        if kind == 0:
            m = msgs.odometry(math.nan, 1.0, 0.0, 0.0, 0.0, 0.0, stamp, "odom", "base_link")
            out.append(("/odom", serialize(m, msgs.ODOMETRY)))
        elif kind == 1:
            m = msgs.odometry(1e308, 1.0, 0.0, 0.0, 0.0, 0.0, stamp, "odom", "base_link")
            out.append(("/odom", serialize(m, msgs.ODOMETRY)))
        elif kind == 2:
            g = msg_class(msgs.POSE_STAMPED)(header=msgs.header(stamp, "map"), pose=msgs.pose(1e308, 2.0, 0.0))
            out.append(("/goal_pose", serialize(g, msgs.POSE_STAMPED)))
        elif kind == 3:
            g = msg_class(msgs.POSE_STAMPED)(header=msgs.header(stamp, ""), pose=msgs.pose(2.0, 2.0, 0.0))
            out.append(("/goal_pose", serialize(g, msgs.POSE_STAMPED)))
        elif kind == 4:
            sc = msgs.laser_scan([1.0] * 91, angles, 5.0, stamp, "base_link")
            sc.angle_min = math.nan
            out.append(("/scan", serialize(sc, msgs.LASER_SCAN)))
        elif kind == 5:
            sc = msgs.laser_scan([1.0] * 91, angles, 5.0, stamp, "base_link")
            sc.ranges = np.full(91, 3e38, dtype=np.float32)
            out.append(("/scan", serialize(sc, msgs.LASER_SCAN)))
        elif kind == 6:
            data = serialize(msgs.odometry(1.0, 1.0, 0.0, 0.0, 0.0, 0.0, stamp, "odom", "base_link"), msgs.ODOMETRY)
            out.append(("/odom", data[: int(rng.integers(0, len(data)))]))
        else:
            out.append((("/odom", "/scan", "/goal_pose")[i % 3], rng.bytes(int(rng.integers(0, 200)))))
    return out


class _FakeRobot:
    """A ROS 2 robot on the ROS side: integrates /cmd_vel (unicycle), publishes /odom (map frame)
    and a scan with no returns at 20 Hz, from a thread of this process."""

    def __init__(self, session: Any, domain: int, pose: tuple[float, float, float]) -> None:
        from agents.ros_bridge import messages as msgs
        from agents.ros_bridge.types import deserialize
        from agents.ros_bridge.wire import Qos, RosNode

        self.x, self.y, self.theta = pose
        self.cmd = (0.0, 0.0)
        self.node = RosNode(session, "fake_robot", domain)
        self.odom = self.node.create_publisher("/odom", msgs.ODOMETRY, Qos())
        self.scan = self.node.create_publisher("/scan", msgs.LASER_SCAN, Qos("best_effort", depth=5))

        def on_cmd(data: bytes) -> None:
            twist = deserialize(data, msgs.TWIST)
            self.cmd = (float(twist.linear.x), float(twist.angular.z))

        self.node.create_subscription("/cmd_vel", msgs.TWIST, Qos(), on_cmd)
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self) -> None:
        import math

        from agents.ros_bridge import messages as msgs

        angles = list(np.linspace(-1.57, 1.57, 91))
        dt = 0.05
        while not self.stop.wait(dt):
            v, w = self.cmd
            self.x += v * math.cos(self.theta) * dt
            self.y += v * math.sin(self.theta) * dt
            self.theta += w * dt
            stamp = msgs.ros_time(time.time())
            self.odom.publish(msgs.odometry(self.x, self.y, self.theta, v, 0.0, w, stamp, "odom", "base_link"))
            self.scan.publish(msgs.laser_scan([10.0] * 91, angles, 5.0, stamp, "base_link"))

    def close(self) -> None:
        self.stop.set()
        self.thread.join(timeout=5)
        self.node.close()


def flood(endpoint: str, seconds: float, rate: float) -> dict[str, Any]:
    import math
    import tempfile

    import psutil

    from agents.ros_bridge import messages as msgs
    from agents.ros_bridge.types import deserialize, msg_class, type_hash
    from agents.ros_bridge.wire import Qos, RosNode, topic_key
    from tools.ros.stats import counts_of

    domain = 6
    payloads = _bad_payloads(64)
    types = {"/odom": msgs.ODOMETRY, "/scan": msgs.LASER_SCAN, "/goal_pose": msgs.POSE_STAMPED}
    assert all(type_hash(t) for t in types.values())
    ros = _session(endpoint)
    robot = _FakeRobot(ros, domain, (0.8, 1.2, 0.0))
    refused = {"value": 0}

    def on_diagnostics(data: bytes) -> None:
        counts = counts_of(deserialize(data, msgs.DIAGNOSTIC_ARRAY), "chronav")
        refused["value"] = sum(row["refused"] for row in counts.values())

    watcher = RosNode(ros, "bench_watch", domain)
    watcher.create_subscription("/diagnostics", msgs.DIAGNOSTIC_ARRAY, Qos(), on_diagnostics)
    import zenoh

    pubs = {t: ros.declare_publisher(topic_key(domain, t, types[t]), congestion_control=zenoh.CongestionControl.DROP)
            for t in types}
    out: dict[str, Any] = {}
    with tempfile.TemporaryDirectory() as runs:
        env = {k: v for k, v in os.environ.items() if not k.startswith("CHRONAV_")}
        env.update({"CHRONAV_ROS_ENDPOINT": endpoint, "CHRONAV_RUNS": runs, "RERUN": "off"})
        launcher = subprocess.Popen([sys.executable, "-m", "tools.cli", "launch", str(FLOOD_SCENE), "--robot", "ros",
                                     "--ros-domain", str(domain), "--no-record", "--timeout", str(seconds + 400)],
                                    cwd=REPO, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                    start_new_session=True)
        try:
            pids = wait_for_bridge(Path(runs), timeout_s=240)
            time.sleep(5.0)   # warm-up
            bridge = psutil.Process(pids["ros_bridge"])
            refused_before = refused["value"]
            cpu_before = sum(bridge.cpu_times()[:2])
            started = time.monotonic()
            sent = 0
            batch = max(1, int(rate / 100))
            next_at = started
            while time.monotonic() - started < seconds:
                for _ in range(batch):
                    topic, data = payloads[sent % len(payloads)]
                    pubs[topic].put(data)
                    sent += 1
                next_at += batch / rate
                time.sleep(max(0.0, next_at - time.monotonic()))
            wall = time.monotonic() - started
            cpu = sum(bridge.cpu_times()[:2]) - cpu_before
            time.sleep(2.0)   # the last /diagnostics of the flood
            pids_after = json.loads(next(Path(runs).glob("*/pids.json")).read_text())
            out.update({"flood_s": round(wall, 1), "flood_sent": sent, "flood_rate_msgs_per_s": round(sent / wall),
                        "flood_cpu_share": round(cpu / wall, 4), "flood_bridge_alive": bridge.is_running(),
                        "flood_bridge_restarts": int(pids_after.get("ros_bridge") != pids["ros_bridge"]),
                        "flood_refused": refused["value"] - refused_before})
            # then a goal: the fake robot must get there
            goal_pub = ros.declare_publisher(topic_key(domain, "/goal_pose", msgs.POSE_STAMPED))
            goal = msg_class(msgs.POSE_STAMPED)(header=msgs.header(msgs.ros_time(time.time()), "map"),
                                                pose=msgs.pose(FLOOD_GOAL[0], FLOOD_GOAL[1], 0.0))
            from agents.ros_bridge.types import serialize

            goal_started = time.monotonic()
            goal_pub.put(serialize(goal, msgs.POSE_STAMPED))
            reached = False
            while time.monotonic() - goal_started < 120:
                if math.hypot(robot.x - FLOOD_GOAL[0], robot.y - FLOOD_GOAL[1]) < 0.35:
                    reached = True
                    break
                time.sleep(0.2)
            out.update({"flood_goal_completed": reached, "flood_goal_s": round(time.monotonic() - goal_started, 1)})
        finally:
            stop_launcher(launcher)
            robot.close()
            watcher.close()
            ros.close()
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--samples", type=int, default=200)
    parser.add_argument("--live-seconds", type=float, default=30.0, help="0: skip the live run")
    parser.add_argument("--flood-s", type=float, default=60.0, help="seconds of bad messages (0: skip)")
    parser.add_argument("--flood-rate", type=float, default=10_000.0, help="bad messages a second")
    parser.add_argument("--only-flood", action="store_true", help="run the flood phase alone")
    parser.add_argument("--subscriber", nargs=3, metavar=("ENDPOINT", "DOMAIN", "SECONDS"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.subscriber:
        subscriber_main(args.subscriber[0], int(args.subscriber[1]), float(args.subscriber[2]))
        return
    from tools.ports import free_port

    port = free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    router = _router(port)
    out: dict[str, Any] = {}
    if args.only_flood:
        try:
            out.update(flood(endpoint, args.flood_s, args.flood_rate))
        finally:
            _stop(router)
        print(json.dumps(out))
        return
    try:
        sub = subprocess.Popen([sys.executable, "-m", "tools.bench.bench_ros_bridge", "--subscriber", endpoint, "3",
                                str(args.seconds + 3)], cwd=REPO, stdout=subprocess.PIPE, start_new_session=True)
        try:
            assert sub.stdout is not None and sub.stdout.readline().strip() == b"ready"
            pub = publishing(endpoint, args.seconds, publish=True)
            idle = publishing(endpoint, min(args.seconds, 5.0), publish=False)
            counts = json.loads(sub.communicate(timeout=60)[0].decode().strip().splitlines()[-1])
        finally:
            _stop(sub)
        out.update({"bridge_publish_cpu_share": round(pub["cpu_share"], 4),
                    "idle_loop_cpu_share": round(idle["cpu_share"], 4),
                    "costmap_1000x600_sent": pub["sent_costmap"], "costmap_1000x600_received": counts["costmap"],
                    "people_30_sent": pub["sent_people"], "people_30_received": counts["people"],
                    "social_map_build_ms_1000x600": round(social_map_build_ms(), 1)})
        out.update({k: round(v, 3) if isinstance(v, float) else v
                    for k, v in latency(endpoint, args.samples).items()})
        if args.live_seconds > 0:
            out.update(live(endpoint, args.live_seconds))
        if args.flood_s > 0:
            out.update(flood(endpoint, args.flood_s, args.flood_rate))
    finally:
        _stop(router)
    print(json.dumps(out))


if __name__ == "__main__":
    main()
