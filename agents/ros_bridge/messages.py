"""chronav's world as ROS 2 messages (and back): pure functions over plain values.

Why separate from the agent: the live bridge and ``chronav export --format mcap`` build the same
messages from the same values (one definition of "the robot's odometry as ROS sees it"), and the
conversions are testable without Zenoh.  Time: ROS stamps are the scene's clock, i.e. the scene's
date at midnight in its timezone plus the sim seconds of the day, so a bag or an RViz session
shows the centre's own time.
"""

from __future__ import annotations

import datetime as dt
import json
import math
from collections.abc import Iterable, Sequence
from typing import Any
from zoneinfo import ZoneInfo

import numpy as np

from agents.ros_bridge.types import msg_class

OCCUPANCY_GRID = "nav_msgs/msg/OccupancyGrid"
COSTMAP_FILTER_INFO = "nav2_msgs/msg/CostmapFilterInfo"
PEOPLE = "people_msgs/msg/People"
PATH = "nav_msgs/msg/Path"
TF = "tf2_msgs/msg/TFMessage"
ODOMETRY = "nav_msgs/msg/Odometry"
LASER_SCAN = "sensor_msgs/msg/LaserScan"
STRING = "std_msgs/msg/String"
CLOCK = "rosgraph_msgs/msg/Clock"
POSE_STAMPED = "geometry_msgs/msg/PoseStamped"
TWIST = "geometry_msgs/msg/Twist"
DIAGNOSTIC_ARRAY = "diagnostic_msgs/msg/DiagnosticArray"
#: diagnostic_msgs/DiagnosticStatus levels
DIAGNOSTIC_OK, DIAGNOSTIC_WARN = 0, 1


def day_epoch_s(date: dt.date, timezone: str) -> float:
    """UNIX time of the scene's midnight: sim second ``t`` of the day is ``day_epoch_s + t``."""
    return dt.datetime.combine(date, dt.time(0, 0), tzinfo=ZoneInfo(timezone)).timestamp()


def ros_time(t_s: float, epoch_s: float = 0.0) -> Any:
    whole = math.floor(epoch_s)   # in integer parts: a float of 1.8e18 ns has 256 ns steps
    total_ns = whole * 1_000_000_000 + round((epoch_s - whole) * 1e9) + round(t_s * 1e9)
    return msg_class("builtin_interfaces/msg/Time")(sec=total_ns // 1_000_000_000, nanosec=total_ns % 1_000_000_000)


def seconds_of(stamp: Any, epoch_s: float = 0.0) -> float:
    return stamp.sec + stamp.nanosec * 1e-9 - epoch_s


def header(stamp: Any, frame_id: str) -> Any:
    return msg_class("std_msgs/msg/Header")(stamp=stamp, frame_id=frame_id)


def quaternion(yaw: float) -> Any:
    return msg_class("geometry_msgs/msg/Quaternion")(x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2))


def yaw_of(q: Any) -> float:
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def point(x: float, y: float, z: float = 0.0) -> Any:
    return msg_class("geometry_msgs/msg/Point")(x=float(x), y=float(y), z=float(z))


def vector3(x: float, y: float, z: float = 0.0) -> Any:
    return msg_class("geometry_msgs/msg/Vector3")(x=float(x), y=float(y), z=float(z))


def pose(x: float, y: float, yaw: float) -> Any:
    return msg_class("geometry_msgs/msg/Pose")(position=point(x, y), orientation=quaternion(yaw))


def occupancy_grid(values: np.ndarray, origin_xy: tuple[float, float], resolution: float, stamp: Any,
                   frame_id: str) -> Any:
    """An OccupancyGrid of ``values`` (rows along +y from the origin, columns along +x; int8 with
    0..100 occupancy or cost, -1 unknown), as map_server and Nav2's costmaps publish."""
    grid = np.ascontiguousarray(values, dtype=np.int8)
    rows, cols = grid.shape
    info = msg_class("nav_msgs/msg/MapMetaData")(map_load_time=stamp, resolution=float(resolution), width=cols,
                                                 height=rows, origin=pose(origin_xy[0], origin_xy[1], 0.0))
    return msg_class(OCCUPANCY_GRID)(header=header(stamp, frame_id), info=info, data=grid.reshape(-1))


def costmap_filter_info(filter_type: int, mask_topic: str, base: float, multiplier: float, stamp: Any,
                        frame_id: str) -> Any:
    return msg_class(COSTMAP_FILTER_INFO)(header=header(stamp, frame_id), type=filter_type,
                                          filter_mask_topic=mask_topic, base=float(base),
                                          multiplier=float(multiplier))


def people(persons: Iterable[Any], stamp: Any, frame_id: str) -> Any:
    """people_msgs/People: name, position, velocity (m/s in the map frame), reliability 1 (tracked),
    the role and group as tags."""
    person_cls = msg_class("people_msgs/msg/Person")
    out = []
    for p in persons:
        tagnames, tags = ["role"], [str(getattr(p, "role", ""))]
        if getattr(p, "interacting_with", ()):
            tagnames.append("interacting_with")
            tags.append(",".join(p.interacting_with))
        out.append(person_cls(name=p.name, position=point(p.x, p.y), velocity=point(p.vx, p.vy), reliability=1.0,
                              tagnames=tagnames, tags=tags))
    return msg_class(PEOPLE)(header=header(stamp, frame_id), people=out)


