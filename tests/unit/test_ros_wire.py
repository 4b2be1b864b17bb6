"""rmw_zenoh's conventions and ROS 2 types as the bridge speaks them, against independent vectors.

The RIHS01 hashes are computed by rosbags from the type descriptions; the expected values are
published by others: std_msgs/String in rmw_zenoh's docs/design.md key-expression examples,
OccupancyGrid, TFMessage and Twist in `ros2 topic info --verbose` outputs of ROS 2 installs
(RViz's /map subscription, amcl's /tf, teleop_turtle's cmd_vel), Odometry, LaserScan,
PoseStamped, Path and Clock in other ROS-2-over-Zenoh clients' tables and golden-hash tests,
DiagnosticArray in rosidl_generator_c's output for diagnostic_msgs
(``diagnostic_msgs__msg__DiagnosticArray__TYPE_HASH``) and in other clients' tables.
"""

from __future__ import annotations

import math
import struct
from pathlib import Path

import numpy as np
import pytest

from agents.ros_bridge import messages as msgs
from agents.ros_bridge.config import BridgeConfigError, load_bridge_config
from agents.ros_bridge.validate import Limits, check_goal
from agents.ros_bridge.types import dds_type_name, deserialize, serialize, type_hash
from agents.ros_bridge.wire import Qos, attachment, fully_qualified, mangle, parse_attachment, topic_key

PUBLISHED_HASHES = {
    "std_msgs/msg/String": "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18",
    "nav_msgs/msg/OccupancyGrid": "RIHS01_8d348150c12913a31ee0ec170fbf25089e4745d17035792a1ba94d6f0bc0cfc7",
    "tf2_msgs/msg/TFMessage": "RIHS01_e369d0f05a23ae52508854b66f6aa0437f3449d652e8cbf22d5abe85d020f087",
    "geometry_msgs/msg/Twist": "RIHS01_9c45bf16fe0983d80e3cfe750d6835843d265a9a6c46bd2e609fcddde6fb8d2a",
    "nav_msgs/msg/Odometry": "RIHS01_3cc97dc7fb7502f8714462c526d369e35b603cfc34d946e3f2eda2766dfec6e0",
    "sensor_msgs/msg/LaserScan": "RIHS01_64c191398013af96509d518dac71d5164f9382553fce5c1f8cca5be7924bd828",
    "geometry_msgs/msg/PoseStamped": "RIHS01_10f3786d7d40fd2b54367835614bff85d4ad3b5dab62bf8bca0cc232d73b4cd8",
    "nav_msgs/msg/Path": "RIHS01_1957a5bb3cee5da65c4e52e52b65a93df227efce4c20f8458b36e73066ca334b",
    "rosgraph_msgs/msg/Clock": "RIHS01_692f7a66e93a3c83e71765d033b60349ba68023a8c689a79e48078bcb5c58564",
    "diagnostic_msgs/msg/DiagnosticArray": "RIHS01_5a8a36efb05fb25070fa0fb3810290c0e6cd4862b54a8fb975a1ee8dc55a333e",
}


@pytest.mark.parametrize("type_name", sorted(PUBLISHED_HASHES))
def test_type_hashes_match_the_ones_ros2_publishes(type_name: str) -> None:
    assert type_hash(type_name) == PUBLISHED_HASHES[type_name]


def test_keys_as_in_rmw_zenoh_design_examples() -> None:
    string_hash = PUBLISHED_HASHES["std_msgs/msg/String"]
    assert topic_key(0, "/chatter", "std_msgs/msg/String") == f"0/chatter/std_msgs::msg::dds_::String_/{string_hash}"
    assert topic_key(0, fully_qualified("chatter", "/robot1"), "std_msgs/msg/String") == (
        f"0/robot1/chatter/std_msgs::msg::dds_::String_/{string_hash}")
    assert dds_type_name("nav_msgs/msg/OccupancyGrid") == "nav_msgs::msg::dds_::OccupancyGrid_"
    assert mangle("/chatter") == "%chatter" and mangle("") == "%"


def test_qos_tokens_as_in_rmw_zenoh_design_examples() -> None:
    assert Qos(depth=10).token() == "::,10:,:,:,,"      # listener's subscription
    assert Qos(depth=7).token() == "::,7:,:,:,,"        # talker's publisher
    assert Qos(durability="transient_local", depth=1).token() == ":1:,1:,:,:,,"
    assert Qos(reliability="best_effort", depth=5).token() == "2::,5:,:,:,,"
    assert Qos(depth=42).token() == "::,:,:,:,,"        # rmw_zenoh's default depth is left out


def test_attachment_layout() -> None:
    gid = bytes(range(16))
    raw = attachment(3, 1_700_000_000_123_456_789, gid)
    assert len(raw) == 8 + 8 + 1 + 16
    assert struct.unpack("<qqB", raw[:17]) == (3, 1_700_000_000_123_456_789, 16) and raw[17:] == gid
    assert parse_attachment(raw) == (3, 1_700_000_000_123_456_789, gid)
    with pytest.raises(ValueError, match="expected at least 17"):
        parse_attachment(raw[:10])


