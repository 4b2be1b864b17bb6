"""What the bridge receives from ROS 2: bounded, decoded, validated, counted; the loop takes from it.

Why apart from the agent and from Zenoh: this is the one path every received byte takes
(``RosNode.create_subscription`` hands each sample's payload to :meth:`Inbox.receive`, on Zenoh's
thread), so it is the one place that must never raise, whatever the bytes hold.  Tests and the
fuzz test drive it directly with bytes, without a ROS network (tests/unit/test_ros_fuzz.py).

Each payload: size bound (wire.MAX_RECEIVED_BYTES), CDR decode as the subscribed type, the
checks of validate.py, then stored (the newest /odom and /scan) or queued (goals, at most
MAX_PENDING_GOALS).  A payload that fails any step is dropped and counted per topic and reason
(:class:`ReceiveStats`); an unexpected exception is counted as ``internal_error``.  Log lines are
rate-limited per topic and reason (one per LOG_INTERVAL_S, saying how many were not logged), so a
flood of bad messages cannot fill the disk or the CPU with logging.
"""

from __future__ import annotations

import logging
import queue
import threading
import time
from collections.abc import Callable
from typing import Any

from agents.ros_bridge import messages as msgs
from agents.ros_bridge import validate as v
from agents.ros_bridge.types import deserialize
from agents.ros_bridge.wire import MAX_RECEIVED_BYTES

#: goals received and not yet turned into missions (more are refused, counted)
MAX_PENDING_GOALS = 16
#: at most one log line per topic and reason in this many seconds
LOG_INTERVAL_S = 5.0
GOAL_POSE, ODOM, SCAN = "goal_pose", "odom", "scan"
TYPES = {GOAL_POSE: msgs.POSE_STAMPED, ODOM: msgs.ODOMETRY, SCAN: msgs.LASER_SCAN}


class ReceiveStats:
    """Messages taken and refused, per topic and reason; thread-safe (Zenoh's threads write, the
    agent's loop reads).  Also the rate limit of the refusal log lines."""

    def __init__(self, log: logging.Logger, clock: Callable[[], float] = time.monotonic) -> None:
        self.log = log
        self.clock = clock
        self._lock = threading.Lock()
        self.accepted: dict[str, int] = {}
        self.refused: dict[str, dict[str, int]] = {}
        self._logged_at: dict[tuple[str, str], float] = {}
        self._silenced: dict[tuple[str, str], int] = {}

    def accept(self, topic: str) -> None:
        with self._lock:
            self.accepted[topic] = self.accepted.get(topic, 0) + 1

    def refuse(self, topic: str, reason: str, detail: str) -> None:
        """Count one refusal; log it unless that topic and reason was logged in the last LOG_INTERVAL_S."""
        now = self.clock()
        with self._lock:
            per_topic = self.refused.setdefault(topic, {})
            per_topic[reason] = per_topic.get(reason, 0) + 1
            key = (topic, reason)
            if now - self._logged_at.get(key, -float("inf")) < LOG_INTERVAL_S:
                self._silenced[key] = self._silenced.get(key, 0) + 1
                return
            self._logged_at[key] = now
            silenced = self._silenced.pop(key, 0)
        more = f" ({silenced} more {reason} on {topic} not logged in the last {LOG_INTERVAL_S:g} s)" if silenced else ""
        self.log.warning("refused %s [%s]: %s%s", topic, reason, detail, more)

    def total_refused(self) -> int:
        with self._lock:
            return sum(sum(r.values()) for r in self.refused.values())

    def snapshot(self) -> dict[str, Any]:
        """{"accepted": {topic: n}, "refused": {topic: {reason: n}}} (copies)."""
        with self._lock:
            return {"accepted": dict(self.accepted),
                    "refused": {t: dict(r) for t, r in self.refused.items()}}


class Inbox:
    """The bridge's received messages, validated: the newest robot state and scan, pending goals."""

    def __init__(self, limits: v.Limits, topics: dict[str, str], stats: ReceiveStats) -> None:
        """``topics``: the ROS name of each subscribed key (goal_pose, odom, scan), for the counters."""
        self.limits = limits
        self.topics = topics
        self.stats = stats
        self.order = v.StampOrder()
        self.goals: queue.Queue[v.Goal] = queue.Queue(maxsize=MAX_PENDING_GOALS)
        self.odom: v.RobotState | None = None
        self.odom_count = 0                   # odometry messages taken (the agent writes each new one once)
        self.odom_at = -float("inf")          # wall clock (stats.clock) when the newest was taken
        self.scan: v.Scan | None = None
        self._lock = threading.Lock()

    def receive(self, key: str, data: bytes) -> None:
        """One payload of subscription ``key``; never raises (Zenoh's callback thread)."""
        topic = self.topics.get(key, key)
        try:
            self._receive(key, topic, data)
        except v.Refused as exc:
            self.stats.refuse(topic, exc.reason, exc.detail)
        except Exception as exc:  # noqa: BLE001 - whatever a message holds must not end the bridge
            self.stats.refuse(topic, v.INTERNAL, f"{type(exc).__name__}: {v.shown(str(exc))}")

    def _receive(self, key: str, topic: str, data: bytes) -> None:
        if len(data) > MAX_RECEIVED_BYTES:
            raise v.Refused(v.TOO_LARGE, f"{topic}: {len(data):,} bytes (at most {MAX_RECEIVED_BYTES:,})")
        type_name = TYPES[key]
        try:
            message = deserialize(data, type_name)
        except Exception:  # noqa: BLE001 - any malformed CDR: rosbags raises several kinds
            raise v.Refused(v.UNDECODABLE, f"{topic}: {len(data):,} bytes that are not a valid {type_name} "
                                           "(a publisher with another type or version of that message?)") from None
        if key == GOAL_POSE:
            goal = v.check_goal(message, self.limits)
            try:
                self.goals.put_nowait(goal)
            except queue.Full:
                raise v.Refused(v.QUEUE_FULL, f"{topic}: goal ({v.shown(goal.x)}, {v.shown(goal.y)}): "
                                              f"{MAX_PENDING_GOALS} goals already wait") from None
            return   # counted as taken once it is a mission (the agent checks it can be reached)
        elif key == ODOM:
            state = v.check_odometry(message, self.limits)
            with self._lock:
                self.order.check(topic, state.stamp_s)
                self.odom = state
                self.odom_count += 1
                self.odom_at = self.stats.clock()
        elif key == SCAN:
            scan = v.check_scan(message, self.limits)
            with self._lock:
                self.order.check(topic, scan.stamp_s)
                self.scan = scan
        self.stats.accept(topic)

    def take_goals(self) -> list[v.Goal]:
        out = []
        while True:
            try:
                out.append(self.goals.get_nowait())
            except queue.Empty:
                return out
