"""Issue 4 acceptance: every agent as its own process on icra_usecase, checked from the DSR's final
state (the launcher's JSON) and from the merged Rerun recording read back with Rerun's API."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import shapely

from agents.lib.metrics.metrics import read_trajectory_csv
from agents.world.offline import SceneMaps
from scenes.clock import parse_clock
from tests.system.launch_helpers import launch_json
from tests.system.recording import load_store, strips_over_time, texts

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def icra_run(tmp_path_factory: pytest.TempPathFactory) -> dict:
    """One launch shared by the assertions below (a run costs ~30 s of the 2-core budget)."""
    return launch_json("icra_usecase", tmp_path_factory.mktemp("icra") / "launch.log")


def _tv_space() -> shapely.Geometry:
    maps = SceneMaps.load("icra_usecase")
    return maps.at(parse_clock("09:00")).interaction_polygons()["tv"]


def _path_at(paths: list[tuple[float, np.ndarray]], mission_time: str) -> np.ndarray:
    """The first global path planned for the mission starting at ``mission_time``."""
    t0 = parse_clock(mission_time)
    return next(points for when, points in paths if t0 <= when < t0 + 120)


def test_every_mission_completes(icra_run: dict) -> None:
    assert icra_run["returncode"] == 0, icra_run
    assert icra_run["ok"]
    assert set(icra_run["missions"]) == {"m0930", "m1045", "m1115", "m1315"}
    assert all(m["state"] == "done" for m in icra_run["missions"].values())


def test_paths_follow_the_agenda(icra_run: dict) -> None:
    store = load_store(Path(icra_run["rrd"]))
    paths = strips_over_time(store, "/world/decision/path")
    tv = _tv_space()
    before = shapely.LineString(_path_at(paths, "09:30"))
    during = shapely.LineString(_path_at(paths, "11:15"))
    assert before.intersects(tv), "at 09:30 nothing is scheduled: the short way across the TV's space is fine"
    assert not during.intersects(tv), "at 11:15 the serious game runs: the path must avoid the TV's space"
    events = [text for _, text in texts(store, "/events/executive")]
    assert any("mission m1115" in text and "done" in text for text in events)


def test_no_trajectory_point_in_an_intimate_zone(icra_run: dict) -> None:
    trajectory = read_trajectory_csv(Path(icra_run["run_dir"]) / "trajectory.csv")
    assert len(trajectory) > 100
    maps = SceneMaps.load("icra_usecase")
    # People move: judge each sample against the zones of its own time (1 s buckets).
    buckets: dict[int, list[np.ndarray]] = {}
    for row in trajectory:
        buckets.setdefault(int(row[0]), []).append(row)
    for second, rows in buckets.items():
        smap = maps.at(float(second))
        for row in rows:
            assert smap.zone_at(row[1], row[2]) != "intimate", f"robot in an intimate zone at t={row[0]:.1f}"


def test_recording_holds_the_days_metrics(icra_run: dict) -> None:
    store = load_store(Path(icra_run["rrd"]))
    table = store.reader(index="sim_time", contents="/metrics/missions/**").to_arrow_table()
    social = table.column("/metrics/missions/social/psi_intimate_pct:Scalars:scalars").to_pylist()
    baseline = table.column("/metrics/missions/baseline/psi_intimate_pct:Scalars:scalars").to_pylist()
    assert len(social) == 4 and all(row == [0.0] for row in social)
    assert any(row[0] > 0.0 for row in baseline), "the non-social baseline cuts through someone's intimate zone"
