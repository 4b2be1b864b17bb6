"""Every message the bridge receives from ROS 2, checked before anything of chronav uses it.

Why a module of pure functions: a ROS 2 network is not chronav's to trust.  A wheel-encoder glitch
sends NaN, a localiser reset sends 1e308, a buggy driver sends a scan whose angles are NaN; taken
as true, such values end up in the DSR (the robot at x = 1e308), crash the bridge, or become
missions that can never succeed.  Each check here takes a decoded message and returns the few
plain values the bridge uses, or raises :class:`Refused` with a short reason code (what the
counters and ``/diagnostics`` show) and a readable detail (what the log line says).  No Zenoh, no
DSR: tests/unit/test_ros_validate.py drives every rule, tests/unit/test_ros_fuzz.py throws
Hypothesis at them.

The rules (docs/ros2.md, "What the bridge accepts"):

- **numbers**: every field the bridge reads is finite; ``/odom`` and ``/goal_pose`` positions lie
  inside the scene's extent plus ``POSE_MARGIN_M`` (and ``|z|`` at most ``MAX_HEIGHT_M``); speeds at most ``MAX_LINEAR_SPEED_MPS`` and
  ``MAX_ANGULAR_SPEED_RPS``; orientations are quaternions of norm 1 +- ``QUATERNION_NORM_TOLERANCE``
  (tf2 normalises; a zero quaternion is not a rotation);
- **scans**: angles within +-2 pi, a non-zero increment of at most 2 pi with the sign of
  ``angle_max - angle_min``, ``0 <= range_min < range_max <= MAX_RANGE_M``, at most
  ``MAX_SCAN_RAYS`` rays; each range is either a finite value in ``[0, MAX_RANGE_M]`` or one of
  REP-117's special values, kept (NaN and +inf: no return; -inf: too close to measure);
- **frames**: ``/goal_pose`` in the map frame; ``/odom`` in the odom or the map frame with the
  robot's base as child; ``/scan`` in the laser or the base frame.  **An empty frame_id is
  refused on every topic**: tf2 cannot place data without a frame, and guessing ``map`` for it
  turned a goal meant in another frame into a wrong mission;
- **stamps**: ``nanosec`` below 1e9 and ``sec`` not negative (builtin_interfaces/Time); a stamp
  of 0 (unset) is accepted.  Ordering is checked by :class:`StampOrder` per topic.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np

from agents.ros_bridge.messages import yaw_of

#: how far outside the scene's extent (walls, rooms or map) a received pose may lie (m): a robot
#: whose localiser drifted a little past the outer wall is still believed, 1e308 is not
POSE_MARGIN_M = 5.0
#: highest |z| a received position may have (m): a robot on an upper floor of a building, not 1e308
MAX_HEIGHT_M = 100.0
#: fastest linear speed an /odom may report (m/s): twice the fastest robot a scene may describe
#: (scenes/model.py MAX_SPEED_MPS = 5.0)
MAX_LINEAR_SPEED_MPS = 10.0
#: fastest turn an /odom may report (rad/s; the scene's robot turns at most 20 rad/s)
MAX_ANGULAR_SPEED_RPS = 20.0
#: a quaternion's norm may differ from 1 by this much (float32 publishers, rounding)
QUATERNION_NORM_TOLERANCE = 0.1
#: longest finite range a scan may report (m): long-range lidars reach 300 m; 3e38 is garbage
MAX_RANGE_M = 1000.0
#: most rays in one scan (a 0.1-degree 360-degree lidar has 3600); the 4 MiB message bound alone
#: would allow a million
MAX_SCAN_RAYS = 100_000
#: a stamp this much older than the newest of its topic is taken as the sender's clock restarting
#: (a robot rebooted, a bag looped), not as a late message
STAMP_RESET_S = 10.0
TWO_PI = 2.0 * math.pi

# reason codes: what the counters, /diagnostics and `chronav ros stats` show
TOO_LARGE = "too_large"
UNDECODABLE = "undecodable"
NOT_FINITE = "not_finite"
OUTSIDE_MAP = "outside_map"
TOO_FAST = "too_fast"
BAD_QUATERNION = "bad_quaternion"
EMPTY_FRAME = "empty_frame"
WRONG_FRAME = "wrong_frame"
BAD_STAMP = "bad_stamp"
OUT_OF_ORDER = "out_of_order"
BAD_SCAN = "bad_scan_geometry"
BAD_RANGE = "bad_range"
UNREACHABLE = "unreachable"
QUEUE_FULL = "queue_full"
INTERNAL = "internal_error"
REASONS = (TOO_LARGE, UNDECODABLE, NOT_FINITE, OUTSIDE_MAP, TOO_FAST, BAD_QUATERNION, EMPTY_FRAME, WRONG_FRAME,
           BAD_STAMP, OUT_OF_ORDER, BAD_SCAN, BAD_RANGE, UNREACHABLE, QUEUE_FULL, INTERNAL)


class Refused(ValueError):
    """A received message the bridge does not use: ``reason`` (a code above) and a readable detail."""

    def __init__(self, reason: str, detail: str) -> None:
        super().__init__(detail)
        self.reason = reason
        self.detail = detail


def shown(value: Any) -> str:
    """A number as a person reads it in a log line: 6 significant digits (``1e+308``, never 309
    digits), ``nan``, ``inf``; anything else by its repr cut to 40 characters."""
    if isinstance(value, int | float | np.floating | np.integer) and not isinstance(value, bool):
        return f"{float(value):.6g}"
    text = repr(value)
    return text if len(text) <= 40 else f"{text[:37]}..."


@dataclass(frozen=True)
class Limits:
    """What a received message is checked against: the scene's extent and the bridge's frames."""

    extent: tuple[float, float, float, float]     # (xmin, ymin, xmax, ymax) of the scene
    map_frame: str = "map"
    odom_frame: str = "odom"
    base_frame: str = "base_link"
    laser_frame: str = "base_link"
    margin_m: float = POSE_MARGIN_M

    def inside(self, x: float, y: float) -> bool:
        xmin, ymin, xmax, ymax = self.extent
        m = self.margin_m
        return xmin - m <= x <= xmax + m and ymin - m <= y <= ymax + m


@dataclass(frozen=True)
class RobotState:
    """What the bridge takes from an /odom: the robot's pose (map frame) and velocity (base frame)."""

    stamp_s: float
    x: float
    y: float
    yaw: float
    v: float
    vy: float
    omega: float


