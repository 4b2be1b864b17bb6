"""Every rule of agents/ros_bridge/validate.py: what a ROS 2 message must hold to be used (issue 42)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from agents.ros_bridge import messages as msgs
from agents.ros_bridge import validate as v
from agents.ros_bridge.types import msg_class

LIMITS = v.Limits((0.0, 0.0, 6.0, 4.0))


def stamp() -> object:
    return msgs.ros_time(36_000.0, 1_764_025_200.0)   # a new one each time: tests change them


def goal(x: float = 2.0, y: float = 2.0, yaw: float = 0.5, frame: str = "map") -> object:
    return msg_class(msgs.POSE_STAMPED)(header=msgs.header(stamp(), frame), pose=msgs.pose(x, y, yaw))


def odom(x: float = 1.0, y: float = 1.0, vx: float = 0.3, omega: float = 0.1, frame: str = "odom",
         child: str = "base_link") -> object:
    return msgs.odometry(x, y, 0.2, vx, 0.0, omega, stamp(), frame, child)


def scan(ranges: list[float] | None = None, **fields: float) -> object:
    message = msgs.laser_scan([1.0] * 91, list(np.linspace(-1.57, 1.57, 91)), 5.0, stamp(), "base_link")
    if ranges is not None:   # as sent (the builder writes ranges beyond range_max as +inf)
        message.ranges = np.asarray(ranges, dtype=np.float32)
    for name, value in fields.items():
        setattr(message, name, value)
    return message


def reason(check: object, *args: object) -> str:
    with pytest.raises(v.Refused) as caught:
        check(*args)  # type: ignore[operator]
    return caught.value.reason


def test_a_good_goal_odometry_and_scan_are_taken() -> None:
    g = v.check_goal(goal(), LIMITS)
    assert (g.x, g.y, g.yaw, g.frame) == (2.0, 2.0, pytest.approx(0.5), "map")
    state = v.check_odometry(odom(), LIMITS)
    assert (state.x, state.v, state.omega, state.yaw) == (1.0, pytest.approx(0.3), pytest.approx(0.1), pytest.approx(0.2))
    taken = v.check_scan(scan([1.0, math.nan, math.inf, -math.inf] + [2.0] * 87), LIMITS)
    assert len(taken.ranges) == 91 and np.isnan(taken.ranges[1])   # REP-117 "no return" values are kept


@pytest.mark.parametrize(("x", "expected"), [(math.nan, v.NOT_FINITE), (math.inf, v.NOT_FINITE),
                                             (1e308, v.OUTSIDE_MAP), (-5.5, v.OUTSIDE_MAP)])
def test_absurd_positions_are_refused(x: float, expected: str) -> None:
    assert reason(v.check_goal, goal(x=x), LIMITS) == expected
    assert reason(v.check_odometry, odom(x=x), LIMITS) == expected


def test_a_position_far_above_the_floor_is_refused() -> None:
    message = goal()
    message.pose.position.z = 1e308
    assert reason(v.check_goal, message, LIMITS) == v.OUTSIDE_MAP
    message.pose.position.z = 3.0                                  # an upper floor
    assert v.check_goal(message, LIMITS).x == 2.0


def test_a_pose_a_little_outside_the_scene_is_believed() -> None:
    assert v.check_odometry(odom(x=-4.0), LIMITS).x == -4.0      # within POSE_MARGIN_M


def test_speeds_beyond_a_robots_are_refused() -> None:
    assert reason(v.check_odometry, odom(vx=1e6), LIMITS) == v.TOO_FAST
    assert reason(v.check_odometry, odom(omega=100.0), LIMITS) == v.TOO_FAST
    assert reason(v.check_odometry, odom(vx=math.nan), LIMITS) == v.NOT_FINITE


def test_the_empty_frame_is_refused_on_every_topic_and_other_frames_too() -> None:
    assert reason(v.check_goal, goal(frame=""), LIMITS) == v.EMPTY_FRAME
    assert reason(v.check_goal, goal(frame="odom"), LIMITS) == v.WRONG_FRAME
    assert reason(v.check_odometry, odom(frame=""), LIMITS) == v.EMPTY_FRAME
    assert reason(v.check_odometry, odom(child=""), LIMITS) == v.EMPTY_FRAME
    assert reason(v.check_odometry, odom(child="laser"), LIMITS) == v.WRONG_FRAME
    assert v.check_odometry(odom(frame="map"), LIMITS).x == 1.0     # a localiser's map poses
    bad = scan()
    bad.header.frame_id = ""
    assert reason(v.check_scan, bad, LIMITS) == v.EMPTY_FRAME


def test_quaternions_must_be_rotations() -> None:
    message = goal()
    message.pose.orientation.w = 0.0
    message.pose.orientation.z = 0.0
    assert reason(v.check_goal, message, LIMITS) == v.BAD_QUATERNION
    message.pose.orientation.z = math.nan
    assert reason(v.check_goal, message, LIMITS) == v.NOT_FINITE


def test_stamps_must_be_times() -> None:
    message = goal()
    message.header.stamp.nanosec = 2_000_000_000
    assert reason(v.check_goal, message, LIMITS) == v.BAD_STAMP
    message.header.stamp.nanosec, message.header.stamp.sec = 0, -5
    assert reason(v.check_goal, message, LIMITS) == v.BAD_STAMP


@pytest.mark.parametrize("fields", [{"angle_min": math.nan}, {"angle_max": math.inf}, {"angle_increment": math.nan},
                                    {"range_max": math.inf}, {"scan_time": math.nan}])
def test_scans_with_nan_or_infinite_geometry_are_refused(fields: dict[str, float]) -> None:
    assert reason(v.check_scan, scan(**fields), LIMITS) == v.NOT_FINITE


@pytest.mark.parametrize("fields", [{"angle_min": 100.0}, {"angle_increment": 0.0}, {"angle_increment": -0.1},
                                    {"range_min": -1.0}, {"range_max": 3e38}, {"range_min": 6.0}])
def test_scans_with_impossible_geometry_are_refused(fields: dict[str, float]) -> None:
    assert reason(v.check_scan, scan(**fields), LIMITS) == v.BAD_SCAN


def test_ranges_of_3e38_are_garbage_not_no_return() -> None:
    assert reason(v.check_scan, scan([3e38] * 91), LIMITS) == v.BAD_RANGE
    assert reason(v.check_scan, scan([-2.0] + [1.0] * 90), LIMITS) == v.BAD_RANGE
    assert reason(v.check_scan, scan([]), LIMITS) == v.BAD_SCAN


def test_stamps_going_back_are_refused_unless_the_clock_restarted() -> None:
    order = v.StampOrder()
    order.check("/odom", 100.0)
    order.check("/odom", 100.5)
    with pytest.raises(v.Refused) as caught:
        order.check("/odom", 100.2)
    assert caught.value.reason == v.OUT_OF_ORDER
    order.check("/odom", 3.0)        # 97 s back: the robot's clock restarted
    order.check("/odom", 3.1)
    order.check("/odom", 0.0)        # unset stamps are not ordered
    order.check("/scan", 1.0)        # per topic


def test_numbers_in_messages_are_shown_readably() -> None:
    assert v.shown(1e308) == "1e+308" and v.shown(math.nan) == "nan" and v.shown(0.1 + 0.2) == "0.3"
    with pytest.raises(v.Refused) as caught:
        v.check_goal(goal(x=1e308), LIMITS)
    assert "1e+308" in str(caught.value) and len(str(caught.value)) < 200


def test_the_documented_bounds_are_the_codes() -> None:
    from agents.ros_bridge.agent import ODOM_TIMEOUT_S
    from agents.ros_bridge.inbox import LOG_INTERVAL_S, MAX_PENDING_GOALS
    from agents.world.plans_file import MAX_PATH_POINTS, MAX_PLANS_BYTES
    from tests.support import REPO_ROOT

    limits = (REPO_ROOT / "docs" / "limits.md").read_text(encoding="utf-8")
    ros2 = (REPO_ROOT / "docs" / "ros2.md").read_text(encoding="utf-8")
    for text in (f"within {v.POSE_MARGIN_M:g} m of the scene's extent", f"at most {v.MAX_LINEAR_SPEED_MPS:g} m/s and "
                 f"{v.MAX_ANGULAR_SPEED_RPS:g} rad/s", f"1 to {v.MAX_SCAN_RAYS:,} rays",
                 f"finite ranges 0 to {v.MAX_RANGE_M:g} m", f"after {ODOM_TIMEOUT_S:g} s a zero",
                 f"every {LOG_INTERVAL_S:g} s", f"| {MAX_PENDING_GOALS} (more", f"{MAX_PLANS_BYTES} bytes",
                 f"{MAX_PATH_POINTS:,} points"):
        assert text in limits, text
    for text in (f"scene's extent plus {v.POSE_MARGIN_M:g} m", f"1 to {v.MAX_SCAN_RAYS:,} rays",
                 f"norm 1 +- {v.QUATERNION_NORM_TOLERANCE:g}", f"more than {v.STAMP_RESET_S:g} s older",
                 f"for {ODOM_TIMEOUT_S:g} s (`ODOM_TIMEOUT_S`"):
        assert text in ros2, text
