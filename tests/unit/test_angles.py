"""The one angle module (scenes/angles.py): wrap convention [-pi, pi), floats and arrays alike."""

from __future__ import annotations

import math

import numpy as np
import pytest

from scenes.angles import angle_difference, lerp_angle, wrap_angle


@pytest.mark.parametrize(("angle", "wrapped"), [
    (0.0, 0.0), (math.pi, -math.pi), (-math.pi, -math.pi), (3 * math.pi / 2, -math.pi / 2),
    (-3 * math.pi / 2, math.pi / 2), (7 * math.pi + 0.25, -math.pi + 0.25), (-2 * math.pi - 0.5, -0.5),
])
def test_wrap_convention_is_minus_pi_inclusive_to_pi_exclusive(angle: float, wrapped: float) -> None:
    assert wrap_angle(angle) == pytest.approx(wrapped, abs=1e-12)
    assert -math.pi <= wrap_angle(angle) < math.pi


def test_arrays_wrap_element_wise_like_floats() -> None:
    angles = np.linspace(-20.0, 20.0, 401)
    wrapped = wrap_angle(angles)
    assert isinstance(wrapped, np.ndarray) and wrapped.shape == angles.shape
    assert np.all((wrapped >= -math.pi) & (wrapped < math.pi))
    assert np.allclose(np.sin(wrapped), np.sin(angles)) and np.allclose(np.cos(wrapped), np.cos(angles))
    assert [wrap_angle(float(a)) for a in angles] == pytest.approx(wrapped.tolist(), abs=0.0)
    assert np.allclose(angle_difference(angles, 1.0), wrap_angle(angles - 1.0))


def test_difference_and_interpolation_take_the_shorter_turn() -> None:
    assert angle_difference(math.radians(170), math.radians(-170)) == pytest.approx(math.radians(-20))
    assert angle_difference(math.radians(-170), math.radians(170)) == pytest.approx(math.radians(20))
    assert lerp_angle(math.radians(170), math.radians(-170), 0.5) == pytest.approx(-math.pi)
    assert lerp_angle(0.1, 0.5, 0.25) == pytest.approx(0.2)
