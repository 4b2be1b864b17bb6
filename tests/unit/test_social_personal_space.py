"""Asymmetric Gaussian (seed Eqs. 1-4), its contours, roles and parameter validation."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pydantic import ValidationError

from agents.lib.socialmap.personal_space import (
    PersonalSpace,
    PersonalSpaceParams,
    asymmetric_gaussian,
    contour_distance,
    gaussian_coefficients,
    sigma_for_contour,
)
from agents.lib.socialmap.roles import RoleParams, role_scale
from agents.lib.socialmap.social_map import SocialMapParams
from agents.lib.socialmap.types import Person, SocialMapInputError


def test_default_sigmas_in_metres() -> None:
    space = PersonalSpace.from_params(PersonalSpaceParams())
    assert (space.front_m, space.rear_m, space.left_m, space.right_m) == pytest.approx((1.0, 0.5, 2 / 3, 2 / 3))


@pytest.mark.parametrize("theta", [0.0, 0.7, 2.5, -1.9])
def test_matches_seed_equation_with_full_cross_term(theta: float) -> None:
    """exp(-(g1 dx^2 + 2 g2 dx dy + g3 dy^2)) with Eqs. 2-4, sigma_h ahead and sigma_r behind."""
    params = PersonalSpaceParams()
    unit = params.sigma_unit_m
    space = PersonalSpace.from_params(params)
    rng = np.random.default_rng(3)
    x0, y0 = 1.5, -2.0
    pts = rng.uniform(-3, 3, size=(200, 2))
    dx, dy = pts[:, 0], pts[:, 1]
    ahead = dx * math.cos(theta) + dy * math.sin(theta) > 0
    expected = np.empty(len(pts))
    for i in range(len(pts)):
        sigma = (params.sigma_h if ahead[i] else params.sigma_r) * unit
        g1, g2, g3 = gaussian_coefficients(theta, sigma, params.sigma_s * unit)
        expected[i] = math.exp(-(g1 * dx[i] ** 2 + 2 * g2 * dx[i] * dy[i] + g3 * dy[i] ** 2))
    got = asymmetric_gaussian(space, x0, y0, theta, x0 + dx, y0 + dy)
    np.testing.assert_allclose(got, expected, rtol=1e-12)


def test_peak_and_asymmetry() -> None:
    space = PersonalSpace.from_params(PersonalSpaceParams())
    assert asymmetric_gaussian(space, 0, 0, 0, 0.0, 0.0) == pytest.approx(1.0)
    ahead = asymmetric_gaussian(space, 0, 0, 0, 1.0, 0.0)
    behind = asymmetric_gaussian(space, 0, 0, 0, -1.0, 0.0)
    side = asymmetric_gaussian(space, 0, 0, 0, 0.0, 1.0)
    assert ahead > side > behind
    assert ahead == pytest.approx(math.exp(-0.5))          # one sigma ahead (1 m)


def test_contour_distance_and_its_inverse() -> None:
    assert contour_distance(1.0, math.exp(-0.5)) == pytest.approx(1.0)
    for level in (0.8, 0.4, 0.1):
        for d in (0.3, 1.0, 2.2):
            sigma = sigma_for_contour(d, level)
            space = PersonalSpace(sigma, sigma, sigma, sigma)
            assert asymmetric_gaussian(space, 0, 0, 0, d, 0.0) == pytest.approx(level)
    with pytest.raises(ValueError, match="contour level"):
        contour_distance(1.0, 1.5)


def test_seed_table_consistency_of_the_metric_scale() -> None:
    """The module doc's argument: intimate reaches past 0.51 m ahead, social ends before 1.39 m behind."""
    space = PersonalSpace.from_params(PersonalSpaceParams())
    assert contour_distance(space.front_m, 0.8) > 0.51
    assert contour_distance(space.rear_m, 0.1) < 1.39
    assert contour_distance(space.left_m, 0.8) == pytest.approx(0.45, abs=0.005)


def test_role_scales_and_unknown_role() -> None:
    params = RoleParams()
    assert role_scale(Person("s", 0, 0, 0, role="staff"), params) < 1.0
    assert role_scale(Person("n", 0, 0, 0, role="new_resident"), params) > 1.0
    with pytest.raises(SocialMapInputError, match="'bob'.*unknown role 'pilot'"):
        role_scale(Person("bob", 0, 0, 0, role="pilot"), params)
    with pytest.raises(ValidationError):
        RoleParams(scales={"staff": 0.0})


def test_params_reject_unknown_keys_and_bad_values() -> None:
    with pytest.raises(ValidationError, match="sigma_hh"):
        SocialMapParams.model_validate({"personal_space": {"sigma_hh": 2}})
    with pytest.raises(ValidationError, match="intimate > personal > social"):
        SocialMapParams.model_validate({"zones": {"intimate": 0.3, "personal": 0.4}})
    with pytest.raises(SocialMapInputError, match="person 'p': x must be finite"):
        Person("p", math.nan, 0.0, 0.0)
