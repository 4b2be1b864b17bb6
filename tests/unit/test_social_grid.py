"""Grid geometry: walls inflated by the robot radius, rooms, doors; adaptive spaces; zone polygons."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely

from agents.lib.socialmap.adaptive import AdaptiveParams
from agents.lib.socialmap.grid import CostPatch, GridParams, GridSpec, compose, static_grid
from agents.lib.planning.search import NoPathFound, warm_up
from agents.lib.socialmap.social_map import SocialMapParams, build_social_map
from agents.lib.planning.plan import plan
from agents.lib.socialmap.types import Person, Room, Wall

RES = 0.05


@pytest.fixture(scope="module", autouse=True)
def _compiled() -> None:
    warm_up()


def test_wall_inflation_is_exactly_the_robot_radius() -> None:
    spec = GridSpec.from_bounds((0.0, 0.0, 5.0, 4.0), RES)
    wall = shapely.LineString([(1.0, 2.0), (4.0, 2.6)])
    grid = static_grid(spec, [Wall(tuple(wall.coords))], [], GridParams(robot_radius_m=0.3))
    xs, ys = np.meshgrid(spec.xs(), spec.ys())
    distance = shapely.distance(wall, shapely.points(xs, ys))
    blocked = np.isinf(grid)
    assert np.all(blocked[distance <= 0.3 - 1e-9])
    assert not np.any(blocked[distance > 0.3 + 1e-9])


def test_rooms_block_the_outside_and_doors_let_the_robot_through() -> None:
    rooms = [Room("left", ((0, 0), (4, 0), (4, 3), (0, 3))), Room("right", ((4, 0), (8, 0), (8, 3), (4, 3)))]
    spec = GridSpec.from_bounds((0.0, 0.0, 8.0, 4.0), RES)
    grid = static_grid(spec, [], rooms, GridParams())
    assert np.isinf(grid[spec.cell_of(2.0, 3.5)]) and grid[spec.cell_of(2.0, 2.5)] == 1.0
    outer = Wall(((0, 0), (8, 0), (8, 3), (0, 3), (0, 0)))

    def wall_with_door(width: float) -> list[Wall]:
        return [outer, Wall(((4, 0), (4, 1.5 - width / 2))), Wall(((4, 1.5 + width / 2), (4, 3)))]

    door = build_social_map((0, 0, 8, 4), wall_with_door(1.2), [], [], [], 0.0, rooms=rooms)
    path = plan(door, (1.0, 1.0), (7.0, 2.0))
    crossing = path.points_m[np.argmin(np.abs(path.points_m[:, 0] - 4.0))]
    assert 0.9 + 0.3 - 1e-9 <= crossing[1] <= 2.1 - 0.3 + 1e-9               # through the door
    narrow = build_social_map((0, 0, 8, 4), wall_with_door(0.5), [], [], [], 0.0, rooms=rooms)
    with pytest.raises(NoPathFound):                                            # 0.5 m < 0.6 m robot
        plan(narrow, (1.0, 1.0), (7.0, 2.0))


def test_compose_takes_the_cellwise_maximum() -> None:
    base = np.ones((4, 4), dtype=np.float32)
    patch_a = CostPatch(slice(0, 2), slice(0, 2), np.array([[2, 0], [4, 2]], dtype=np.float32))
    patch_b = CostPatch(slice(1, 3), slice(1, 3), np.array([[3.5, 0], [0, np.inf]], dtype=np.float32))
    out = compose(base, [patch_a, patch_b])
    expected = np.ones((4, 4))
    expected[0, 0], expected[1, 0], expected[1, 1], expected[2, 2] = 2, 4, 3.5, np.inf
    np.testing.assert_array_equal(out, expected)
    assert base.max() == 1.0                                                     # input untouched


def test_zone_polygons_match_the_analytic_areas() -> None:
    """A level-L region of the four-quadrant Gaussian is four quarter ellipses:
    area = (pi / 4) * 2 ln(1/L) * (s_front + s_rear) * (s_left + s_right)."""
    smap = build_social_map((0, 0, 8, 8), [], [Person("p", 4.0, 4.0, 0.7)], [], [], 0.0)
    (zones,) = smap.zones()
    for name, level in (("intimate", 0.8), ("personal", 0.4), ("social", 0.1)):
        expected = math.pi / 4 * 2 * math.log(1 / level) * (1.0 + 0.5) * (2 / 3 + 2 / 3)
        assert zones.zone(name).area == pytest.approx(expected, rel=0.01)
    assert zones.intimate.contains(shapely.Point(4.0, 4.0))
    assert zones.personal.contains(zones.intimate) and zones.social.contains(zones.personal)
    assert smap.zone_at(4.0 + 0.5 * math.cos(0.7), 4.0 + 0.5 * math.sin(0.7)) == "intimate"   # 0.5 m ahead
    assert smap.zone_at(7.5, 7.5) == "public"


def test_zone_costs_in_the_grid() -> None:
    smap = build_social_map((0, 0, 8, 8), [], [Person("p", 4.0, 4.0, 0.0)], [], [], 0.0)
    ahead = lambda d: float(smap.cost[smap.spec.cell_of(4.0 + d, 4.0)])  # noqa: E731
    # Front sigma 1 m: intimate to 0.67 m, personal to 1.35 m, social to 2.15 m.
    assert math.isinf(ahead(0.6)) and ahead(0.8) == 4.0 and ahead(1.5) == 2.0 and ahead(2.3) == 1.0


def adapted_map(person_y: float, adaptive: bool = True):  # type: ignore[no-untyped-def]
    """A person facing along a corridor (+x), ``person_y`` m from the wall on her right (y = 0)."""
    walls = [Wall(((0.0, 0.0), (10.0, 0.0)), name="right_wall")]
    params = SocialMapParams(adaptive=AdaptiveParams(enabled=adaptive))
    return build_social_map((0, -0.5, 10, 5), walls, [Person("p", 5.0, person_y, 0.0)], [], [], 0.0, params)


def test_adaptive_contour_lands_at_d_s_within_one_cell() -> None:
    """d_i = 1.2 m to the right wall, d_r = 2 * 0.3 + 0.1 = 0.7 m, so d_s = 0.5 m in (0.45, 1.2):
    the right side shrinks until its personal contour (0.90 m unadapted) lies at 0.5 m."""
    smap = adapted_map(1.2)
    (person,) = smap.person_spaces
    assert person.adaptation.adapted == ("right",)
    assert person.adaptation.wall_distance_m[3] == pytest.approx(1.2)
    assert person.space.left_m == pytest.approx(2 / 3)                       # the other side unchanged
    d_s = 1.2 - 0.7
    # On the grid: the farthest cell centre to the right still in the personal zone.
    column = smap.spec.cell_of(5.0, 1.0)[1]
    ys = smap.spec.ys()
    right = ys < 1.2
    density = smap.density_at(np.full(right.sum(), smap.spec.xs()[column]), ys[right])
    farthest = 1.2 - ys[right][density >= 0.4].min()
    assert abs(farthest - d_s) <= RES
    # On the contour polygon: where the ray to the right leaves the personal zone.
    ray = shapely.LineString([(5.0, 1.2), (5.0, 0.0)])
    exit_point = ray.intersection(smap.zones()[0].personal.boundary)
    assert exit_point.geom_type == "Point"
    assert abs((1.2 - exit_point.y) - d_s) <= RES
    # And the robot fits between the wall (inflated) and the personal zone at social cost or less.
    gap = [float(smap.cost[smap.spec.cell_of(5.0, y)]) for y in (0.35, 0.5, 0.65)]
    assert all(c <= 2.0 for c in gap)
    unadapted = adapted_map(1.2, adaptive=False)
    assert float(unadapted.cost[unadapted.spec.cell_of(5.0, 0.5)]) == 4.0


@pytest.mark.parametrize(("person_y", "reason"), [(1.0, "d_s = 0.3 <= d_min"), (2.3, "d_s = 1.6 >= d_max")])
def test_no_adaptation_outside_the_comfort_band(person_y: float, reason: str) -> None:
    (person,) = adapted_map(person_y).person_spaces
    assert person.adaptation.adapted == (), reason
    assert person.space.right_m == pytest.approx(2 / 3)


def test_cell_centres_of_a_window_are_the_numbers_computed_for_that_window() -> None:
    """GridSpec.xs/ys slice one cached array (grid.cell_centres); the definition is
    origin + (k + 0.5) resolution computed for the window's own columns, bit for bit."""
    import numpy as np

    from agents.lib.socialmap.grid import GridSpec

    spec = GridSpec(x0=-3.3, y0=7.1, resolution=0.05, rows=310, cols=420)
    for start, stop in ((0, 420), (17, 18), (133, 260), (400, 420), (5, 5)):
        cols, rows = slice(start, stop), slice(min(start, 310), min(stop, 310))
        np.testing.assert_array_equal(spec.xs(cols), spec.x0 + (np.arange(start, stop, dtype=np.float64) + 0.5) * 0.05)
        np.testing.assert_array_equal(spec.ys(rows), spec.y0 + (np.arange(rows.start, rows.stop, dtype=np.float64)
                                                               + 0.5) * 0.05)
    assert not spec.xs().flags.writeable, "a shared array: callers get a read-only view"