def test_cdr_has_the_encapsulation_header_and_round_trips() -> None:
    stamp = msgs.ros_time(36_000.25, msgs.day_epoch_s(__import__("datetime").date(2026, 11, 25), "Europe/Madrid"))
    values = np.arange(12, dtype=np.int8).reshape(3, 4)
    grid = msgs.occupancy_grid(values, (1.0, -2.0), 0.05, stamp, "map")
    data = serialize(grid, msgs.OCCUPANCY_GRID)
    assert data[:4] == b"\x00\x01\x00\x00"                       # CDR little endian, options 0
    back = deserialize(data, msgs.OCCUPANCY_GRID)
    assert (back.info.width, back.info.height) == (4, 3) and back.data.tolist() == list(range(12))
    assert back.info.origin.position.x == 1.0 and back.header.frame_id == "map"
    # 10:00:00.25 in Madrid on 2026-11-25 is 09:00:00.25 UTC
    assert back.header.stamp.sec == 1795597200 and back.header.stamp.nanosec == 250_000_000


def test_goal_pose_and_laser_conventions() -> None:
    goal = msgs.path([0.0, 1.0], [0.0, 1.0], msgs.ros_time(0.0), "map").poses[-1]
    limits = Limits((0.0, 0.0, 6.0, 4.0))
    taken = check_goal(goal, limits)
    assert (taken.x, taken.y, taken.yaw) == pytest.approx((1.0, 1.0, math.pi / 4))
    bad = msgs.path([math.nan, 1.0], [0.0, 1.0], msgs.ros_time(0.0), "map").poses[0]
    with pytest.raises(ValueError, match="is nan"):
        check_goal(bad, limits)
    scan = msgs.laser_scan([1.0, 5.0, 2.0], [-0.5, 0.0, 0.5], 5.0, msgs.ros_time(0.0), "base_link")
    assert scan.angle_increment == pytest.approx(0.5) and math.isinf(scan.ranges[1])   # REP-117: no return


def test_bridge_config_errors_name_the_file_and_key(tmp_path: Path) -> None:
    good = tmp_path / "ros.yaml"
    good.write_text("domain: 3\ntopics:\n  people: {name: /humans, rate_hz: 2}\nframes: {base: base_footprint}\n")
    cfg = load_bridge_config(good)
    assert (cfg.domain, cfg.topics.people.name, cfg.frames.base) == (3, "/humans", "base_footprint")
    assert cfg.topics.map.qos.qos() == Qos(durability="transient_local", depth=1)
    bad = tmp_path / "bad.yaml"
    bad.write_text("topics:\n  people: {nmae: /humans}\n")
    with pytest.raises(BridgeConfigError, match=r"bad.yaml: topics.people.nmae: Extra inputs"):
        load_bridge_config(bad)
    with pytest.raises(BridgeConfigError, match="domain"):
        load_bridge_config(None, domain=999)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_keepout_values_equal_their_numpy_definition(dtype: type) -> None:
    """The compiled keepout conversion (nav2.keepout_values, used by the bridge several times a
    second) gives exactly docs/maps.md's formula, half steps and lethal cells included."""
    from agents.lib.socialmap.nav2 import MaskScale, keepout_values
    from agents.lib.socialmap.social_map import SocialMapParams

    scale = MaskScale.for_params(SocialMapParams())
    rng = np.random.default_rng(5)
    costs = rng.uniform(-1, 6, size=(60, 100)).astype(dtype)
    costs[rng.random(costs.shape) < 0.1] = np.inf
    costs[0, :99] = (scale.free_cost + (np.arange(99) + 0.5) * scale.multiplier).astype(dtype)
    finite = np.isfinite(costs)
    graded = np.rint((np.where(finite, costs, scale.free_cost) - scale.free_cost) / scale.multiplier)
    expected = np.where(finite, np.clip(graded, 0, 99), 100).astype(np.int8)
    assert np.array_equal(keepout_values(costs, scale), expected)


def test_a_ros_robots_scan_is_resampled_to_the_scenes_rays() -> None:
    """--robot ros: the navigation reads the laser at the scene's ray angles; rays the robot's
    scanner does not cover, or that saw nothing (inf, NaN, beyond range), read as max range."""
    from agents.ros_bridge.agent import resample_scan

    scan = msgs.laser_scan([1.0, 2.0, 9.0, 3.0, 4.0], [-1.0, -0.5, 0.0, 0.5, 1.0], 6.0, msgs.ros_time(0.0), "laser")
    scan.ranges[3] = np.nan
    out = resample_scan(scan, [-2.0, -1.0, -0.49, 0.0, 0.5, 0.99], 5.0)
    assert out == [5.0, 1.0, 2.0, 5.0, 5.0, 4.0]