def path(xs: Sequence[float], ys: Sequence[float], stamp: Any, frame_id: str) -> Any:
    """nav_msgs/Path through the points, each pose heading to the next (the last keeps the previous heading)."""
    poses = []
    yaw = 0.0
    for i, (x, y) in enumerate(zip(xs, ys, strict=True)):
        if i + 1 < len(xs):
            yaw = math.atan2(ys[i + 1] - y, xs[i + 1] - x)
        poses.append(msg_class(POSE_STAMPED)(header=header(stamp, frame_id), pose=pose(x, y, yaw)))
    return msg_class(PATH)(header=header(stamp, frame_id), poses=poses)


def transform(parent: str, child: str, x: float, y: float, yaw: float, stamp: Any) -> Any:
    tf = msg_class("geometry_msgs/msg/Transform")(translation=vector3(x, y), rotation=quaternion(yaw))
    return msg_class("geometry_msgs/msg/TransformStamped")(header=header(stamp, parent), child_frame_id=child,
                                                           transform=tf)


def tf_message(transforms: Iterable[Any]) -> Any:
    return msg_class(TF)(transforms=list(transforms))


def odometry(x: float, y: float, yaw: float, vx: float, vy: float, omega: float, stamp: Any, odom_frame: str,
             base_frame: str) -> Any:
    """nav_msgs/Odometry: pose in the odom frame, twist in the base frame (REP-105)."""
    cov = np.zeros(36, dtype=np.float64)
    pwc = msg_class("geometry_msgs/msg/PoseWithCovariance")(pose=pose(x, y, yaw), covariance=cov)
    twist = msg_class(TWIST)(linear=vector3(vx, vy), angular=vector3(0.0, 0.0, omega))
    twc = msg_class("geometry_msgs/msg/TwistWithCovariance")(twist=twist, covariance=cov.copy())
    return msg_class(ODOMETRY)(header=header(stamp, odom_frame), child_frame_id=base_frame, pose=pwc, twist=twc)


def laser_scan(ranges: Sequence[float], angles: Sequence[float], range_max: float, stamp: Any, frame_id: str,
               scan_time_s: float = 0.1) -> Any:
    """sensor_msgs/LaserScan of evenly spaced rays (chronav's laser: ``angles`` in the robot frame)."""
    count = len(angles)
    increment = (angles[-1] - angles[0]) / (count - 1) if count > 1 else 0.0
    values = np.asarray(ranges, dtype=np.float32)
    values = np.where(values >= range_max, np.float32(np.inf), values)   # REP-117: no return is +inf
    return msg_class(LASER_SCAN)(header=header(stamp, frame_id), angle_min=float(angles[0]) if count else 0.0,
                                 angle_max=float(angles[-1]) if count else 0.0, angle_increment=float(increment),
                                 time_increment=0.0, scan_time=float(scan_time_s), range_min=0.05,
                                 range_max=float(range_max), ranges=values, intensities=np.zeros(0, np.float32))


def string(data: str) -> Any:
    return msg_class(STRING)(data=data)


def agenda_json(activities: Iterable[Any]) -> str:
    """The agenda as one JSON document (std_msgs/String): every activity with its state and times."""
    return json.dumps({"activities": [
        {"id": a.id, "name": a.name, "object": a.object, "room": a.room, "start_s": a.start_s, "end_s": a.end_s,
         "participants": list(a.participants), "state": a.state} for a in activities]}, sort_keys=True)


def clock(stamp: Any) -> Any:
    return msg_class(CLOCK)(clock=stamp)


def twist(vx: float, vy: float, omega: float) -> Any:
    return msg_class(TWIST)(linear=vector3(vx, vy), angular=vector3(0.0, 0.0, omega))


def diagnostics(node: str, received: dict[str, Any], before: dict[str, Any], topics: Sequence[str],
                stamp: Any) -> Any:
    """diagnostic_msgs/DiagnosticArray of what the bridge received: one status per subscribed
    topic (``<node>: received <topic>``), level WARN when it refused a message of that topic since
    the previous array (``before``), values ``taken``, ``refused`` and ``refused.<reason>``
    (totals since the bridge started, as ReceiveStats.snapshot gives them)."""
    status_cls, value_cls = msg_class("diagnostic_msgs/msg/DiagnosticStatus"), msg_class("diagnostic_msgs/msg/KeyValue")
    out = []
    for topic in topics:
        taken = int(received["accepted"].get(topic, 0))
        reasons = received["refused"].get(topic, {})
        refused = sum(reasons.values())
        new = refused - sum(before.get("refused", {}).get(topic, {}).values())
        values = [value_cls(key="taken", value=str(taken)), value_cls(key="refused", value=str(refused))]
        values += [value_cls(key=f"refused.{reason}", value=str(n)) for reason, n in sorted(reasons.items())]
        worst = max(reasons, key=lambda r: reasons[r]) if reasons else ""
        text = f"{taken} taken, {refused} refused" + (f" (most: {worst})" if worst else "")
        out.append(status_cls(level=DIAGNOSTIC_WARN if new > 0 else DIAGNOSTIC_OK, name=f"{node}: received {topic}",
                              message=text, hardware_id=node, values=values))
    return msg_class(DIAGNOSTIC_ARRAY)(header=header(stamp, ""), status=out)
