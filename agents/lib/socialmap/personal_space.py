"""The asymmetric 2-D Gaussian personal space of one person (seed Eqs. 1-4).

Units of the seed's sigmas. The framework seed fixes sigma_h = 2, sigma_r = 1, sigma_s = 4/3 but
never states a unit; its figures come from RoboComp code that multiplies by sigma^2 instead of
dividing (so there the numbers act as inverse lengths), and the adaptive seed's fit
sigma = 1.2 x^-0.97 (sigma falls as the contour distance grows) confirms that reading. We use
Eqs. 2-4 as printed (sigma divides, so sigma is a standard deviation) and make the unit explicit:
``sigma_unit_m`` metres per seed unit, default 0.5 m. Why 0.5 m: it is the only scale consistent
with the seed's Table 1 and 2 measurements under the default zone thresholds (zones.py):

* the non-social path passes 0.51 m in front of senior_1 and is 4.21 % intimate, so the intimate
  contour reaches beyond 0.51 m in front: 0.5 * 2 * sqrt(2 ln 1.25) = 0.67 m (> 0.51);
* Path 2 passes 1.13 m from senior_2 and is 11 % personal: front personal 1.35 m (> 1.13);
* Path 1 passes 1.39 m from senior_1 and is 100 % public: the social contour lies 2.15 m ahead,
  1.43 m to the sides and 1.07 m behind, so that is possible passing behind her; with 1 m per unit
  it would lie 2.86 m to the sides and 2.15 m behind, and no path at 1.39 m could be all public.

It also gives the classic 0.45 m intimate distance (Hall) on the sides. The resulting metric
standard deviations are front 1.0 m, rear 0.5 m, sides 0.67 m, the same as the effective values of
the RoboComp implementation (1/sigma: 1.0, 0.5, 0.75 m) within 0.08 m on the sides.

Eq. 1 as printed has ``gamma_2 (x-x_i)(y-y_i)``; with Eq. 3's ``sin(2 theta)/4`` that is half the
cross term of a rotated ellipse (Kirby 2010 and the RoboComp code use ``2 gamma_2``). We evaluate in
the person's frame, ``u`` ahead and ``v`` to the left: ``exp(-(u^2 / 2 s_u^2 + v^2 / 2 s_v^2))``,
which equals Eq. 1 with ``2 gamma_2`` on each half (tested). ``s_u`` is sigma_h ahead and sigma_r
behind; ``s_v`` is sigma_s on both sides unless the adaptive space (adaptive.py) shrinks one side.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from pydantic import BaseModel, ConfigDict, Field

FloatArray = NDArray[np.float64]


class PersonalSpaceParams(BaseModel):
    """The seed's sigmas (in seed units) and the metric scale that turns them into metres."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    sigma_h: float = Field(2.0, gt=0, description="ahead of the person, seed units (Eqs. 2-4)")
    sigma_r: float = Field(1.0, gt=0, description="behind the person, seed units")
    sigma_s: float = Field(4.0 / 3.0, gt=0, description="to both sides, seed units")
    sigma_unit_m: float = Field(0.5, gt=0, description="metres per seed sigma unit (see module doc)")


@dataclass(frozen=True, slots=True)
class PersonalSpace:
    """Metric standard deviations (m) of one person's asymmetric Gaussian, one per half-axis."""

    front_m: float
    rear_m: float
    left_m: float
    right_m: float

    @classmethod
    def from_params(cls, params: PersonalSpaceParams, scale: float = 1.0) -> PersonalSpace:
        unit = params.sigma_unit_m * scale
        return cls(front_m=params.sigma_h * unit, rear_m=params.sigma_r * unit,
                   left_m=params.sigma_s * unit, right_m=params.sigma_s * unit)

    @property
    def max_m(self) -> float:
        return max(self.front_m, self.rear_m, self.left_m, self.right_m)

    def with_side(self, side: str, sigma_m: float) -> PersonalSpace:
        """A copy with one half-axis replaced (``front``, ``rear``, ``left`` or ``right``)."""
        values = {"front_m": self.front_m, "rear_m": self.rear_m, "left_m": self.left_m, "right_m": self.right_m}
        key = f"{side}_m"
        if key not in values:
            raise ValueError(f"unknown side {side!r}; expected front, rear, left or right")
        values[key] = sigma_m
        return PersonalSpace(**values)


