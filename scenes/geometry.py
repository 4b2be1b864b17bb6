"""Plane geometry every layer shares: object shapes, posed polygons, angles, nearest points.

Why here, at the bottom: the scene file declares shapes, the simulator rasterises footprints for
its laser, the social map prices interaction spaces and the DSR carries them as attributes. With
one definition a shape parameter cannot mean one thing to the simulator and another to the map.

Shapes are defined in the object's frame (+x is where the object faces, e.g. the TV screen): a
rectangle is centred on the object (shifted ``offset`` along +x), a circle is centred on it, a
trapezoid starts at the object with its near edge and widens to its far edge ``height`` ahead
(seed section 4.2, Fig. 7; Eqs. 10-12 give the areas, which the polygons reproduce).
Conventions: metres, radians (theta from +x, counter-clockwise).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
import shapely
from numpy.typing import ArrayLike, NDArray
from shapely.geometry import Polygon

# re-exported for existing callers (the `x as x` form marks a re-export for ruff and mypy)
from scenes.angles import angle_difference as angle_difference
from scenes.angles import lerp_angle as lerp_angle
from scenes.angles import wrap_angle as wrap_angle

CIRCLE_QUAD_SEGMENTS = 16   # 64-gon: area within 0.2 % of pi r^2


class GeometryError(ValueError):
    """A shape or coordinate that cannot be used; the message names the item and the key."""


def finite(owner: str, name: str, value: Any) -> float:
    """``value`` as a finite float, or GeometryError naming ``owner`` and ``name``."""
    if isinstance(value, bool):  # YAML's true/false, which Python would take for 1 and 0
        raise GeometryError(f"{owner}: {name} must be a number, got {'true' if value else 'false'}")
    try:
        number = float(value)
    except (TypeError, ValueError, OverflowError):
        raise GeometryError(f"{owner}: {name} must be a number, got {value!r}") from None
    if not math.isfinite(number):
        raise GeometryError(f"{owner}: {name} must be finite, got {value!r}")
    return number


def positive(owner: str, name: str, value: Any) -> float:
    number = finite(owner, name, value)
    if number <= 0.0:
        raise GeometryError(f"{owner}: {name} must be > 0, got {value!r}")
    return number


# ----------------------------------------------------------------------------------- shapes
@dataclass(frozen=True, slots=True)
class Rectangle:
    """Rectangle in the object's frame: ``length`` along +x (the facing), ``width`` along +y,
    centre shifted ``offset`` along +x. Seed Eq. 11: area r'_h * r'_w."""

    length: float
    width: float
    offset: float = 0.0
    shape: Literal["rectangle"] = field(default="rectangle", init=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "length", positive("rectangle", "length", self.length))
        object.__setattr__(self, "width", positive("rectangle", "width", self.width))
        object.__setattr__(self, "offset", finite("rectangle", "offset", self.offset))

    @property
    def area(self) -> float:
        return self.length * self.width


@dataclass(frozen=True, slots=True)
class Circle:
    """Circle centred on the object (seed Eq. 12: area pi * c'_r^2)."""

    radius: float
    shape: Literal["circle"] = field(default="circle", init=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "radius", positive("circle", "radius", self.radius))

    @property
    def area(self) -> float:
        return math.pi * self.radius**2


@dataclass(frozen=True, slots=True)
class Trapezoid:
    """Isosceles trapezoid in front of the object (+x): near edge (``near_width``) through the
    object's origin, far edge (``far_width``) ``height`` ahead. Seed Eq. 10: t'_h (t'_w1+t'_w2)/2."""

    height: float
    near_width: float
    far_width: float
    shape: Literal["trapezoid"] = field(default="trapezoid", init=False)

    def __post_init__(self) -> None:
        for name in ("height", "near_width", "far_width"):
            object.__setattr__(self, name, positive("trapezoid", name, getattr(self, name)))

    @property
    def area(self) -> float:
        return self.height * (self.near_width + self.far_width) / 2.0


Shape = Rectangle | Circle | Trapezoid

# kind -> (class, required keys, optional keys); the order of the keys is the order of the
# numbers in the DSR's ``<prefix>_dims`` attribute (agents/world/vocabulary.py).
SHAPE_FIELDS: dict[str, tuple[type, tuple[str, ...], tuple[str, ...]]] = {
    "rectangle": (Rectangle, ("length", "width"), ("offset",)),
    "circle": (Circle, ("radius",), ()),
    "trapezoid": (Trapezoid, ("height", "near_width", "far_width"), ()),
}


def shape_keys(kind: str) -> tuple[str, ...]:
    """Every numeric key of a shape kind, required ones first."""
    _, required, optional = SHAPE_FIELDS[kind]
    return (*required, *optional)


def shape_from_spec(spec: Shape | Mapping[str, Any] | Any, where: str = "shape") -> Shape:
    """Build a shape from a mapping (``{"shape": "circle", "radius": 1.5}``) or any object with the
    same attributes. Errors name ``where`` and the offending key."""
    if isinstance(spec, Rectangle | Circle | Trapezoid):
        return spec
    if isinstance(spec, Mapping):
        get = spec.get
    else:
        def get(key: str, default: Any = None) -> Any:
            return getattr(spec, key, default)
    kind = get("shape")
    if not isinstance(kind, str) or kind not in SHAPE_FIELDS:
        raise GeometryError(f"{where}: 'shape' must be one of {sorted(SHAPE_FIELDS)}, got {kind!r}")
    cls, required, optional = SHAPE_FIELDS[kind]
    kwargs: dict[str, Any] = {}
    for key in required:
        value = get(key)
        if value is None:
            raise GeometryError(f"{where}: {kind} needs key {key!r}")
        kwargs[key] = value
    for key in optional:
        value = get(key)
        if value is not None:
            kwargs[key] = value
    if isinstance(spec, Mapping):
        unknown = set(spec) - {"shape", *required, *optional}
        if unknown:
            raise GeometryError(f"{where}: unknown key(s) {sorted(map(str, unknown))} for a {kind}")
    try:
        return cls(**kwargs)
    except GeometryError as exc:  # the shape's own message already starts with its kind
        raise GeometryError(str(exc) if where == kind else f"{where}: {exc}") from None


def shape_to_dict(shape: Shape) -> dict[str, Any]:
    """The mapping form written in scene files (inverse of :func:`shape_from_spec`)."""
    return {"shape": shape.shape, **{key: getattr(shape, key) for key in shape_keys(shape.shape)}}


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




# ----------------------------------------------------------------------------------- segments
@dataclass(frozen=True)
class SegmentProjection:
    """A point projected on each of N segments: ``fraction`` along each (0..1), the ``closest``
    points and their ``distance`` to the point."""

    fraction: NDArray[np.float64]
    closest: NDArray[np.float64]
    distance: NDArray[np.float64]


def project_on_segments(point: ArrayLike, starts: ArrayLike, ends: ArrayLike) -> SegmentProjection:
    """Project ``point`` on the segments ``starts[i]`` -> ``ends[i]`` (arrays of shape (N, 2)).

    Used for a polyline (starts = points[:-1], ends = points[1:]) by the controller and the
    elastic band, and for wall segments by the simulator's bumper."""
    p = np.asarray(point, dtype=np.float64)[:2]
    a = np.asarray(starts, dtype=np.float64).reshape(-1, 2)
    seg = np.asarray(ends, dtype=np.float64).reshape(-1, 2) - a
    length2 = (seg * seg).sum(axis=1)
    fraction = np.clip(((p - a) * seg).sum(axis=1) / np.maximum(length2, 1e-18), 0.0, 1.0)
    closest = a + fraction[:, None] * seg
    return SegmentProjection(fraction, closest, np.hypot(*(closest - p).T))
