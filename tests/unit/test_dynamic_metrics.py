"""HuNavSim's dynamic metrics (agents/lib/metrics/dynamic_metrics.py) against values worked out by
hand, and `chronav metrics` reading a run's people.csv."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import shapely
from typer.testing import CliRunner

from agents.lib.metrics.dynamic_metrics import tracks_from_rows
from agents.lib.metrics.metrics import compute_metrics, read_people_csv
from tools.cli import app

ROBOT_R = 0.3


def robot_line(xs: list[float], dt: float = 1.0, y: float = 0.0) -> np.ndarray:
    return np.array([[k * dt, x, y, 0.0] for k, x in enumerate(xs)])


def still(name: str, x: float, y: float, times: list[float], theta: float = 0.0, group: str = "") -> list:
    return [(t, name, x, y, theta, 0.0, 0.0, group) for t in times]


def test_distances_and_intrusions_past_a_standing_person() -> None:
    """Robot along y = 0 at 1 m/s, a person at (2, 1.1): centre distances hypot(2, 1.1),
    hypot(1, 1.1), 1.1, ...; minus the robot's 0.3 m and the person's 0.25 m (body edges): 1.733,
    0.937, 0.55, 0.937, 1.733."""
    traj = robot_line([0, 1, 2, 3, 4])
    tracks = tracks_from_rows(still("ana", 2.0, 1.1, [0, 1, 2, 3, 4], theta=-math.pi / 2))
    d = compute_metrics(traj, people_tracks=tracks, robot_radius_m=ROBOT_R).dynamic
    assert d is not None
    assert d.min_distance_to_people_m == pytest.approx(0.55)
    edges = [math.hypot(dx, 1.1) - 0.55 for dx in (2, 1, 0, 1, 2)]
    assert d.max_distance_to_people_m == pytest.approx(math.hypot(2, 1.1) - 0.55)
    assert d.avg_distance_to_closest_person_m == pytest.approx(np.mean(edges))
    assert d.avg_robot_linear_speed_mps == pytest.approx(1.0) and d.avg_acceleration_mps2 == pytest.approx(0.0)
    assert d.avg_pedestrian_speed_mps == d.avg_closest_pedestrian_speed_mps == 0.0
    assert (d.intimate_intrusions_percent, d.personal_intrusions_percent, d.social_intrusions_percent) == \
        pytest.approx((0.0, 60.0, 40.0))
    assert d.intrusions_per_person == {"ana": pytest.approx({"intimate": 0.0, "personal": 60.0, "social": 40.0})}
    assert d.time_not_moving_s == 0.0
    assert d.robot_on_person_collisions == d.person_on_robot_collisions == 0


def test_social_forces_between_two_still_bodies_and_the_walls_push() -> None:
    """Both at rest, 1.1 m apart: the interaction vector is the unit direction (theta = 0, B = 0.35), so
    each pushes the other with 2.1 exp(-1.1 / 0.35); a wall 1 m from the robot's centre
    pushes with 10 exp(-(1 - 0.3) / 0.2) = 0.3020.  Two samples."""
    traj = robot_line([0.0, 0.0])
    tracks = tracks_from_rows(still("ben", 1.1, 0.0, [0, 1], theta=math.pi))
    force = 2.1 * math.exp(-1.1 / 0.35)
    wall = shapely.LineString([(-5, 1.0), (5, 1.0)])
    d = compute_metrics(traj, people_tracks=tracks, robot_radius_m=ROBOT_R, obstacles=wall).dynamic
    assert d.social_force_on_robot == pytest.approx(2 * force, rel=1e-6)
    assert d.social_force_on_people == pytest.approx(2 * force, rel=1e-6)
    push = 10.0 * math.exp(-0.7 / 0.2)
    assert d.social_work == pytest.approx(2 * (force + push + force), rel=1e-6)
    assert d.obstacle_force_on_robot == pytest.approx(2 * push, rel=1e-6)
    assert d.obstacle_force_on_people == pytest.approx(2 * 10.0 * math.exp(-0.75 / 0.2), rel=1e-6)  # 1 m - 0.25
    assert d.time_not_moving_s == pytest.approx(1.0), "one interval of 1 s at rest"
    assert d.intimate_intrusions_percent == pytest.approx(0.0)
    assert d.personal_intrusions_percent == pytest.approx(100.0), "1.1 - 0.3 - 0.25 = 0.55 m: personal"


def test_collisions_are_blamed_on_who_moved_into_whom() -> None:
    """Contact is d < 0.3 + 0.25 + 0.02 = 0.57 m.  The robot drives into a still person at 0.5 m/s
    (in contact at x = 0.75 and 1.0: one collision, the robot's); then a person walks into the still
    robot (one, the person's)."""
    traj = robot_line([0.0, 0.25, 0.5, 0.75, 1.0], dt=0.5)
    times = [0.0, 0.5, 1.0, 1.5, 2.0]
    d = compute_metrics(traj, people_tracks=tracks_from_rows(still("ana", 1.1, 0.0, times)),
                        robot_radius_m=ROBOT_R).dynamic
    assert (d.robot_on_person_collisions, d.person_on_robot_collisions) == (1, 0)
    walker = [(t, "ben", 1.5 - 0.5 * t, 0.0, math.pi, -0.5, 0.0, "") for t in times]   # 1.5 .. 0.5 m
    d = compute_metrics(robot_line([0.0] * 5, dt=0.5), people_tracks=tracks_from_rows(walker),
                        robot_radius_m=ROBOT_R).dynamic
    assert (d.robot_on_person_collisions, d.person_on_robot_collisions) == (0, 1)


def test_group_intrusions_use_where_the_members_gazes_meet() -> None:
    """Two people facing each other 3 m apart at y = 2: each gaze 1.5 m ahead ends at (1.5, 2), the
    group's centre; the robot at (1.5, 0) is 2 - 0.3 = 1.7 m from it (social), and 0.3 m ... no
    person is closer than sqrt(1.5^2 + 2^2) - 0.3 = 2.2 m (social too)."""
    traj = np.array([[0.0, 1.5, 0.0, 0.0], [1.0, 1.5, 0.0, 0.0]])
    rows = still("a", 0.0, 2.0, [0, 1], theta=0.0, group="chat/1") + \
        still("b", 3.0, 2.0, [0, 1], theta=math.pi, group="chat/1")
    d = compute_metrics(traj, people_tracks=tracks_from_rows(rows), robot_radius_m=ROBOT_R).dynamic
    assert (d.group_intimate_intrusions_percent, d.group_personal_intrusions_percent,
            d.group_social_intrusions_percent) == pytest.approx((0.0, 0.0, 100.0))
    assert d.intrusions_per_group == {"chat/1": pytest.approx({"intimate": 0.0, "personal": 0.0, "social": 100.0})}
    assert d.min_distance_to_people_m == pytest.approx(2.5 - 0.3 - 0.25)


def test_chronav_metrics_reads_the_runs_people_csv(tmp_path: Path) -> None:
    """A run directory holds trajectory.csv and people.csv: `chronav metrics` measures both."""
    (tmp_path / "trajectory.csv").write_text("t,x,y,theta\n" + "".join(
        f"{36000 + k},{1.0 + 0.5 * k},1.2,0\n" for k in range(5)))
    (tmp_path / "people.csv").write_text("t,name,role,x,y,theta,vx,vy,group\n" + "".join(
        f"{36000 + k},walker,resident,3.0,1.2,3.14159,0,0,\n" for k in range(5)))
    result = CliRunner().invoke(app, ["metrics", "center_a", str(tmp_path / "trajectory.csv"), "--json"])
    assert result.exit_code == 0, result.output
    dynamic = json.loads(result.stdout)["metrics"]["dynamic"]
    # robot x 1.0 .. 3.0 toward a person at x = 3: centre distances 2, 1.5, 1, 0.5, 0 -> contact at the
    # last two (0.5 < 0.57): one collision, the robot's
    assert dynamic["min_distance_to_people_m"] == 0.0, "overlapping bodies: clipped at 0, never negative"
    assert dynamic["robot_on_person_collisions"] == 1 and dynamic["person_on_robot_collisions"] == 0
    assert dynamic["robot_intimate_entries"] == 1
    assert json.loads(result.stdout)["metrics"]["duration_s"] == 4.0
    table = CliRunner().invoke(app, ["metrics", "center_a", str(tmp_path / "trajectory.csv")], env={"COLUMNS": "200"})
    assert "social work (m/s^2, summed over samples)" in table.output and "collisions" in table.output
    assert "no target" in table.output, "a metric without a value says why"


def test_a_bad_people_csv_is_named_with_its_line(tmp_path: Path) -> None:
    bad = tmp_path / "people.csv"
    bad.write_text("t,name,role,x,y,theta,vx,vy,group\n36000,ana,resident,1,2,0,0,0,\n36001,ana,resident,one,2,0,0,0,\n")
    with pytest.raises(ValueError, match=rf"{bad}:3: column 'x': 'one' is not a number"):
        read_people_csv(bad)
    (tmp_path / "trajectory.csv").write_text("t,x,y,theta\n36000,1,1.2,0\n36001,1.5,1.2,0\n")
    result = CliRunner().invoke(app, ["metrics", "center_a", str(tmp_path / "trajectory.csv")])
    assert result.exit_code != 0 and f"{bad}:3" in result.output and "Traceback" not in result.output


def test_intimate_zone_entries_count_only_the_robots_approaches() -> None:
    """A resident's intimate zone reaches sqrt(2 ln 1.25) x 1.0 m = 0.668 m in front of them
    (personal_space.py).  The robot drives up to a resident facing it: at 0.6 m it is inside, one
    entry; a therapist (0.75 scale: 0.50 m) at the same place is not entered; a resident who walks
    up to a still robot is not the robot's entry."""
    traj = robot_line([0.0, 0.5, 1.0, 1.4], dt=0.5)
    times = [0.0, 0.5, 1.0, 1.5]
    facing = [(t, "ana", 2.0, 0.0, math.pi, 0.0, 0.0, "", "resident") for t in times]
    d = compute_metrics(traj, people_tracks=tracks_from_rows(facing), robot_radius_m=ROBOT_R).dynamic
    assert d.robot_intimate_entries == 1
    staff = [(t, "eva", 2.0, 0.0, math.pi, 0.0, 0.0, "", "therapist") for t in times]
    assert compute_metrics(traj, people_tracks=tracks_from_rows(staff), robot_radius_m=ROBOT_R).dynamic \
        .robot_intimate_entries == 0
    walker = [(t, "ben", 1.5 - t, 0.0, math.pi, -1.0, 0.0, "", "resident") for t in times]
    d = compute_metrics(robot_line([0.0] * 4, dt=0.5), people_tracks=tracks_from_rows(walker),
                        robot_radius_m=ROBOT_R).dynamic
    assert d.robot_intimate_entries == 0


def test_time_not_moving_skips_the_gap_between_two_missions() -> None:
    """Samples every second at rest, then nothing for 98 s (parked between missions), then two more:
    three one-second intervals at rest, not 101 s."""
    traj = np.array([[t, 1.0, 1.0, 0.0] for t in (0.0, 1.0, 2.0, 100.0, 101.0)])
    d = compute_metrics(traj, people_tracks=tracks_from_rows(still("ana", 5.0, 5.0, [0.0, 101.0])),
                        robot_radius_m=ROBOT_R).dynamic
    assert d.time_not_moving_s == pytest.approx(3.0)
