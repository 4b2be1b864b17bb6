"""Metrics of the seed's tables on hand-computed trajectories (every expected number by hand)."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest
from shapely.geometry import Polygon, box

from agents.lib.metrics.metrics import (
    MetricsInputError,
    TrajectoryFormatError,
    compute_metrics,
    read_trajectory_csv,
)


def straight_line() -> np.ndarray:
    """0 -> 10 m along +x at 1 m/s, heading 0, sampled every second."""
    t = np.arange(11.0)
    return np.column_stack([t, t, np.zeros(11), np.zeros(11)])


def right_angle_turn() -> np.ndarray:
    """(0,0) -> (4,0) heading 0, turn on the spot to pi/2, then (4,0) -> (4,3)."""
    return np.array([
        [0.0, 0.0, 0.0, 0.0],
        [2.0, 2.0, 0.0, 0.0],
        [4.0, 4.0, 0.0, 0.0],
        [5.0, 4.0, 0.0, math.pi / 2],
        [6.5, 4.0, 1.5, math.pi / 2],
        [8.0, 4.0, 3.0, math.pi / 2],
    ])


def test_straight_line_distance_time_heading_and_clearances() -> None:
    report = compute_metrics(straight_line(), people={"alice": (5.0, 2.0), "bob": (12.0, 0.0)},
                             objects={"table": box(4.0, 3.0, 6.0, 5.0), "crossed": box(3.0, -1.0, 4.0, 1.0)})
    assert report.samples == 11
    assert report.distance_travelled_m == pytest.approx(10.0)
    assert report.duration_s == pytest.approx(10.0)
    assert report.cumulative_heading_change_rad == 0.0
    assert report.d_min_person_m == {"alice": pytest.approx(2.0), "bob": pytest.approx(2.0)}
    assert report.d_min_object_m == {"table": pytest.approx(3.0), "crossed": 0.0}
    # No zones at all: the whole path is public.
    assert report.psi_zone_percent == {"intimate": 0.0, "personal": 0.0, "social": 0.0, "public": 100.0}


def test_right_angle_turn() -> None:
    report = compute_metrics(right_angle_turn(), people={"p": (6.0, 1.0)})
    assert report.distance_travelled_m == pytest.approx(7.0)
    assert report.duration_s == pytest.approx(8.0)
    assert report.cumulative_heading_change_rad == pytest.approx(math.pi / 2)
    # Closest approach to (6, 1) is the vertical leg x = 4: distance 2.
    assert report.d_min_person_m["p"] == pytest.approx(2.0)


def test_heading_change_wraps_across_pi() -> None:
    """3.1 -> -3.1 rad is a 0.0832 rad turn through pi, not 6.2 rad the long way round."""
    traj = np.array([[0.0, 0.0, 0.0, 3.1], [1.0, 1.0, 0.0, -3.1], [2.0, 2.0, 0.0, 3.1]])
    expected = 2 * (2 * math.pi - 6.2)
    assert compute_metrics(traj).cumulative_heading_change_rad == pytest.approx(expected)


def test_psi_exclusive_bands_through_known_squares() -> None:
    """Path y = 0, x 0..10. Intimate covers x in [4,5] (1 m), personal [3,6] (3 m, 2 m exclusive),
    social [2,8] (6 m, 3 m exclusive); public is the remaining 4 m. TV space covers [7,9] (2 m)."""
    zones = {"intimate": box(4.0, -1.0, 5.0, 1.0),
             "personal": box(3.0, -1.0, 6.0, 1.0),
             "social": box(2.0, -1.0, 8.0, 1.0)}
    report = compute_metrics(straight_line(), zones=zones,
                             interaction_spaces={"tv": box(7.0, -1.0, 9.0, 1.0),
                                                 "bed": box(0.0, 5.0, 1.0, 6.0)})
    assert report.psi_zone_percent == {"intimate": pytest.approx(10.0), "personal": pytest.approx(20.0),
                                       "social": pytest.approx(30.0), "public": pytest.approx(40.0)}
    assert report.psi_object_percent == {"tv": pytest.approx(20.0), "bed": 0.0}


def test_psi_is_by_path_length_not_by_time() -> None:
    """The robot crawls through the intimate square (9 of 10 s) but it is 1 m of a 10 m path."""
    traj = np.array([[0.0, 0.0, 0.0, 0.0], [0.4, 4.0, 0.0, 0.0],
                     [9.4, 5.0, 0.0, 0.0], [10.0, 10.0, 0.0, 0.0]])
    report = compute_metrics(traj, zones={"intimate": box(4.0, -1.0, 5.0, 1.0)})
    assert report.psi_zone_percent["intimate"] == pytest.approx(10.0)


def test_robot_that_never_moves_is_classified_by_its_position() -> None:
    traj = np.array([[0.0, 4.5, 0.0, 0.0], [3.0, 4.5, 0.0, 1.0]])
    report = compute_metrics(traj, zones={"personal": box(3.0, -1.0, 6.0, 1.0)})
    assert report.distance_travelled_m == 0.0
    assert report.cumulative_heading_change_rad == pytest.approx(1.0)
    assert report.psi_zone_percent == {"intimate": 0.0, "personal": 100.0, "social": 0.0, "public": 0.0}


def test_report_table_and_json() -> None:
    report = compute_metrics(straight_line(), people={"alice": (5.0, 2.0)},
                             zones={"social": box(2.0, -1.0, 8.0, 1.0)},
                             interaction_spaces={"tv": box(7.0, -1.0, 9.0, 1.0)})
    table = report.to_table()
    rows = dict(table)
    assert len(rows) == len(table), "no two rows with the same label"
    assert rows["path length d_t (m)"] == "10.00"
    assert rows["d_min to alice at the start, path to centre (m)"] == "2.000"
    assert rows["Psi social zone, seeds' contours (% of path)"] == "60.0"
    assert rows["Psi public zone, seeds' contours (% of path)"] == "40.0"
    assert rows["Psi tv's interaction space (% of path)"] == "20.0"
    assert rows["metrics among moving people"].startswith("- (no people's trajectories")
    dumped = json.loads(json.dumps(report.model_dump()))
    assert dumped["psi_basis"] == "path_length"
    assert dumped["psi_zone_percent"]["social"] == pytest.approx(60.0)


@pytest.mark.parametrize(("kwargs", "fragment"), [
    ({"trajectory": np.zeros((3, 3))}, "shape (N, 4)"),
    ({"trajectory": np.zeros((0, 4))}, "no samples"),
    ({"trajectory": [[0, 0, 0, 0], [1, np.nan, 0, 0]]}, "sample 1 is not finite"),
    ({"trajectory": [[1, 0, 0, 0], [0, 1, 0, 0]]}, "time goes backwards at sample 1"),
    ({"trajectory": [[0, 0, 0, 0]], "zones": {"intmate": box(0, 0, 1, 1)}}, "unknown key 'intmate'"),
    ({"trajectory": [[0, 0, 0, 0]], "objects": {"tv": (1, 2)}}, "objects['tv']"),
    ({"trajectory": [[0, 0, 0, 0]], "people": {"ann": (1,)}}, "people['ann']"),
    ({"trajectory": [[0, 0, 0, 0]],
      "interaction_spaces": {"bow": Polygon([(0, 0), (1, 1), (1, 0), (0, 1)])}}, "invalid geometry"),
])
def test_bad_input_names_the_culprit(kwargs: dict, fragment: str) -> None:
    with pytest.raises(MetricsInputError, match=re.escape(fragment)):
        compute_metrics(**kwargs)


def test_read_trajectory_csv_round_trip(tmp_path: Path) -> None:
    path = tmp_path / "run.csv"
    path.write_text("t,x,y,theta\n0,0,0,0\n\n1.5, 1.0 ,2,0.25\n", encoding="utf-8")
    traj = read_trajectory_csv(path)
    np.testing.assert_array_equal(traj, [[0, 0, 0, 0], [1.5, 1.0, 2.0, 0.25]])


@pytest.mark.parametrize(("text", "fragment"), [
    ("", "run.csv:1: empty file"),
    ("x,y,t,theta\n0,0,0,0\n", "run.csv:1: expected header"),
    ("t,x,y,theta\n", "header only"),
    ("t,x,y,theta\n0,0,0,0\n1,0,0\n", "run.csv:3: expected 4 values"),
    ("t,x,y,theta\n0,0,0,0\n1,0,abc,0\n", "run.csv:3: column 'y': 'abc' is not a number"),
    ("t,x,y,theta\n0,0,0,nan\n", "run.csv:2: column 'theta'"),
    ("t,x,y,theta\n2,0,0,0\n\n1,0,0,0\n", "run.csv:4: time goes backwards"),
])
def test_read_trajectory_csv_errors_name_file_and_line(tmp_path: Path, text: str, fragment: str) -> None:
    path = tmp_path / "run.csv"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(TrajectoryFormatError) as info:
        read_trajectory_csv(path)
    assert fragment in str(info.value)


def test_missing_csv_file_is_a_clear_error(tmp_path: Path) -> None:
    with pytest.raises(TrajectoryFormatError, match="absent.csv: no such file"):
        read_trajectory_csv(tmp_path / "absent.csv")


def test_every_metric_has_its_row_in_docs_metrics_md_with_unit_and_source() -> None:
    """One vocabulary: metric_catalog.py and docs/metrics.md list the same metrics, units and sources."""
    from agents.lib.metrics.metric_catalog import CATALOG, SOURCES

    doc = (Path(__file__).resolve().parents[2] / "docs" / "metrics.md").read_text()
    rows = {line.split("|")[1].strip().strip("`"): [c.strip() for c in line.split("|")[1:-1]]
            for line in doc.splitlines() if line.startswith("| `")}
    for metric in CATALOG:
        assert metric.key in rows, metric.key
        _, _, unit, source, *_ = rows[metric.key]
        assert (unit, source) == (metric.unit, metric.source), metric.key
        assert metric.source in SOURCES and metric.unit and metric.definition
    labels = [m.label for m in CATALOG]
    assert len(set(labels)) == len(labels), "no two metrics share a name"


def test_psi_is_measured_on_the_adapted_zones_the_planner_used() -> None:
    """The corridor case: a person 0.35 m from the south wall of a 1.6 m corridor, facing across it.
    The adaptation moves her personal contour in front of her to the room a robot passing at the far
    wall leaves; the planned path passes there: 0 % in her (adapted) personal and social zones, while
    the same path on the unadapted spaces crosses her personal zone."""
    from agents.lib.socialmap.social_map import build_social_map
    from agents.lib.planning.plan import plan
    from agents.lib.socialmap.types import Person, Wall
    from agents.world.offline import path_as_trajectory

    walls = [Wall(((0.0, 0.0), (12.0, 0.0))), Wall(((0.0, 1.6), (12.0, 1.6)))]
    smap = build_social_map((0, 0, 12, 1.6), walls, [Person("ana", 6.0, 0.35, math.pi / 2)], [], [], 0.0)
    assert smap.person_spaces[0].adaptation.adapted == ("front",)
    path = plan(smap, (1.0, 1.0), (11.0, 1.0))
    report = compute_metrics(path_as_trajectory(np.asarray(path.points_m), 0.0, 0.5),
                             zones=smap.zone_polygons(), unadapted_zones=smap.unadapted_zone_polygons())
    assert report.psi_zone_percent["personal"] == 0.0 and report.psi_zone_percent["intimate"] == 0.0
    assert report.psi_unadapted_zone_percent["personal"] > 5.0
    rows = dict(report.to_table())
    assert "Psi personal zone, unadapted contours (% of path)" in rows
