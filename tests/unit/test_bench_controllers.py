"""bench_planner's local-controller keys: the scene is what the keys' names say, and every
controller, chronav's elastic band included, is timed (no time is asserted: that is the bench's)."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np

from scenes.geometry import project_on_segments
from tools.bench.bench_planner import controller_scene

REPO = Path(__file__).resolve().parents[2]


def test_the_scene_has_30_people_near_the_robot_and_20_wall_segments() -> None:
    scene = controller_scene()
    x, y, _ = scene["robot"]
    people, walls = scene["people"], scene["walls"]
    assert people.shape == (30, 5) and walls.shape == (20, 4)
    assert np.all(np.hypot(people[:, 0] - x, people[:, 1] - y) <= 4.0)
    # The robot is in free space: off every wall by more than its body.
    assert project_on_segments((x, y), walls[:, :2], walls[:, 2:]).distance.min() > 0.3


def test_only_controllers_prints_one_flat_json_object_with_the_five_keys() -> None:
    out = subprocess.run([sys.executable, "tools/bench/bench_planner.py", "--only", "controllers", "--repeats", "1"],
                         cwd=REPO, capture_output=True, text=True, check=True, timeout=120)
    result = json.loads(out.stdout)
    names = ("orca", "hrvo", "hl", "social_force", "elastic_band")
    assert set(result) == {f"controller_step_ms_30_{name}" for name in names}
    assert all(isinstance(v, float) and math.isfinite(v) and v > 0 for v in result.values())
