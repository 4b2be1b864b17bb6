"""Grouping by Omega_d / Omega_theta, Eqs. 5-8, and what grouping changes in the zones."""

from __future__ import annotations

import math

import pytest

from agents.lib.socialmap.groups import (
    GroupParams,
    are_neighbours,
    density_contribution,
    group_people,
    group_threshold,
)
from agents.lib.socialmap.personal_space import PersonalSpace, PersonalSpaceParams
from agents.lib.socialmap.social_map import SocialMapParams, build_social_map
from agents.lib.socialmap.types import Person

SPACE = PersonalSpace.from_params(PersonalSpaceParams())
PARAMS = GroupParams()


def facing_pair(gap: float = 1.5) -> list[Person]:
    return [Person("a", 0.0, 0.0, 0.0), Person("b", gap, 0.0, math.pi)]


def back_to_back(gap: float = 1.5) -> list[Person]:
    return [Person("a", 0.0, 0.0, math.pi), Person("b", gap, 0.0, 0.0)]


def test_neighbour_rule() -> None:
    assert are_neighbours(*facing_pair(), PARAMS)
    assert not are_neighbours(*back_to_back(), PARAMS)
    assert not are_neighbours(*facing_pair(gap=2.5), PARAMS)                         # beyond Omega_d
    side_by_side = [Person("a", 0.0, 0.0, math.pi / 2), Person("b", 1.0, 0.0, math.pi / 2)]
    assert are_neighbours(*side_by_side, PARAMS)                                     # bearing at pi/2
    assert not are_neighbours(*side_by_side, GroupParams(omega_theta_rad=1.0))
    told = [Person("a", 0.0, 0.0, math.pi, interacting_with=("b",)), Person("b", 5.0, 0.0, 0.0)]
    assert are_neighbours(*told, PARAMS)                                             # DSR 'interacting'


def test_groups_k_delta_phi() -> None:
    people = [*facing_pair(), Person("c", 10.0, 10.0, 0.0)]
    groups = group_people(people, [SPACE] * 3, PARAMS)
    by_names = {g.names: g for g in groups}
    assert set(by_names) == {("a", "b"), ("c",)}
    pair = by_names[("a", "b")]
    delta = math.exp(-0.5 * 1.5**2)            # 1.5 m straight ahead, sigma_h = 1 m: Eq. 6
    assert density_contribution(people[0], SPACE, people[1]) == pytest.approx(delta)
    assert (pair.k, pair.delta) == (1, pytest.approx(delta))
    assert pair.phi == pytest.approx(group_threshold(1, delta)) == pytest.approx(1 + delta)
    assert (by_names[("c",)].k, by_names[("c",)].phi) == (0, 1.0)


def test_group_fills_the_space_between_talkers_but_not_between_strangers() -> None:
    """Facing at 1.5 m: each Gaussian gives exp(-0.5 * 0.75^2) = 0.75 at the midpoint, below the
    intimate level alone; summed within the group it is 1.51 (forbidden). Back to back, the two
    are separate groups (max): 0.75 m behind each, exp(-0.5 * 1.5^2) = 0.32, social only."""
    bounds = (-3.0, -3.0, 4.5, 3.0)
    talkers = build_social_map(bounds, [], facing_pair(), [], [], 0.0)
    strangers = build_social_map(bounds, [], back_to_back(), [], [], 0.0)
    assert talkers.zone_at(0.75, 0.0) == "intimate"
    assert math.isinf(talkers.cost[talkers.spec.cell_of(0.75, 0.0)])
    assert len(strangers.groups) == 2
    assert strangers.zone_at(0.75, 0.0) == "social"
    assert strangers.density_at(0.75, 0.0) == pytest.approx(math.exp(-0.5 * 1.5**2))
    summed = build_social_map(bounds, [], back_to_back(), [], [], 0.0,
                              SocialMapParams(groups=GroupParams(composition="sum")))
    assert len(summed.groups) == 1                     # seed Eq. 5 over everybody
    assert summed.zone_at(0.75, 0.0) == "personal"     # 2 * 0.32 = 0.65


def test_group_zones_merge_and_core() -> None:
    smap = build_social_map((-3.0, -3.0, 4.5, 3.0), [], facing_pair(), [], [], 0.0)
    zones = smap.zones()
    assert len(zones) == 1 and zones[0].names == ("a", "b")
    assert zones[0].intimate.geom_type == "Polygon"      # one blob around both people
    assert zones[0].core.contains(zones[0].core.centroid)
    assert zones[0].core.area > 0 and zones[0].intimate.contains(zones[0].core)
