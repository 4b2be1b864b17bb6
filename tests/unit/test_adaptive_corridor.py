"""Psi in the adapted personal space, through `chronav path` on a scene (issue 43).

The adaptive seed: d_r is the robot's diameter plus a safety margin; a side whose room to the wall
d_s = d_i - d_r lies between d_min and d_max has its personal contour moved to d_s, so a robot that
keeps d_s from the person is outside her adapted personal zone. A scene's maps inflate the robot by
a planning clearance (agents/world/building.py PLANNING_MARGIN_M); the adaptation read that inflated
radius as the body's, d_r = 2 x (0.25 + 0.15) + 0.1 = 0.9 m, so in a 1.6 m corridor d_s = 0.35 m fell
below d_min and nothing was adapted: Psi personal 15.4 % on a path 0.825 m from her. The unit twin
in tests/unit/test_metrics.py builds its map directly (robot radius 0.3 m, no planning margin:
d_s = 0.55 m), so it never met the inflated radius.
"""

from __future__ import annotations

import json

from typer.testing import CliRunner

from tests.support import REPO_ROOT
from tools.cli import app

SCENE = REPO_ROOT / "tests" / "data" / "corridor_adaptive.yaml"


def test_a_robot_keeping_the_adapted_distance_is_outside_her_adapted_personal_zone() -> None:
    result = CliRunner().invoke(app, ["path", str(SCENE), "--at", "09:00", "--from", "0.5,0.8", "--to", "9.5,0.8",
                                      "--json"])
    assert result.exit_code == 0, result.output
    metrics = json.loads(result.stdout)["metrics"]
    adapted_distance = (1.6 - 0.35) - (2 * 0.25 + 0.1)
    assert metrics["d_min_person_m"]["ana"] > adapted_distance
    assert metrics["psi_percent"]["personal"] == 0.0 and metrics["psi_percent"]["intimate"] == 0.0
    # the adaptation changed her space: the same path on the unadapted contours crosses her personal zone
    assert metrics["psi_unadapted_zone_percent"]["personal"] > 5.0


def test_the_adaptation_makes_room_for_the_robots_body_not_its_planning_radius() -> None:
    from agents.world.offline import SceneMaps

    smap = SceneMaps.load(SCENE).at(9 * 3600.0)
    adaptation = smap.person_spaces[0].adaptation
    assert adaptation.adapted == ("front",)
    assert smap.params.adaptive.robot_diameter_m == 0.5
    assert smap.params.grid.robot_radius_m > 0.25  # the planner still keeps its clearance


def test_wall_distances_cast_only_near_walls_and_equal_every_ray_cast() -> None:
    """adaptive.wall_distances skips the people farther than the rays' range from every wall; the
    distances are those of casting all four rays of everybody (the definition), bit for bit."""
    import numpy as np
    import shapely

    from agents.lib.socialmap.adaptive import _SIDE_ANGLES, wall_distances
    from agents.lib.socialmap.types import Person

    walls = shapely.MultiLineString([[(0, 0), (20, 0), (20, 20), (0, 20), (0, 0)], [(8, 8), (12, 8)]])
    rng = np.random.default_rng(2)
    people = [Person(f"p{i}", float(x), float(y), float(t)) for i, (x, y, t) in
              enumerate(zip(rng.uniform(-2, 22, 300), rng.uniform(-2, 22, 300), rng.uniform(-4, 4, 300), strict=True))]
    people += [Person("on_range", 3.0, 10.0, 0.0), Person("at_wall", 0.0, 5.0, 1.0)]   # exactly max range; on one
    max_range = 3.0

    def every_ray() -> np.ndarray:          # the definition: all rays cast, as one vectorised call
        starts = np.array([[p.x, p.y] for p in people], dtype=np.float64)
        headings = np.array([[p.theta + a for a in _SIDE_ANGLES] for p in people], dtype=np.float64)
        coords = np.empty((len(people) * 4, 2, 2))
        coords[:, 0, :] = np.repeat(starts, 4, axis=0)
        coords[:, 1, 0] = (starts[:, :1] + max_range * np.cos(headings)).ravel()
        coords[:, 1, 1] = (starts[:, 1:] + max_range * np.sin(headings)).ravel()
        hits = shapely.intersection(shapely.linestrings(coords), walls)
        distances = shapely.distance(shapely.points(coords[:, 0, :]), hits)
        return np.where(shapely.is_empty(hits) | np.isnan(distances), np.inf, distances).reshape(len(people), 4)

    ours = wall_distances(people, walls, max_range)
    np.testing.assert_array_equal(ours, every_ray())
    assert np.isinf(ours).all(axis=1).any() and np.isfinite(ours).any(), "both kinds of people exercised"
