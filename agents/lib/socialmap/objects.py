"""Objects on the grid: their posed polygons and a closed-form point test for rasterising.

The shapes themselves (and ``posed_polygon``) are the scene's, ``scenes/geometry.py``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from shapely.geometry import Polygon

from agents.lib.socialmap.types import SocialObject
from scenes.geometry import Circle, Rectangle, Shape, Trapezoid, posed_polygon

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
