"""The one angle convention (scenes/angles.py): [-pi, pi), floats and numpy arrays alike, and
bit-for-bit the inline expression it replaced across the agents."""

from __future__ import annotations

import math

import numpy as np
import pytest

from scenes import geometry
from scenes.angles import angle_difference, lerp_angle, wrap_angle


@pytest.mark.parametrize(("angle", "wrapped"), [
    (0.0, 0.0), (math.pi, -math.pi), (-math.pi, -math.pi), (3 * math.pi, -math.pi),
    (3 * math.pi / 2, -math.pi / 2), (-3 * math.pi / 2, math.pi / 2), (2 * math.pi, 0.0), (7.0, 7.0 - 2 * math.pi),
])
def test_wrap_maps_to_minus_pi_inclusive_pi_exclusive(angle: float, wrapped: float) -> None:
    assert wrap_angle(angle) == pytest.approx(wrapped, abs=1e-12)
    assert -math.pi <= wrap_angle(angle) < math.pi


def test_wrap_is_exactly_the_expression_it_replaced_on_floats_and_arrays() -> None:
    rng = np.random.default_rng(34)
    values = rng.uniform(-50, 50, 2000)
    inline = (values + math.pi) % (2 * math.pi) - math.pi
    assert np.array_equal(wrap_angle(values), inline)
    assert all(wrap_angle(float(v)) == float(w) for v, w in zip(values, inline))


def test_difference_is_the_shorter_turn_and_lerp_follows_it() -> None:
    assert angle_difference(math.radians(10), math.radians(350)) == pytest.approx(math.radians(20))
    assert angle_difference(math.radians(350), math.radians(10)) == pytest.approx(math.radians(-20))
    assert lerp_angle(math.radians(170), math.radians(-170), 0.5) == pytest.approx(-math.pi)  # across the seam
    assert lerp_angle(0.0, 1.0, 0.25) == pytest.approx(0.25)


def test_geometry_reexports_the_same_functions() -> None:
    assert geometry.wrap_angle is wrap_angle and geometry.angle_difference is angle_difference
    assert geometry.lerp_angle is lerp_angle