@dataclass(frozen=True)
class Goal:
    """What the bridge takes from a /goal_pose."""

    stamp_s: float
    x: float
    y: float
    yaw: float
    frame: str


@dataclass(frozen=True)
class Scan:
    """What the bridge takes from a /scan (REP-117 "no return" values kept as NaN/inf)."""

    stamp_s: float
    angle_min: float
    angle_increment: float
    range_min: float
    range_max: float
    ranges: np.ndarray       # float64


def finite(what: str, values: Iterable[tuple[str, Any]]) -> list[float]:
    """The values as floats, or Refused(NOT_FINITE) naming the first that is NaN or infinite."""
    out = []
    for name, value in values:
        number = float(value)
        if not math.isfinite(number):
            raise Refused(NOT_FINITE, f"{what}: {name} is {shown(number)}")
        out.append(number)
    return out


def stamp_seconds(header: Any, what: str) -> float:
    """The header's stamp in seconds; Refused(BAD_STAMP) when it is not a valid ROS time."""
    sec, nanosec = int(header.stamp.sec), int(header.stamp.nanosec)
    if sec < 0 or not 0 <= nanosec < 1_000_000_000:
        raise Refused(BAD_STAMP, f"{what}: stamp {sec} s {nanosec} ns is not a valid time "
                                 "(sec >= 0, nanosec < 1e9)")
    return sec + nanosec * 1e-9


def check_frame(frame_id: Any, allowed: Iterable[str], what: str, field: str = "frame_id") -> str:
    """``frame_id`` when it is one of ``allowed``; an empty one is refused as empty (one rule for all topics)."""
    frame = str(frame_id)
    names = tuple(dict.fromkeys(allowed))
    if not frame:
        raise Refused(EMPTY_FRAME, f"{what}: empty {field}; give {' or '.join(map(repr, names))}")
    if frame not in names:
        raise Refused(WRONG_FRAME, f"{what}: {field} {shown(frame)} is not {' or '.join(map(repr, names))}")
    return frame


def yaw_of_quaternion(q: Any, what: str) -> float:
    """The yaw of a unit quaternion; Refused when not finite or not of norm ~1."""
    qx, qy, qz, qw = finite(what, (("orientation.x", q.x), ("orientation.y", q.y), ("orientation.z", q.z),
                                   ("orientation.w", q.w)))
    norm = math.sqrt(qx * qx + qy * qy + qz * qz + qw * qw)
    if abs(norm - 1.0) > QUATERNION_NORM_TOLERANCE:
        raise Refused(BAD_QUATERNION, f"{what}: orientation has norm {shown(norm)}, not 1 (a rotation)")
    return yaw_of(q)


def _position(p: Any, limits: Limits, what: str) -> tuple[float, float]:
    x, y, z = finite(what, (("position.x", p.x), ("position.y", p.y), ("position.z", p.z)))
    if abs(z) > MAX_HEIGHT_M:
        raise Refused(OUTSIDE_MAP, f"{what}: position.z {shown(z)} m is more than {MAX_HEIGHT_M:g} m from the floor")
    if not limits.inside(x, y):
        xmin, ymin, xmax, ymax = limits.extent
        raise Refused(OUTSIDE_MAP, f"{what}: position ({shown(x)}, {shown(y)}) is more than {limits.margin_m:g} m "
                                   f"outside the scene ({xmin:g}..{xmax:g} x {ymin:g}..{ymax:g} m)")
    return x, y


def check_goal(message: Any, limits: Limits) -> Goal:
    """A geometry_msgs/PoseStamped from /goal_pose: in the map frame, finite, inside the scene."""
    what = "/goal_pose"
    stamp = stamp_seconds(message.header, what)
    frame = check_frame(message.header.frame_id, (limits.map_frame,), what)
    x, y = _position(message.pose.position, limits, what)
    yaw = yaw_of_quaternion(message.pose.orientation, what)
    return Goal(stamp, x, y, yaw, frame)


