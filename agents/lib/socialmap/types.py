"""Plain, immutable inputs of the social map: people, objects, walls and rooms.

Why frozen dataclasses and not the scene's pydantic models: the social map is rebuilt many times a
second from the replicated graph, not only from scene files; these small value types validate
themselves in ``__post_init__`` (cheap) and can be hashed, compared and built by any caller. The
object shapes are the scene's own (``scenes/geometry.py``); activity windows are the agenda's
(``agents/lib/agenda/model.py``).

Conventions (docs/CONTRACTS.md): metres, radians (theta from +x, counter-clockwise), times in
seconds since local midnight.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from scenes.geometry import GeometryError, Shape, finite, shape_from_spec


class SocialMapInputError(GeometryError):
    """Bad input to the social map; the message names the item and the field."""


def _finite(owner: str, name: str, value: float) -> float:
    try:
        return finite(owner, name, value)
    except GeometryError as exc:
        raise SocialMapInputError(str(exc)) from None


@dataclass(frozen=True, slots=True)
class Person:
    """A detected person: pose and role (the role scales the personal space, see roles.py).

    ``interacting_with`` names other people this one is known to interact with (the DSR's
    ``interacting`` edges); such pairs are grouped even when the Omega rule would not group them.
    ``vx``/``vy`` stretch a walker's space and predict where they go (motion.py), toward
    ``destination`` when the agenda says where that is, through the doors ``via``.
    """

    name: str
    x: float
    y: float
    theta: float
    role: str = "resident"
    interacting_with: tuple[str, ...] = ()
    vx: float = 0.0                                  # velocity (m/s, world frame), as the observer estimates it
    vy: float = 0.0
    destination: tuple[float, float] | None = None   # where the agenda says they are walking to
    via: tuple[tuple[float, float], ...] = ()        # the doors on their way there (motion.py)

    def __post_init__(self) -> None:
        owner = f"person {self.name!r}"
        for attr in ("x", "y", "theta", "vx", "vy"):
            object.__setattr__(self, attr, _finite(owner, attr, getattr(self, attr)))
        object.__setattr__(self, "interacting_with", tuple(self.interacting_with))
        object.__setattr__(self, "via", tuple((_finite(owner, "via x", p[0]), _finite(owner, "via y", p[1]))
                                              for p in self.via))
        if self.destination is not None:
            object.__setattr__(self, "destination", (_finite(owner, "destination x", self.destination[0]),
                                                      _finite(owner, "destination y", self.destination[1])))


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
        try:
            object.__setattr__(self, "footprint", shape_from_spec(self.footprint, f"{owner} footprint"))
            object.__setattr__(self, "interaction", shape_from_spec(self.interaction, f"{owner} interaction"))
        except SocialMapInputError:
            raise
        except GeometryError as exc:
            raise SocialMapInputError(str(exc)) from None


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


def _points(owner: str, raw: Sequence[Sequence[float]]) -> tuple[tuple[float, float], ...]:
    points: list[tuple[float, float]] = []
    for index, point in enumerate(raw):
        if len(point) != 2:
            raise SocialMapInputError(f"{owner}: point {index} must be (x, y), got {point!r}")
        points.append((_finite(owner, f"point {index} x", point[0]), _finite(owner, f"point {index} y", point[1])))
    return tuple(points)
