"""The ROS 2 bridge agent: reads the DSR, publishes ROS 2 topics over Zenoh; /goal_pose -> mission.

Why an agent of its own (not code inside the navigation): the bridge is an optional window on
the system, started with ``chronav launch --ros`` or alone against a running system; it talks to
the other agents only through the DSR, like any agent, and to ROS 2 through a second Zenoh
session towards the ROS side's router (rmw_zenohd), so the run's own Zenoh network keeps its
credentials and ACL and ROS nodes never see chronav's graph traffic.

What it publishes (names, frames and QoS in config.py, conventions in wire.py):
``/map`` (the building as the planner rasterises it, without the robot's inflation),
``/social_costmap`` (the navigation's social map of the moment, built from the DSR by the same
``NavigationMaps`` the navigation agent uses, as 0..100 with walls 100), ``/keepout_filter_mask``
+ ``/costmap_filter_info`` (the social layers as ``chronav map export`` writes them),
``/people`` (people_msgs/People), ``/plan`` (the path the navigation adopted), ``/tf``
(map -> odom -> base_link and map -> person/<name>), ``/odom``, ``/scan``, ``/agenda`` (JSON),
``/clock`` (the scene's clock).  Each topic has a wall-clock rate limit and is published only
when what it shows changed.

What it subscribes: ``/goal_pose`` (geometry_msgs/PoseStamped in the map frame) becomes a pose
mission (``mission/ros_goal_<n>``, due now) that the executive plans and runs like any other.
Every received message first goes through inbox.py (size, CDR, the checks of validate.py); a goal
that passes them is still refused when the robot can never stand there (outside the building, in
a wall's or an object's margin: ``RosMaps.goal_problem``), so it never becomes a mission that
fails the run.  Refusals are counted per topic and reason, logged (rate-limited), and published
on ``/diagnostics`` (diagnostic_msgs/DiagnosticArray, 1 Hz); ``chronav ros stats`` reads them.
Nothing a message holds can raise out of the loop: an unexpected error while using one is
counted as ``internal_error``.

``-o robot=ros`` (``chronav launch --robot ros``): the robot is a ROS 2 robot.  The bridge then
does not publish ``/odom``, ``/scan`` and the odom -> base_link transform (the robot does); it
subscribes them and writes the robot's pose (``/odom`` read in the map frame: a robot whose
odometry is not aligned with the map needs a localiser that publishes map poses on that topic),
velocity and laser (resampled to the scene's rays) into the DSR, stamped with the scene clock,
at most ``robot_rate_hz`` times a second; and it publishes the navigation's every command on
``/cmd_vel`` (geometry_msgs/Twist) the moment the command reaches its replica (a DSR signal, not
the loop's period), and a stop when the bridge ends.
"""

from __future__ import annotations

import json
import math
import time
from functools import partial
from typing import Any

import numpy as np

from agents.lib.socialmap.nav2 import KEEPOUT_FILTER_TYPE
from agents.ros_bridge import messages as msgs
from agents.ros_bridge import validate
from agents.ros_bridge.config import BridgeConfig, BridgeConfigError, TopicSpec, config_from_options
from agents.ros_bridge.inbox import GOAL_POSE, ODOM, SCAN, TYPES, Inbox, ReceiveStats
from agents.ros_bridge.maps import Grid, RosMaps
from agents.ros_bridge.wire import RosNode, RosPublisher, fully_qualified, ros_session_config
from agents.runtime.base import Agent
from agents.runtime.checked_graph import CheckedGraph
from agents.runtime.recording import Recorder
from agents.world.dsr_readers import closed_doors, dsr_people
from agents.world.vocabulary import WORLD, EdgeType, MissionState, NodeType, activities, mission_name, now_s
from scenes.clock import format_clock

