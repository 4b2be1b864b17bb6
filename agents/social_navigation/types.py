"""Plain, immutable inputs of the social map: people, objects, walls, rooms and activity windows.

Why frozen dataclasses and not the scene's pydantic models: the social map is rebuilt many times a
second from the replicated graph, not only from scene files; these small value types validate
themselves in ``__post_init__`` (cheap) and can be hashed, compared and built by any caller. Field
names of the shapes mirror the scene schema (``scenes/model.py``) so that converting is one line.

Conventions (docs/CONTRACTS.md): metres, radians (theta from +x, counter-clockwise), times in
seconds since local midnight.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal


class SocialMapInputError(ValueError):
    """Bad input to the social map; the message names the item and the field."""


def _finite(owner: str, name: str, value: float) -> float:
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise SocialMapInputError(f"{owner}: {name} must be a number, got {value!r}") from None
    if not math.isfinite(number):
        raise SocialMapInputError(f"{owner}: {name} must be finite, got {value!r}")
    return number


def _positive(owner: str, name: str, value: float) -> float:
    number = _finite(owner, name, value)
    if number <= 0.0:
        raise SocialMapInputError(f"{owner}: {name} must be > 0, got {value!r}")
    return number


@dataclass(frozen=True, slots=True)
class Person:
    """A detected person: pose and role (the role scales the personal space, see roles.py).

    ``interacting_with`` names other people this one is known to interact with (the DSR's
    ``interacting`` edges); such pairs are grouped even when the Omega rule would not group them.
    """

    name: str
    x: float
    y: float
    theta: float
    role: str = "resident"
    interacting_with: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        owner = f"person {self.name!r}"
        for attr in ("x", "y", "theta"):
            object.__setattr__(self, attr, _finite(owner, attr, getattr(self, attr)))
        object.__setattr__(self, "interacting_with", tuple(self.interacting_with))


@dataclass(frozen=True, slots=True)
class Rectangle:
    """Rectangle in the object's frame: ``length`` along +x (the facing), ``width`` along +y,
    centre shifted ``offset`` along +x. Seed Eq. 11: area r'_h * r'_w."""

    length: float
    width: float
    offset: float = 0.0
    shape: Literal["rectangle"] = field(default="rectangle", init=False)

    def __post_init__(self) -> None:
        _positive("rectangle", "length", self.length)
        _positive("rectangle", "width", self.width)
        _finite("rectangle", "offset", self.offset)

    @property
    def area(self) -> float:
        return self.length * self.width


@dataclass(frozen=True, slots=True)
class Circle:
    """Circle centred on the object (seed Eq. 12: area pi * c'_r^2)."""

    radius: float
    shape: Literal["circle"] = field(default="circle", init=False)

    def __post_init__(self) -> None:
        _positive("circle", "radius", self.radius)

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
        _positive("trapezoid", "height", self.height)
        _positive("trapezoid", "near_width", self.near_width)
        _positive("trapezoid", "far_width", self.far_width)

    @property
    def area(self) -> float:
        return self.height * (self.near_width + self.far_width) / 2.0


Shape = Rectangle | Circle | Trapezoid

_SHAPE_FIELDS: dict[str, tuple[type, tuple[str, ...], tuple[str, ...]]] = {
    "rectangle": (Rectangle, ("length", "width"), ("offset",)),
    "circle": (Circle, ("radius",), ()),
    "trapezoid": (Trapezoid, ("height", "near_width", "far_width"), ()),
}


def shape_from_spec(spec: Shape | Mapping[str, Any] | Any, where: str = "shape") -> Shape:
    """Build a shape from a mapping (``{"shape": "circle", "radius": 1.5}``) or any object with the
    same attributes (the scene's pydantic shapes). Errors name ``where`` and the offending key."""
    if isinstance(spec, Rectangle | Circle | Trapezoid):
        return spec
    get = spec.get if isinstance(spec, Mapping) else (lambda key, default=None: getattr(spec, key, default))
    kind = get("shape")
    if kind not in _SHAPE_FIELDS:
        raise SocialMapInputError(f"{where}: 'shape' must be one of {sorted(_SHAPE_FIELDS)}, got {kind!r}")
    cls, required, optional = _SHAPE_FIELDS[kind]
    kwargs: dict[str, float] = {}
    for key in required:
        value = get(key)
        if value is None:
            raise SocialMapInputError(f"{where}: {kind} needs key {key!r}")
        kwargs[key] = value
    for key in optional:
        value = get(key)
        if value is not None:
            kwargs[key] = value
    if isinstance(spec, Mapping):
        unknown = set(spec) - {"shape", *required, *optional}
        if unknown:
            raise SocialMapInputError(f"{where}: unknown key(s) {sorted(unknown)} for a {kind}")
    try:
        return cls(**kwargs)
    except SocialMapInputError as exc:
        raise SocialMapInputError(f"{where}: {exc}") from None


@dataclass(frozen=True, slots=True)
class SocialObject:
    """An object people use: physical footprint (never traversable) and an interaction space whose
    cost follows the agenda, R(t) (chronemics.py). ``forbidden_while_active`` makes the interaction
    space an obstacle while one of its activities runs (the first seed's banned regions)."""

    name: str
    kind: str
    x: float
    y: float
    theta: float
    footprint: Shape
    interaction: Shape
    forbidden_while_active: bool = False

    def __post_init__(self) -> None:
        owner = f"object {self.name!r}"
        for attr in ("x", "y", "theta"):
            object.__setattr__(self, attr, _finite(owner, attr, getattr(self, attr)))
        object.__setattr__(self, "footprint", shape_from_spec(self.footprint, f"{owner} footprint"))
        object.__setattr__(self, "interaction", shape_from_spec(self.interaction, f"{owner} interaction"))


@dataclass(frozen=True, slots=True)
class Wall:
    """A wall as a polyline (>= 2 points). Its thickness is zero: the grid inflates it by the
    robot radius."""

    points: tuple[tuple[float, float], ...]
    name: str = ""

    def __post_init__(self) -> None:
        owner = f"wall {self.name!r}" if self.name else "wall"
        points = _points(owner, self.points)
        if len(points) < 2:
            raise SocialMapInputError(f"{owner}: a polyline needs at least 2 points, got {len(points)}")
        object.__setattr__(self, "points", points)


@dataclass(frozen=True, slots=True)
class Room:
    """A room polygon (>= 3 points). Cells outside every room are not traversable."""

    name: str
    polygon: tuple[tuple[float, float], ...]

    def __post_init__(self) -> None:
        owner = f"room {self.name!r}"
        points = _points(owner, self.polygon)
        if len(points) < 3:
            raise SocialMapInputError(f"{owner}: a polygon needs at least 3 points, got {len(points)}")
        object.__setattr__(self, "polygon", points)


@dataclass(frozen=True, slots=True)
class ActivityWindow:
    """One scheduled use of an object: ``object`` is the object's name, times in seconds since
    local midnight. A cancelled window is kept (for display) but has no effect on R(t)."""

    object: str
    start_s: float
    end_s: float
    cancelled: bool = False

    def __post_init__(self) -> None:
        owner = f"activity on {self.object!r}"
        start = _finite(owner, "start_s", self.start_s)
        end = _finite(owner, "end_s", self.end_s)
        if end < start:
            raise SocialMapInputError(f"{owner}: end_s ({end:g}) is before start_s ({start:g})")
        object.__setattr__(self, "start_s", start)
        object.__setattr__(self, "end_s", end)


def _points(owner: str, raw: Sequence[Sequence[float]]) -> tuple[tuple[float, float], ...]:
    points: list[tuple[float, float]] = []
    for index, point in enumerate(raw):
        if len(point) != 2:
            raise SocialMapInputError(f"{owner}: point {index} must be (x, y), got {point!r}")
        points.append((_finite(owner, f"point {index} x", point[0]), _finite(owner, f"point {index} y", point[1])))
    return tuple(points)
