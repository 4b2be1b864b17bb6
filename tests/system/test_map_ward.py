"""Issue 17 acceptance (multi-process): the ward on its occupancy map runs with every agent as a
process; the missions complete, the robot's body stays off the map's walls (the bumper and the
planner see the wall cells) and the simulated laser hits the map's walls."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from agents.lib.metrics.metrics import read_trajectory_csv
from agents.world.building import scene_occupancy
from scenes.loader import load_scene
from tests.system.launch_helpers import launch_json
from tests.system.recording import load_store

pytestmark = pytest.mark.slow


def points_over_time(store: object, entity: str) -> list[tuple[float, np.ndarray]]:
    table = store.reader(index="sim_time", contents=entity).to_arrow_table()  # type: ignore[attr-defined]
    column = table.column(f"{entity}:Points2D:positions")
    return [(when.total_seconds(), np.asarray(points, dtype=float).reshape(-1, 2))
            for when, points in zip(table.column("sim_time").to_pylist(), column.to_pylist(), strict=True) if points]


def test_map_ward_missions_complete_off_the_maps_walls(tmp_path: Path) -> None:
    run = launch_json("map_ward", tmp_path / "launch.log")
    assert run["returncode"] == 0 and run["ok"], run
    assert {name: m["state"] for name, m in run["missions"].items()} == \
           {"to_dining": "done", "to_nurses": "done", "to_bedroom_4": "done"}

    scene = load_scene("map_ward").scene
    walls = scene_occupancy(scene)
    assert walls is not None
    trajectory = read_trajectory_csv(Path(run["run_dir"]) / "trajectory.csv")
    clearance = np.array([walls.clearance(x, y, reach_m=1.0) for x, y in trajectory[:, 1:3]])
    assert clearance.min() >= 0.9 * scene.robot.radius - 1e-6, "the robot's body touched a wall of the map"
    assert np.hypot(*(trajectory[-1, 1:3] - (21.5, 3.5))) < 0.5, "the last mission ends in bedroom 4"

    store = load_store(Path(run["rrd"]))
    hits = np.vstack([points for _, points in points_over_time(store, "/world/truth/robot/laser")])
    # every 10th hit (~12,000 of ~120,000): the share on the walls to well under a percent, for a tenth
    # of the ~3 CPU seconds one clearance query per hit cost
    on_walls = np.array([walls.clearance(x, y, reach_m=0.2) <= 0.03 for x, y in hits[::10]])
    assert len(hits) > 1000 and on_walls.mean() > 0.8, f"{on_walls.mean():.0%} of the laser hits are on the map's walls"
