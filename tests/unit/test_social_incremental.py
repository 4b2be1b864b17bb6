"""The replanner's incremental arrival-time grid (incremental.py) against fresh builds, on random
sequences of social maps: people walking, appearing and leaving, objects moved, the agenda
changed, the building's static map replaced, failed searches and other planners in between."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from agents.lib.agenda.model import ActivityWindow
from agents.lib.planning import replan, search
from agents.lib.socialmap import arrival
from agents.lib.socialmap.grid import GridParams
from agents.lib.planning.replan import Replanner, truncate_down
from agents.lib.planning.search import PlanningError
from agents.lib.socialmap.grid import TimeCosts
from agents.lib.socialmap.social_map import SocialMapParams, build_social_map, build_static_map
from agents.lib.planning.plan import plan
from agents.lib.socialmap.types import Person, SocialObject, Wall
from scenes.geometry import Circle, Rectangle, Trapezoid

H = 3600.0
SIZE = (12.0, 8.0)
PARAMS = SocialMapParams(grid=GridParams(resolution_m=0.1))
WALLS = [Wall(((0, 0), (12, 0), (12, 8), (0, 8), (0, 0)), name="outer"), Wall(((6, 0), (6, 5)), name="inner")]
START, GOAL = (0.6, 0.6), (11.4, 0.6)


@pytest.fixture(scope="module", autouse=True)
def _compiled() -> None:
    search.warm_up()
    replan.warm_up()
    arrival.warm_up()


def objects() -> list[SocialObject]:
    return [SocialObject("tv", "tv", 3.0, 0.2, math.pi / 2, Rectangle(0.2, 1.2), Trapezoid(2.5, 1.2, 3.0)),
            SocialObject("table", "table", 9.0, 3.0, 0.0, Circle(0.6), Circle(1.4), forbidden_while_active=True),
            SocialObject("bed", "bed", 3.0, 6.5, 0.0, Rectangle(2.0, 0.9), Rectangle(2.6, 1.8))]


FORCED = {2: "agenda", 3: "object", 5: "walk", 8: "agenda", 11: "jump"}   # every sequence has these


def step_world(rng: np.random.Generator, people: list[Person], things: list[SocialObject],
               agenda: list[ActivityWindow], kind: str | None = None) -> None:
    """One change of the world (``kind``, or a random one), in place."""
    if kind is None:
        kind = str(rng.choice(["walk", "walk", "walk", "jump", "object", "agenda", "arrive", "leave", "nothing"]))
    if kind in ("walk", "jump") and people:
        k = int(rng.integers(len(people)))
        step = 0.2 if kind == "walk" else 3.0
        p = people[k]
        people[k] = dataclasses.replace(p, x=float(np.clip(p.x + rng.uniform(-step, step), 0.8, 11.2)),
                                        y=float(np.clip(p.y + rng.uniform(-step, step), 1.2, 7.2)),
                                        vx=float(rng.choice([0.0, 0.5])), vy=0.0)
    elif kind == "object":
        k = int(rng.integers(len(things)))
        things[k] = dataclasses.replace(things[k], x=float(things[k].x + rng.uniform(-0.5, 0.5)))
    elif kind == "agenda":
        k = int(rng.integers(len(agenda)))
        shift = float(rng.choice([-1800.0, -600.0, 600.0]))
        agenda[k] = dataclasses.replace(agenda[k], start_s=agenda[k].start_s + shift, end_s=agenda[k].end_s + shift,
                                        cancelled=bool(rng.random() < 0.2))
    elif kind == "arrive":
        people.append(Person(f"p{rng.integers(10**6)}", float(rng.uniform(1, 11)), float(rng.uniform(1.5, 7)),
                             float(rng.uniform(-math.pi, math.pi))))
    elif kind == "leave" and people:
        people.pop(int(rng.integers(len(people))))


def expected_bounds(costs: TimeCosts) -> np.ndarray:
    """Every cell's lower bound computed afresh: what the replanner's bounds must hold."""
    flat = costs.grid.reshape(-1).astype(np.float64)
    coded = flat < 0
    values = flat.copy()
    values[coded] = costs.table.min(axis=1)[(-flat[coded]).astype(int) - 1]
    return truncate_down(values)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_incremental_grid_is_the_fresh_one_and_replans_cost_what_fresh_plans_do(seed: int) -> None:
    rng = np.random.default_rng(seed)
    people = [Person(f"p{k}", float(rng.uniform(1, 11)), float(rng.uniform(1.5, 7)), float(rng.uniform(-3, 3)))
              for k in range(5)]
    things = objects()
    agenda = [ActivityWindow("tv", 11 * H + 300.0, 12 * H), ActivityWindow("table", 11 * H - 600.0, 11 * H + 900.0),
              ActivityWindow("bed", 13 * H, 14 * H)]
    static = build_static_map((0, 0, *SIZE), WALLS, (), PARAMS)
    replanner = Replanner()
    robot = START
    for step in range(14):
        if step:
            step_world(rng, people, things, agenda, FORCED.get(step))
        if step == 7:   # the building map rebuilt: a new static grid, the same values
            static = build_static_map((0, 0, *SIZE), WALLS, (), PARAMS)
        t_s = 11 * H + 0.2 * step
        smap = build_social_map((0, 0, *SIZE), WALLS, people, things, agenda, t_s, PARAMS, static=static)
        built = smap.time_costs(0.25, incremental=replanner.costs)
        fresh = smap.time_costs(0.25)
        assert built is not None and fresh is not None
        assert np.array_equal(built.grid, fresh.grid) and built.grid is not fresh.grid
        assert np.array_equal(built.table, fresh.table) and built.cells_per_bin == fresh.cells_per_bin
        if step == 4:   # another planner's grid searched in between: the bounds follow it, then come back
            plan(smap, robot, GOAL, planner="departure", replanner=replanner)
        if step == 9:   # a search that fails after the grid was built
            with pytest.raises(PlanningError):
                plan(smap, (6.0, 2.0), GOAL, replanner=replanner)   # in the inner wall
        try:
            replanned = plan(smap, robot, GOAL, replanner=replanner)
        except PlanningError:
            with pytest.raises(PlanningError):
                plan(smap, robot, GOAL)
            continue
        assert np.array_equal(replanner._bounds, expected_bounds(replanner.costs.current).reshape(-1))
        assert replanned.cost == pytest.approx(plan(smap, robot, GOAL).cost, rel=1e-7)
        robot = tuple(replanned.points_m[min(3, len(replanned.points_m) - 1)])


def test_only_changed_windows_are_recomposed() -> None:
    """A person moving far from every interaction space recomposes their own windows and encodes
    no space again; one walking into a space encodes them all again; the table always follows
    the agenda."""
    things = objects()
    agenda = [ActivityWindow("tv", 11 * H + 300.0, 12 * H)]
    static = build_static_map((0, 0, *SIZE), WALLS, (), PARAMS)
    replanner = Replanner()

    def built(people: list[Person], agenda: list[ActivityWindow]) -> TimeCosts:
        smap = build_social_map((0, 0, *SIZE), WALLS, people, things, agenda, 11 * H, PARAMS, static=static)
        costs = smap.time_costs(0.25, incremental=replanner.costs)
        assert costs is not None
        fresh = smap.time_costs(0.25)
        assert fresh is not None and np.array_equal(costs.grid, fresh.grid) and np.array_equal(costs.table, fresh.table)
        return costs

    built([Person("ann", 9.0, 7.2, 0.0)], agenda)
    assert replanner.costs.last_windows is None and replanner.costs.last_encoded
    built([Person("ann", 9.2, 7.2, 0.0)], agenda)
    windows = replanner.costs.last_windows
    assert windows and not replanner.costs.last_encoded
    assert all(r0 >= 40 and c0 >= 60 for r0, _, c0, _ in windows)   # around her only (y >= 4 m, x >= 6 m)
    before = built([Person("ann", 9.2, 7.2, 0.0)], agenda).table.copy()
    assert replanner.costs.last_windows == [] and not replanner.costs.last_encoded
    moved = [dataclasses.replace(agenda[0], start_s=agenda[0].start_s - 1800.0)]
    after = built([Person("ann", 9.2, 7.2, 0.0)], moved).table
    assert not np.array_equal(before, after) and not replanner.costs.last_encoded
    built([Person("ann", 3.0, 1.5, 0.0)], moved)   # in front of the TV
    assert replanner.costs.last_encoded