def level_factor(level: float) -> float:
    """Distance from the centre to the ``level`` contour, in standard deviations: sqrt(2 ln 1/level)."""
    if not 0.0 < level < 1.0:
        raise ValueError(f"a contour level of a unit-peak Gaussian must be in (0, 1), got {level}")
    return math.sqrt(2.0 * math.log(1.0 / level))


def contour_distance(sigma_m: float, level: float) -> float:
    """Where a half-axis with standard deviation ``sigma_m`` crosses ``level`` (m)."""
    return sigma_m * level_factor(level)


def sigma_for_contour(distance_m: float, level: float) -> float:
    """The standard deviation that puts the ``level`` contour exactly at ``distance_m``.

    This is the exact inverse the adaptive seed approximated by the fit ``1.2 x^-0.97`` (a fit in
    inverse-length units on a coarse grid); here it is closed-form."""
    return distance_m / level_factor(level)


def gaussian_coefficients(theta: float, sigma: float, sigma_s: float) -> tuple[float, float, float]:
    """gamma_1, gamma_2, gamma_3 of seed Eqs. 2-4 (sigma is sigma_h or sigma_r for the half)."""
    c2, s2, sin2 = math.cos(theta) ** 2, math.sin(theta) ** 2, math.sin(2.0 * theta)
    gamma1 = c2 / (2 * sigma**2) + s2 / (2 * sigma_s**2)
    gamma2 = sin2 / (4 * sigma**2) - sin2 / (4 * sigma_s**2)
    gamma3 = s2 / (2 * sigma**2) + c2 / (2 * sigma_s**2)
    return gamma1, gamma2, gamma3


def asymmetric_gaussian(space: PersonalSpace, x0: float, y0: float, theta: float,
                        xs: ArrayLike, ys: ArrayLike) -> FloatArray:
    """g(x, y) in [0, 1], 1 at the person, for points (xs, ys) (broadcast like numpy).

    Pass a row of x and a column of y to fill a grid window without building a meshgrid."""
    dx = np.asarray(xs, dtype=np.float64) - x0
    dy = np.asarray(ys, dtype=np.float64) - y0
    cos_t, sin_t = math.cos(theta), math.sin(theta)
    a_u, b_u, a_v, b_v = half_axis_factors(space)
    u = dx * cos_t + dy * sin_t
    v = dy * cos_t - dx * sin_t
    su = u * a_u + np.abs(u) * b_u
    sv = v * a_v + np.abs(v) * b_v
    return np.exp(-(su * su + sv * sv))


def half_axis_factors(space: PersonalSpace) -> tuple[float, float, float, float]:
    """(a_u, b_u, a_v, b_v): the scaled half-axis coordinates are su = a_u u + b_u |u| along the
    heading and sv = a_v v + b_v |v| to the left, g = exp(-(su^2 + sv^2)).

    Why this form (no np.where): k(u) u = a u + b |u| with a, b the mean and half-difference of the
    two halves' 1 / (sqrt 2 sigma) (u > 0 gives k_front, u < 0 k_rear).  One definition for
    asymmetric_gaussian and the compiled banding (banded.py)."""
    k_front, k_rear = _inv(space.front_m), _inv(space.rear_m)
    k_left, k_right = _inv(space.left_m), _inv(space.right_m)
    return (0.5 * (k_front + k_rear), 0.5 * (k_front - k_rear), 0.5 * (k_left + k_right), 0.5 * (k_left - k_right))


def _inv(sigma_m: float) -> float:
    return 1.0 / (math.sqrt(2.0) * sigma_m)


def support_radius(space: PersonalSpace, level: float) -> float:
    """Radius beyond which g < ``level`` in every direction (used to size grid windows)."""
    return contour_distance(space.max_m, level)
