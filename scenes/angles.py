"""Angles: the one place headings are wrapped, differenced and interpolated.

Convention: a wrapped angle lies in [-pi, pi) (``(a + pi) mod 2 pi - pi``), for a float or
element-wise for a numpy array.  Why here: scenes is the lowest layer that handles headings
(poses in scene files), and everything above it (crowd, perception, socialmap, world, agents,
tools) imports downward to it.  The one other wrap is ``dsr.poses.normalize_angle`` (RT edges,
(-pi, pi]): the DSR imports nothing of chronav, so it keeps its own.
"""

from __future__ import annotations

import math
from typing import TypeVar

import numpy as np
from numpy.typing import NDArray

#: a heading or an array of headings (radians); the functions return the same kind
Angle = TypeVar("Angle", float, NDArray[np.floating])


def wrap_angle(angle: Angle) -> Angle:
    """``angle`` mapped to [-pi, pi) (element-wise for an array).  A value a hair below -pi may
    round to pi, as with any float modulo."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi  # type: ignore[return-value]


def angle_difference(a: Angle, b: Angle | float) -> Angle:
    """``a - b`` wrapped to [-pi, pi): how far to turn from ``b`` to reach ``a``."""
    return wrap_angle(a - b)  # type: ignore[operator]


def lerp_angle(a: float, b: float, fraction: float) -> float:
    """The heading ``fraction`` of the way from ``a`` to ``b`` along the shorter turn."""
    return wrap_angle(a + fraction * angle_difference(b, a))
