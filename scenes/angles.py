"""Angles in one convention: headings and turns wrapped to [-pi, pi).

Why one module: chronav had three wrap functions with two conventions and a dozen inline copies
of ``(a + pi) % (2 * pi) - pi`` across the agents; a copy that wraps to (-pi, pi] instead of
[-pi, pi) disagrees with the others exactly at a half turn. Every library and agent wraps here.
It lives in ``scenes`` because that is the lowest layer the agents' libraries import (the DSR,
below it, imports nothing of chronav and keeps its own ``dsr.poses.normalize_angle``, which wraps
to (-pi, pi] for RT edges).

The functions take a float or a numpy array (the crowd and the metrics wrap whole columns) and
compute exactly the expression they replace, so results are bit-for-bit those of the copies.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, TypeVar

if TYPE_CHECKING:
    import numpy as np

A = TypeVar("A", float, "np.ndarray")

FULL_TURN = 2.0 * math.pi


def wrap_angle(angle: A) -> A:
    """Map an angle (radians) to [-pi, pi): ``pi`` becomes ``-pi``."""
    return (angle + math.pi) % FULL_TURN - math.pi


def angle_difference(a: A, b: A) -> A:
    """``a - b`` wrapped to [-pi, pi): how far to turn from ``b`` to reach ``a``."""
    return wrap_angle(a - b)


def lerp_angle(a: float, b: float, fraction: float) -> float:
    """The heading ``fraction`` of the way from ``a`` to ``b`` along the shorter turn."""
    return wrap_angle(a + fraction * angle_difference(b, a))