GOAL_PREFIX = "ros_goal_"
ROBOT_RATE_HZ = 20.0     # DSR writes of the ROS robot's odometry per second (the simulator's is 10)
#: share of one core the bridge may spend rebuilding the social map from the DSR (a 1000 x 600
#: map with 30 people takes ~0.1-0.15 s here: its rate then drops below the configured 5 Hz)
SOCIAL_MAP_CPU_BUDGET = 0.25
RETRY_S = 2.0            # between attempts to reach the ROS side's router
#: with --robot ros, after this long (wall s) without a valid /odom the bridge sends a zero /cmd_vel
#: and forwards no command until odometry returns: the navigation would steer by a frozen pose
ODOM_TIMEOUT_S = 0.5
#: the bridge's received/refused counts in the run directory (rewritten when they change, at most 1/s)
RECEIVED_FILE = "ros_received.json"
ODOM_WAIT_S = 5.0        # wall s after joining the ROS side before a silent robot (--robot ros) is reported


class RosBridgeAgent(Agent):
    kind = "ros_bridge"

    def setup(self, graph: CheckedGraph, recorder: Recorder) -> None:
        self.graph = graph
        self.rec = recorder
        try:
            self.cfg: BridgeConfig = config_from_options(self.config.options)
        except BridgeConfigError as exc:
            raise SystemExit(f"ros_bridge: {exc}") from None
        self.epoch_s = msgs.day_epoch_s(self.scene.clock.date, self.scene.clock.timezone)
        self.maps = RosMaps(self.scene)
        self.scale = self.maps.scale
        self.session: Any = None
        self.node: RosNode | None = None
        self.pubs: dict[str, RosPublisher] = {}
        self._last: dict[str, float] = {}
        self._seen: dict[str, Any] = {}
        self._social_next = -math.inf
        self._retry_at = -math.inf
        self.stats: dict[str, dict[str, float]] = {}
        self.external = self.config.option("robot", "sim") == "ros"
        self._robot_written = -math.inf
        self._odom_written = 0        # inbox.odom_count when the robot was last written
        self._halted = False          # True while /odom is silent: zero /cmd_vel sent, commands held
        self._joined_at = math.inf
        self._last_cmd: Any = None
        frames, topics = self.cfg.frames, self.cfg.topics
        limits = validate.Limits(tuple(self.scene.bounds), frames.map, frames.odom, frames.base,  # type: ignore[arg-type]
                                 frames.laser)
        self.received = ReceiveStats(self.log)
        self.subscribed = {key: fully_qualified(getattr(topics, key).name, self.cfg.namespace)
                           for key in (GOAL_POSE, ODOM, SCAN)}
        self.inbox = Inbox(limits, self.subscribed, self.received)
        self._diagnosed: dict[str, Any] = {"accepted": {}, "refused": {}}
        self._goal_count = sum(1 for n in graph.nodes_of_type(NodeType.MISSION) if n.name.startswith(
            f"mission/{GOAL_PREFIX}"))
        if self.external:
            graph.connect("node_updated", self._on_robot_command)
        self._open_ros()

    def _open_ros(self) -> bool:
        """Join the ROS side; while its router is not there, log it and try again every
        RETRY_S (the run goes on: the bridge is a window, not a part the robot needs)."""
        import zenoh

        try:
            self.node = self._connect()
        except zenoh.ZError:
            self._retry_at = time.monotonic() + RETRY_S
            self.problem = (f"the ROS 2 side does not answer: no Zenoh router at {self.cfg.endpoint} (start "
                            "`ros2 run rmw_zenoh_cpp rmw_zenohd`, or give --ros-endpoint)")
            self.log.warning("the ROS 2 side's Zenoh router at %s does not answer; trying again in %.0f s "
                             "(start it with `ros2 run rmw_zenoh_cpp rmw_zenohd`, or give its endpoint with "
                             "CHRONAV_ROS_ENDPOINT or --ros-endpoint)", self.cfg.endpoint, RETRY_S)
            return False
        self.problem = ""
        self._joined_at = time.monotonic()
        self._declare()
        return True

    def _connect(self) -> RosNode:
        """The Zenoh session towards the ROS side's router, and the ROS node on it (tests replace
        this with a node that records, tests/ros_bridge_harness.py)."""
        import zenoh

        self.session = zenoh.open(ros_session_config(self.cfg.endpoint, self.cfg.mode))
        return RosNode(self.session, self.cfg.node, self.cfg.domain, self.cfg.namespace)

    def _declare(self) -> None:
        """The node's publishers and subscriptions."""
        assert self.node is not None
        topics = self.cfg.topics
        own_robot = () if self.external else ("odom", "scan")
        for key, type_name in (("map", msgs.OCCUPANCY_GRID), ("social_costmap", msgs.OCCUPANCY_GRID),
                               ("keepout_filter_mask", msgs.OCCUPANCY_GRID),
                               ("costmap_filter_info", msgs.COSTMAP_FILTER_INFO), ("people", msgs.PEOPLE),
                               ("plan", msgs.PATH), ("tf", msgs.TF), ("odom", msgs.ODOMETRY),
                               ("scan", msgs.LASER_SCAN), ("agenda", msgs.STRING), ("clock", msgs.CLOCK),
                               ("diagnostics", msgs.DIAGNOSTIC_ARRAY)):
            spec: TopicSpec = getattr(topics, key)
            if spec.enabled and (key not in ("odom", "scan") or key in own_robot):
                self.pubs[key] = self.node.create_publisher(spec.name, type_name, spec.qos.qos())
        if topics.goal_pose.enabled:
            self._subscribe(GOAL_POSE)
        if self.external:
            self._setup_external()
        self.log.info("ROS 2 node /%s on domain %d via %s: %s", self.cfg.node, self.cfg.domain, self.cfg.endpoint,
                      ", ".join(p.topic for p in self.pubs.values()))

    # ------------------------------------------------------------------ --robot ros
    def _setup_external(self) -> None:
        topics = self.cfg.topics
        assert self.node is not None
        self.cmd_pub = self.node.create_publisher(topics.cmd_vel.name, msgs.TWIST, topics.cmd_vel.qos.qos())
        self._subscribe(ODOM)
        self._subscribe(SCAN)

    def _subscribe(self, key: str) -> None:
        """Every payload of subscription ``key`` goes to the inbox (decoded, checked, counted there)."""
        assert self.node is not None
        spec: TopicSpec = getattr(self.cfg.topics, key)
        self.node.create_subscription(spec.name, TYPES[key], spec.qos.qos(), partial(self.inbox.receive, key))

    def _on_robot_command(self, node: Any, *_rest: object) -> None:
        """The navigation's command reached this replica: send it now (the agent's thread)."""
        if node.type != NodeType.ROBOT or self.node is None:
            return
        a = node.attrs
        cmd = (a.get("cmd_stamp"), a.get("cmd_vx"), a.get("cmd_vy"), a.get("cmd_omega"))
        if cmd[0] is None or cmd == self._last_cmd or self._halted:
            return
        self._last_cmd = cmd
        self.cmd_pub.publish(msgs.twist(float(cmd[1] or 0.0), float(cmd[2] or 0.0), float(cmd[3] or 0.0)))

    def _check_odom(self, wall: float) -> None:
        """--robot ros: say so (on the launcher's console) while the ROS robot sends no odometry."""
        if self.inbox.odom is not None:
            self.problem = ""
        elif wall - self._joined_at >= ODOM_WAIT_S:
            self.problem = (f"the ROS 2 robot sends no {self.cfg.topics.odom.name} (waited {wall - self._joined_at:.0f} s "
                            f"on ROS domain {self.cfg.domain} via {self.cfg.endpoint}): is the robot up, on that domain?")

    def _write_robot(self, t_s: float, wall: float) -> None:
        """The ROS robot's latest odometry and scan (checked by the inbox) into the DSR, as the
        simulator would write them."""
        odom, scan, g, count = self.inbox.odom, self.inbox.scan, self.graph, self.inbox.odom_count
        if odom is None or count == self._odom_written or wall - self._robot_written < 1.0 / ROBOT_RATE_HZ:
            return   # nothing new: a pose is written once, so its pose_stamp never makes an old pose look fresh
        robot, world = g.get_node_by_name(self.scene.robot.name), g.get_node_by_name(WORLD)
        if robot is None or world is None:
            return
        attrs: dict[str, Any] = {"pose_stamp": t_s, "v": odom.v, "vy": odom.vy, "omega": odom.omega}
        angles = robot.attrs.get("laser_angles") or []
        if scan is not None and angles:
            attrs["laser_ranges"] = resample_scan(scan, angles, self.scene.robot.laser_range)
        with g.transaction():
            g.insert_or_assign_edge(world.id, robot.id, EdgeType.RT, attrs={"x": odom.x, "y": odom.y, "theta": odom.yaw})
            g.update_node(robot.id, attrs=attrs)
        self._robot_written = wall
        self._odom_written = count

    def _watch_odometry(self, wall: float) -> None:
        """Stop the ROS robot while its odometry is silent (or every message of it refused)."""
        silent_s = wall - self.inbox.odom_at
        if silent_s > ODOM_TIMEOUT_S and not self._halted:
            self._halted = True
            self.cmd_pub.publish(msgs.twist(0.0, 0.0, 0.0))
            self.log.warning("no valid %s %s: zero %s sent, commands held until odometry comes",
                             self.subscribed[ODOM], "yet" if math.isinf(silent_s) else f"for {silent_s:.1f} s",
                             self.cfg.topics.cmd_vel.name)
        elif silent_s <= ODOM_TIMEOUT_S and self._halted:
            self._halted = False
            self._last_cmd = None   # the navigation's current command goes out at its next write
            self.log.info("%s is back: commands go out again", self.subscribed[ODOM])

    # ------------------------------------------------------------------ goals
    def _take_goals(self, t_s: float) -> None:
        """Goals the inbox took become missions, unless the robot can never stand there."""
        goals = self.inbox.take_goals()
        if not goals:
            return
        topic, closed = self.subscribed[GOAL_POSE], tuple(closed_doors(self.graph))
        for goal in goals:
            problem = self.maps.goal_problem(self.graph, goal.x, goal.y, closed)
            if problem is not None:
                self.received.refuse(topic, validate.UNREACHABLE, f"{topic}: goal refused: {problem}")
                self.rec.event(f"{format_clock(t_s)} ROS 2 goal refused: {problem}")
                continue
            self._goal_count += 1
            mission_id = f"{GOAL_PREFIX}{self._goal_count}"
            text = f"pose:{goal.x:.3f},{goal.y:.3f},{goal.yaw:.4f}"
            self.graph.insert_node(type=NodeType.MISSION, name=mission_name(mission_id),
                                   attrs={"mission_id": mission_id, "goal": text, "time_s": t_s,
                                          "state": MissionState.PENDING, "description": "goal from ROS 2 /goal_pose",
                                          "replans": 0})
            self.received.accept(topic)
            self.rec.event(f"{format_clock(t_s)} ROS 2 goal {text} -> mission {mission_id}")
            self.log.info("goal %s -> mission %s", text, mission_id)

    def _guarded(self, key: str, action: Any, *args: Any) -> None:
        """``action(*args)`` on received data; an error it raises is counted on ``key``'s topic as
        internal_error (and logged, rate-limited), never raised out of the loop."""
        try:
            action(*args)
        except Exception as exc:  # noqa: BLE001 - whatever a message held must not end the bridge
            topic = self.subscribed[key]
            self.received.refuse(topic, validate.INTERNAL, f"{topic}: {type(exc).__name__}: {validate.shown(str(exc))}")

    # ------------------------------------------------------------------ loop
    def step(self) -> None:
        if self.node is None and (time.monotonic() < self._retry_at or not self._open_ros()):
            return
        g = self.graph
        t_s = now_s(g)
        if t_s is None or g.get_node_by_name(WORLD) is None:
            return
        self._guarded(GOAL_POSE, self._take_goals, t_s)
        wall = time.monotonic()
        if self.external:
            self._check_odom(wall)
            self._guarded(ODOM, self._write_robot, t_s, wall)
            self._watch_odometry(wall)
        stamp = msgs.ros_time(t_s, self.epoch_s)
        frames = self.cfg.frames
        robot = g.get_node_by_name(self.scene.robot.name)
        self._publish_if("clock", wall, t_s, lambda: msgs.clock(stamp))
        if self._due("map", wall):
            closed = tuple(closed_doors(g))
            self._publish_if("map", wall, closed, lambda: self._map(stamp, closed))
        if "costmap_filter_info" in self.pubs and "costmap_filter_info" not in self._seen:
            self._publish_if("costmap_filter_info", wall, True, lambda: msgs.costmap_filter_info(  # the scene's time
                KEEPOUT_FILTER_TYPE, self.pubs["keepout_filter_mask"].topic if "keepout_filter_mask" in self.pubs
                else self.cfg.topics.keepout_filter_mask.name, self.scale.base, self.scale.multiplier, stamp,
                frames.map))
        if self._due("agenda", wall):
            text = msgs.agenda_json(activities(g))
            self._publish_if("agenda", wall, text, lambda: msgs.string(text))
        if robot is not None:
            self._robot_topics(robot, wall, t_s, stamp)
        people = None
        if self._due("people", wall) or self._due("tf", wall):
            people = dsr_people(g)
        if people is not None:
            key = tuple((p.name, round(p.x, 3), round(p.y, 3)) for p in people)
            self._publish_if("people", wall, (t_s, key), lambda: msgs.people(people, stamp, frames.map))
        if (self._due("social_costmap", wall) or self._due("keepout_filter_mask", wall)) and wall >= self._social_next:
            self._social(wall, t_s, stamp, people)
        if robot is not None and people is not None:
            self._publish_if("tf", wall, (t_s, robot.attrs.get("pose_stamp")), lambda: self._tf(robot, people, stamp))
        if self._due("diagnostics", wall):
            self._publish_if("diagnostics", wall, wall, lambda: self._diagnostics(stamp))

    def _diagnostics(self, stamp: Any) -> Any:
        """What was received and refused since the start, per subscribed topic (ROS's health topic)."""
        now = self.received.snapshot()
        topics = [self.subscribed[GOAL_POSE]] + ([self.subscribed[ODOM], self.subscribed[SCAN]] if self.external else [])
        message = msgs.diagnostics(self.cfg.node, now, self._diagnosed, topics, stamp)
        if now != self._diagnosed:
            self._keep_counts(now)
        self._diagnosed = now
        return message

    def _keep_counts(self, counts: dict[str, Any]) -> None:
        """``<run>/ros_received.json``: the counts as of now, so a finished run keeps them and the
        launcher can show them (replaced atomically; nothing without a run directory)."""
        run_dir = self.config.run_dir
        if run_dir is None:
            return
        tmp = run_dir / f"{RECEIVED_FILE}.tmp"
        try:
            tmp.write_text(json.dumps({"node": self.cfg.node, **counts}, sort_keys=True), encoding="utf-8")
            tmp.replace(run_dir / RECEIVED_FILE)
        except OSError as exc:
            self.log.warning("cannot write %s: %s", run_dir / RECEIVED_FILE, exc)

    def _due(self, key: str, wall: float) -> bool:
        if key not in self.pubs:
            return False
        rate = getattr(self.cfg.topics, key).rate_hz
        return rate is None or wall - self._last.get(key, -math.inf) >= 1.0 / rate

    def _publish_if(self, key: str, wall: float, token: Any, build: Any) -> None:
        """Publish topic ``key`` when its rate allows and ``token`` (what it shows) changed; a
        look that found no change counts against the rate too."""
        if not self._due(key, wall):
            return
        self._last[key] = wall
        if self._seen.get(key, object()) == token:
            return
        started = time.perf_counter()
        size = self.pubs[key].publish(build())
        self._seen[key] = token
        stat = self.stats.setdefault(key, {"count": 0, "bytes": 0, "seconds": 0.0})
        stat["count"] += 1
        stat["bytes"] += size
        stat["seconds"] += time.perf_counter() - started

    def _grid(self, grid: Grid, stamp: Any) -> Any:
        return msgs.occupancy_grid(grid.values, grid.origin, grid.resolution, stamp, self.cfg.frames.map)

    def _map(self, stamp: Any, closed: tuple[str, ...]) -> Any:
        return self._grid(self.maps.building(closed), stamp)

    def _social(self, wall: float, t_s: float, stamp: Any, people: list | None) -> None:
        started = time.process_time()
        costmap, keepout = self.maps.social(self.maps.nav.build(self.graph, t_s))
        self._social_next = wall + (time.process_time() - started) / SOCIAL_MAP_CPU_BUDGET
        self._publish_if("social_costmap", wall, t_s, lambda: self._grid(costmap, stamp))
        self._publish_if("keepout_filter_mask", wall, t_s, lambda: self._grid(keepout, stamp))

    def _robot_topics(self, robot: Any, wall: float, t_s: float, stamp: Any) -> None:
        a, frames = robot.attrs, self.cfg.frames
        try:
            x, y, theta = self.graph.world_pose(robot.id)
        except (LookupError, ValueError):
            return
        pose_stamp = a.get("pose_stamp")
        self._publish_if("odom", wall, pose_stamp, lambda: msgs.odometry(
            x, y, theta, float(a.get("v", 0.0)), float(a.get("vy", 0.0)), float(a.get("omega", 0.0)), stamp,
            frames.odom, frames.base))
        ranges, angles = a.get("laser_ranges"), a.get("laser_angles")
        if ranges and angles and len(ranges) == len(angles):
            self._publish_if("scan", wall, pose_stamp, lambda: msgs.laser_scan(
                ranges, angles, self.scene.robot.laser_range, stamp, frames.laser))
        xs, ys = a.get("path_x") or [], a.get("path_y") or []
        if len(xs) == len(ys) and xs:
            self._publish_if("plan", wall, a.get("planned_s"), lambda: msgs.path(xs, ys, stamp, frames.map))

    def _tf(self, robot: Any, people: list, stamp: Any) -> Any:
        frames = self.cfg.frames
        x, y, theta = self.graph.world_pose(robot.id)
        transforms = [msgs.transform(frames.map, frames.odom, 0.0, 0.0, 0.0, stamp)]
        if not self.external:   # a ROS robot publishes its own odom -> base_link
            transforms.append(msgs.transform(frames.odom, frames.base, x, y, theta, stamp))
        transforms += [msgs.transform(frames.map, f"{frames.person_prefix}{p.name}", p.x, p.y, p.theta, stamp)
                       for p in people]
        return msgs.tf_message(transforms)

    def teardown(self) -> None:
        summary = ", ".join(f"{k} {int(v['count'])} msgs {v['seconds'] * 1000:.0f} ms"
                            for k, v in sorted(self.stats.items()))
        self.log.info("published: %s", summary or "nothing")
        received = self.received.snapshot()
        self.log.info("received: taken %s; refused %s", received["accepted"] or "nothing",
                      received["refused"] or "nothing")
        self._keep_counts(received)
        if self.node is None:
            return
        if self.external:
            self.cmd_pub.publish(msgs.twist(0.0, 0.0, 0.0))   # leave the robot stopped
        self.node.close()
        self.session.close()


def resample_scan(scan: Any, angles: list[float], range_max: float) -> list[float]:
    """A scan's ranges (a LaserScan, or validate.Scan) at the scene's ray angles (nearest ray; no
    return or out of the scan's field of view: ``range_max``, as the simulator's laser reports a ray
    that hits nothing).  REP-117: +inf and NaN are no return, -inf is "too close to measure", so an
    obstacle at the scanner's ``range_min`` (never free space)."""
    ranges = np.asarray(scan.ranges, dtype=float)
    if len(ranges) == 0 or scan.angle_increment == 0:
        return [range_max] * len(angles)
    index = np.rint((np.asarray(angles) - scan.angle_min) / scan.angle_increment).astype(int)
    inside = (index >= 0) & (index < len(ranges))
    picked = np.where(inside, ranges[np.clip(index, 0, len(ranges) - 1)], range_max)
    valid = np.isfinite(picked) & (picked >= scan.range_min) & (picked <= scan.range_max)
    out = np.where(valid, picked, range_max)
    out = np.where(inside & np.isneginf(picked), float(scan.range_min), out)
    return np.minimum(out, range_max).tolist()
