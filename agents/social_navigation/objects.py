"""Footprint and interaction-space polygons of objects, posed by the object's (x, y, theta).

Shapes are defined in the object's frame (+x is where the object faces, e.g. the TV screen):
a rectangle is centred on the object (shifted ``offset`` along +x), a circle is centred on it and
a trapezoid starts at the object with its near edge and widens to its far edge ``height`` ahead
(seed section 4.2, Fig. 7; Eqs. 10-12 give the areas, which the polygons reproduce).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import shapely
from numpy.typing import NDArray
from shapely.geometry import Polygon

from agents.social_navigation.types import Circle, Rectangle, Shape, SocialObject, Trapezoid

CIRCLE_QUAD_SEGMENTS = 16   # 64-gon: area within 0.2 % of pi r^2


def local_polygon(shape: Shape) -> Polygon:
    """The shape in the object's frame."""
    if isinstance(shape, Rectangle):
        half_l, half_w = shape.length / 2.0, shape.width / 2.0
        return Polygon([(shape.offset - half_l, -half_w), (shape.offset + half_l, -half_w),
                        (shape.offset + half_l, half_w), (shape.offset - half_l, half_w)])
    if isinstance(shape, Circle):
        return shapely.Point(0.0, 0.0).buffer(shape.radius, quad_segs=CIRCLE_QUAD_SEGMENTS)
    if isinstance(shape, Trapezoid):
        near, far = shape.near_width / 2.0, shape.far_width / 2.0
        return Polygon([(0.0, -near), (shape.height, -far), (shape.height, far), (0.0, near)])
    raise TypeError(f"not a shape: {shape!r}")


def posed_polygon(shape: Shape, x: float, y: float, theta: float) -> Polygon:
    """The shape rotated by ``theta`` and moved to (x, y)."""
    local = np.asarray(local_polygon(shape).exterior.coords)
    cos_t, sin_t = math.cos(theta), math.sin(theta)
    world = np.column_stack([x + local[:, 0] * cos_t - local[:, 1] * sin_t,
                             y + local[:, 0] * sin_t + local[:, 1] * cos_t])
    return Polygon(world)


def local_contains(shape: Shape, u: NDArray[np.float64], v: NDArray[np.float64],
                   inflate_m: float = 0.0) -> NDArray[np.bool_] | None:
    """Whether object-frame points (u ahead, v left) lie in ``shape`` grown by ``inflate_m``
    (boundary included). Closed-form, because rasterising 30 shapes through shapely took most of
    a rebuild; None for the one case without a closed form here (an inflated trapezoid)."""
    if isinstance(shape, Rectangle):
        du = np.maximum(np.abs(u - shape.offset) - shape.length / 2.0, 0.0)
        dv = np.maximum(np.abs(v) - shape.width / 2.0, 0.0)
        return du * du + dv * dv <= inflate_m * inflate_m + 1e-12
    if isinstance(shape, Circle):
        radius = shape.radius + inflate_m
        return u * u + v * v <= radius * radius + 1e-12
    if isinstance(shape, Trapezoid) and inflate_m == 0.0:
        half = shape.near_width / 2.0 + (shape.far_width - shape.near_width) / 2.0 * (u / shape.height)
        return (u >= 0.0) & (u <= shape.height) & (np.abs(v) <= half)
    return None


@dataclass(frozen=True, slots=True)
class ObjectGeometry:
    """An object's polygons in the world frame."""

    name: str
    footprint: Polygon
    interaction: Polygon


def object_geometry(obj: SocialObject) -> ObjectGeometry:
    return ObjectGeometry(name=obj.name,
                          footprint=posed_polygon(obj.footprint, obj.x, obj.y, obj.theta),
                          interaction=posed_polygon(obj.interaction, obj.x, obj.y, obj.theta))