def check_odometry(message: Any, limits: Limits) -> RobotState:
    """A nav_msgs/Odometry from the ROS robot: pose in the odom or map frame (read as the map's,
    docs/ros2.md), child frame the robot's base, finite, inside the scene, speeds a robot can have."""
    what = "/odom"
    stamp = stamp_seconds(message.header, what)
    check_frame(message.header.frame_id, (limits.odom_frame, limits.map_frame), what)
    check_frame(message.child_frame_id, (limits.base_frame,), what, "child_frame_id")
    pose, twist = message.pose.pose, message.twist.twist
    x, y = _position(pose.position, limits, what)
    yaw = yaw_of_quaternion(pose.orientation, what)
    vx, vy, vz, wx, wy, wz = finite(what, (("linear.x", twist.linear.x), ("linear.y", twist.linear.y),
                                           ("linear.z", twist.linear.z), ("angular.x", twist.angular.x),
                                           ("angular.y", twist.angular.y), ("angular.z", twist.angular.z)))
    if math.hypot(vx, vy, vz) > MAX_LINEAR_SPEED_MPS:
        raise Refused(TOO_FAST, f"{what}: linear speed {shown(math.hypot(vx, vy, vz))} m/s is more than "
                                f"{MAX_LINEAR_SPEED_MPS:g} m/s")
    if max(abs(wx), abs(wy), abs(wz)) > MAX_ANGULAR_SPEED_RPS:
        raise Refused(TOO_FAST, f"{what}: angular speed {shown(max(abs(wx), abs(wy), abs(wz)))} rad/s is more than "
                                f"{MAX_ANGULAR_SPEED_RPS:g} rad/s")
    return RobotState(stamp, x, y, yaw, vx, vy, wz)


def check_scan(message: Any, limits: Limits) -> Scan:
    """A sensor_msgs/LaserScan from the ROS robot: its geometry finite and plausible, every range
    finite within [0, MAX_RANGE_M] or a REP-117 "no return" value (NaN, +-inf)."""
    what = "/scan"
    stamp = stamp_seconds(message.header, what)
    check_frame(message.header.frame_id, (limits.laser_frame, limits.base_frame), what)
    a_min, a_max, inc, _t_inc, _scan_t, r_min, r_max = finite(what, (
        ("angle_min", message.angle_min), ("angle_max", message.angle_max),
        ("angle_increment", message.angle_increment), ("time_increment", message.time_increment),
        ("scan_time", message.scan_time), ("range_min", message.range_min), ("range_max", message.range_max)))
    if not (-TWO_PI <= a_min <= TWO_PI and -TWO_PI <= a_max <= TWO_PI):
        raise Refused(BAD_SCAN, f"{what}: angles {shown(a_min)}..{shown(a_max)} rad are not within +-2 pi")
    if inc == 0.0 or abs(inc) > TWO_PI or (a_max != a_min and (a_max - a_min) * inc < 0):
        raise Refused(BAD_SCAN, f"{what}: angle_increment {shown(inc)} rad does not step from angle_min "
                                f"{shown(a_min)} to angle_max {shown(a_max)}")
    if not 0.0 <= r_min < r_max <= MAX_RANGE_M:
        raise Refused(BAD_SCAN, f"{what}: range_min {shown(r_min)} m and range_max {shown(r_max)} m are not "
                                f"0 <= range_min < range_max <= {MAX_RANGE_M:g}")
    ranges = np.asarray(message.ranges, dtype=np.float64)
    if ranges.ndim != 1 or not 0 < len(ranges) <= MAX_SCAN_RAYS:
        raise Refused(BAD_SCAN, f"{what}: {ranges.size} rays; a scan has 1 to {MAX_SCAN_RAYS:,}")
    finite_mask = np.isfinite(ranges)
    bad = finite_mask & ((ranges < 0.0) | (ranges > MAX_RANGE_M))
    if bad.any():
        first = float(ranges[np.argmax(bad)])
        raise Refused(BAD_RANGE, f"{what}: {int(bad.sum())} range(s) outside 0..{MAX_RANGE_M:g} m "
                                 f"(e.g. {shown(first)}); no return is NaN or inf (REP-117)")
    return Scan(stamp, a_min, inc, r_min, r_max, ranges)


class StampOrder:
    """Refuses a message older than the newest accepted on its topic (a late or replayed sample
    would move the robot back), unless it is more than STAMP_RESET_S older: then the sender's
    clock restarted and its new stamps are taken from there.  Unset stamps (0) are not ordered."""

    def __init__(self) -> None:
        self._newest: dict[str, float] = {}

    def check(self, topic: str, stamp_s: float) -> None:
        if stamp_s == 0.0:
            return
        newest = self._newest.get(topic)
        if newest is not None and newest - STAMP_RESET_S <= stamp_s < newest:
            raise Refused(OUT_OF_ORDER, f"{topic}: stamp {stamp_s:.3f} s is older than the last one taken "
                                        f"({newest:.3f} s)")
        self._newest[topic] = stamp_s
