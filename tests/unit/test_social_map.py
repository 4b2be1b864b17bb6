"""The social map and planner on small scenes whose right answer is known (issue 3 acceptance)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely

from agents.lib.agenda.chronemics import ChronemicsParams
from agents.lib.socialmap.grid import GridParams
from agents.lib.planning.search import GoalOccupied, NoPathFound, SearchWorkspace, StartOccupied, warm_up
from agents.lib.planning.plan import plan
from agents.lib.planning.protocol import PlannerParams
from agents.lib.socialmap.social_map import SocialMapParams, build_social_map, build_static_map
from agents.lib.agenda.model import ActivityWindow
from agents.lib.socialmap.types import Person, SocialMapInputError, SocialObject, Wall
from scenes.geometry import Rectangle, Trapezoid

H = 3600.0


@pytest.fixture(scope="module", autouse=True)
def _compiled() -> None:
    warm_up()


def box(width: float, height: float) -> list[Wall]:
    return [Wall(((0, 0), (width, 0), (width, height), (0, height), (0, 0)), name="outer")]


def path_zones(smap, path) -> list[str]:  # type: ignore[no-untyped-def]
    return [smap.zone_at(x, y) for x, y in path.points_m]


def cells_inside(polygon, path) -> int:  # type: ignore[no-untyped-def]
    return int(shapely.intersects_xy(polygon, path.points_m[:, 0], path.points_m[:, 1]).sum())


def test_social_path_never_enters_an_intimate_zone_while_the_baseline_does() -> None:
    """Ann stands 0.6 m from the bottom wall facing the room; the wall side is too narrow, so a
    path must pass in front of her. The baseline only avoids her body (0.55 m with the robot)."""
    ann = Person("ann", 5.0, 0.6, math.pi / 2)
    smap = build_social_map((0, 0, 10, 4), box(10, 4), [ann], [], [], 0.0)
    social = plan(smap, (1.0, 0.8), (9.0, 0.8))
    baseline = plan(smap, (1.0, 0.8), (9.0, 0.8), planner="baseline")
    assert "intimate" not in path_zones(smap, social)
    assert "intimate" in path_zones(smap, baseline)
    dist = lambda p: float(np.hypot(p.points_m[:, 0] - 5.0, p.points_m[:, 1] - 0.6).min())  # noqa: E731
    assert dist(baseline) >= 0.55 - 0.05 and dist(baseline) < 0.67      # body respected, intimate not
    assert baseline.length_m < social.length_m
    # The zone polygons agree with the grid: the social path stays out of the intimate polygon.
    assert cells_inside(smap.zone_polygons()["intimate"], social) == 0
    assert cells_inside(smap.zone_polygons()["intimate"], baseline) > 0


def tv_room(t_s: float, params: SocialMapParams | None = None, forbidden: bool = False,
            activities: list[ActivityWindow] | None = None, width: float = 12.0):  # type: ignore[no-untyped-def]
    """A TV on the bottom wall of a width x 6 m room, 1 m before the right end; its trapezoid
    spans the room but for a 0.6 m strip at the top (the detour)."""
    tv = SocialObject("tv", "tv", width - 6.0, 0.1, math.pi / 2, Rectangle(0.2, 1.2), Trapezoid(5.0, 1.2, 9.0),
                      forbidden_while_active=forbidden)
    acts = activities if activities is not None else [ActivityWindow("tv", 11 * H, 12 * H)]
    return build_social_map((0, 0, width, 6), box(width, 6), [], [tv], acts, t_s, params)


def test_tv_space_is_crossed_with_nothing_scheduled_and_avoided_during_the_activity() -> None:
    free = tv_room(9 * H)
    busy = tv_room(11.5 * H)
    assert (free.object_spaces[0].r, busy.object_spaces[0].r) == (1.5, 3.5)
    crossing = plan(free, (1.0, 3.0), (11.0, 3.0))
    detour = plan(busy, (1.0, 3.0), (11.0, 3.0))
    tv_space = free.object_spaces[0].interaction
    assert cells_inside(tv_space, crossing) > 50
    assert cells_inside(tv_space, detour) == 0
    assert detour.length_m > crossing.length_m + 2.0
    # Forbidden while active: an obstacle, so a goal inside it is refused; after the end it is not.
    forbidden = tv_room(11.5 * H, forbidden=True)
    assert math.isinf(forbidden.cost[forbidden.spec.cell_of(6.0, 3.0)])
    with pytest.raises(GoalOccupied):
        plan(forbidden, (1.0, 3.0), (6.0, 3.0), planner="departure")
    assert plan(tv_room(12.5 * H, forbidden=True), (1.0, 3.0), (6.0, 3.0)).cost > 0


def two_corridors(t_s: float, activity: ActivityWindow):  # type: ignore[no-untyped-def]
    """30 m x 8 m, split by a wall at y = 4 (x 3..27) into a bottom and a top corridor joined at
    both ends. A TV on the bottom wall at x = 15 has a space (forbidden while active) spanning the
    whole bottom corridor; the top corridor is the ~7 m longer way round. Ramps are 0 so that R
    jumps at the start and end (with the 45-minute default a 30 m scene would show no change)."""
    params = SocialMapParams(chronemics=ChronemicsParams(ramp_before_s=0, ramp_after_s=0),
                             grid=GridParams(resolution_m=0.1))
    walls = [*box(30, 8), Wall(((3.0, 4.0), (27.0, 4.0)), name="middle")]
    tv = SocialObject("tv", "tv", 15.0, 0.1, math.pi / 2, Rectangle(0.2, 1.2), Trapezoid(3.8, 1.2, 6.0),
                      forbidden_while_active=True)
    return build_social_map((0, 0, 30, 8), walls, [], [tv], [activity], t_s, params)


def test_arrival_time_chronemics_differs_from_departure_time() -> None:
    """The therapy starts 30 s after departure; the TV is 12 m away, reached after ~50 s at the
    default 0.25 m/s: only arrival-time pricing sees the therapy and takes the top corridor."""
    t0 = 11 * H - 30.0
    smap = two_corridors(t0, ActivityWindow("tv", 11 * H, 12 * H))
    start, goal = (1.0, 2.0), (29.0, 2.0)
    tv_space = smap.object_spaces[0].interaction
    departure = plan(smap, start, goal, planner="departure")
    arrival = plan(smap, start, goal, planner="social")
    assert smap.object_spaces[0].r == 1.5 and not smap.object_spaces[0].active
    assert cells_inside(tv_space, departure) > 20                  # the seeds' planner crosses
    assert cells_inside(tv_space, arrival) == 0                    # ours goes round, by the top
    assert float(arrival.points_m[:, 1].max()) > 4.0
    assert arrival.cost > departure.cost
    # A robot fast enough to pass before the start (2 m/s: 14 s for the whole trip) crosses too.
    sprint = plan(smap, start, goal, planner="social", cruise_speed_mps=2.0)
    assert cells_inside(tv_space, sprint) > 20
    assert sprint.cost == pytest.approx(departure.cost, rel=1e-6)
    # The mirror case: the therapy ends 30 s after departure; departure pricing goes round.
    ending = two_corridors(11 * H - 30.0, ActivityWindow("tv", 10 * H, 11 * H))
    assert ending.object_spaces[0].forbidden
    assert cells_inside(tv_space, plan(ending, start, goal, planner="departure")) == 0
    assert cells_inside(tv_space, plan(ending, start, goal, planner="social")) > 20


def test_arrival_time_equals_departure_time_when_nothing_changes() -> None:
    smap = tv_room(11.5 * H)          # mid-therapy: R = 3.5 throughout any short trip
    a = plan(smap, (1.0, 3.0), (11.0, 3.0), planner="social")
    d = plan(smap, (1.0, 3.0), (11.0, 3.0), planner="departure")
    dj = plan(smap, (1.0, 3.0), (11.0, 3.0), planner="social", method="dijkstra")
    assert a.cost == pytest.approx(d.cost, rel=1e-6)
    assert dj.cost == pytest.approx(d.cost, rel=1e-6)


def test_rebuild_with_static_map_and_workspace() -> None:
    walls = box(10, 4)
    static = build_static_map((0, 0, 10, 4), walls)
    workspace = SearchWorkspace()
    costs = []
    for x in (3.0, 5.0, 7.0):           # a person walking along the room
        smap = build_social_map((0, 0, 10, 4), walls, [Person("p", x, 2.0, 0.0)], [], [], 0.0, static=static)
        costs.append(plan(smap, (1.0, 1.0), (9.0, 3.0), workspace=workspace).cost)
    fresh = build_social_map((0, 0, 10, 4), walls, [Person("p", 7.0, 2.0, 0.0)], [], [], 0.0)
    assert plan(fresh, (1.0, 1.0), (9.0, 3.0)).cost == pytest.approx(costs[-1])
    with pytest.raises(SocialMapInputError, match="static map was built for other"):
        build_social_map((0, 0, 10, 4), walls[:0], [], [], [], 0.0, static=static)


def test_layers_and_object_state_for_display() -> None:
    smap = tv_room(10.5 * H)          # 30 min before: R = 1.5 + 2 * 15/45
    space = smap.object_spaces[0]
    assert space.r == pytest.approx(1.5 + 2 * 15 / 45) and space.band == 1 and not space.active
    objects_layer = smap.layer("objects")
    assert float(objects_layer.max()) == pytest.approx(space.r, rel=1e-6)
    assert float(smap.layer("people").max()) == 1.0            # nobody in the room
    assert np.isinf(smap.layer("walls")).any()
    assert set(smap.interaction_polygons()) == {"tv"}
    with pytest.raises(ValueError, match="unknown layer"):
        smap.layer("furniture")


def test_bad_input_is_named() -> None:
    with pytest.raises(SocialMapInputError, match="duplicate person name 'p'"):
        build_social_map((0, 0, 5, 5), [], [Person("p", 1, 1, 0), Person("p", 2, 2, 0)], [], [], 0.0)
    with pytest.raises(SocialMapInputError, match="bounds must be"):
        build_social_map((0, 0, -5, 5), [], [], [], [], 0.0)
    with pytest.raises(SocialMapInputError, match="t_s must be finite"):
        build_social_map((0, 0, 5, 5), [], [], [], [], math.inf)
    lost = ActivityWindow("piano", 0.0, 10.0)
    smap = build_social_map((0, 0, 5, 5), [], [], [], [lost], 5.0)
    assert smap.unmatched_activities == (lost,) and smap.activities == ()


def test_start_in_intimate_zone_is_refused() -> None:
    smap = build_social_map((0, 0, 6, 4), [], [Person("p", 3.0, 2.0, 0.0)], [], [], 0.0)
    with pytest.raises(StartOccupied):
        plan(smap, (3.6, 2.0), (0.5, 0.5))                  # 0.6 m in front of p: intimate
    with pytest.raises(NoPathFound):
        walled = build_social_map((0, 0, 6, 4), [Wall(((3.0, 0.0), (3.0, 4.0)))], [], [], [], 0.0)
        plan(walled, (1.0, 2.0), (5.0, 2.0))


def test_planner_params_are_used() -> None:
    """arrival_time False makes the social planner price R at departure (the seeds' setting)."""
    smap = tv_room(9 * H)
    slow = PlannerParams(arrival_time=False)
    assert plan(smap, (1.0, 3.0), (11.0, 3.0), params=slow).cost == pytest.approx(
        plan(smap, (1.0, 3.0), (11.0, 3.0), planner="departure").cost)
