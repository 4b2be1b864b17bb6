"""Where people stand together: places around an activity's object, and conversation circles.

Why F-formations (Kendon 1990): people who do something together arrange themselves so that their
transactional segments overlap in a shared o-space.  Around a table, a bed or a bookshelf that is
the object itself: participants stand on a ring ``RING_M`` out from its footprint, spread evenly
over the part of the ring a body fits, each facing the nearest point of the object.  In front of a
screen (an interaction space shaped as a trapezoid, scenes/geometry.py) they stand on an arc
``ARC_RADIUS_M`` from it within ``ARC_HALF_ANGLE_RAD`` of its axis, facing it.  Two or three people
chatting stand on a circle of radius ``CHAT_RADIUS_M`` around a shared centre, facing it.  These are
exactly the arrangements the social map groups (agents/lib/socialmap/groups.py: close and facing
each other, or linked by ``interacting`` edges from the agenda, agents/world/interactions.py).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np
from shapely.geometry.base import BaseGeometry
from shapely.ops import nearest_points

RING_M = 0.5                 # a participant's centre from the object's edge (a chair's depth)
PLACE_SPACING_M = 0.7        # shoulder to shoulder at a table
ARC_RADIUS_M = 1.5           # viewers of a screen, from its centre (within the 1.8 m interaction range)
ARC_STEP_RAD = 0.47          # 0.7 m between viewers on that arc
ARC_HALF_ANGLE_RAD = 1.2     # never beside the screen
CHAT_RADIUS_M = 0.55         # half the distance between two people talking (Hall's personal distance)

Pose = tuple[float, float, float]


def _facing(x: float, y: float, tx: float, ty: float) -> float:
    return math.atan2(ty - y, tx - x)


def screen_places(x: float, y: float, theta: float, count: int, fits: Callable[[float, float], bool]) -> list[Pose]:
    """``count`` places on an arc in front of a screen at (x, y) facing ``theta``, nearest the axis
    first (alternating sides); places a body does not fit are skipped."""
    places: list[Pose] = []
    step = ARC_STEP_RAD
    angles = [0.0] + [sign * k * step for k in range(1, 20) for sign in (1, -1)]
    for radius in (ARC_RADIUS_M, ARC_RADIUS_M - 0.5, ARC_RADIUS_M + 0.6):
        for offset in angles:
            if abs(offset) > ARC_HALF_ANGLE_RAD:
                continue
            px, py = x + radius * math.cos(theta + offset), y + radius * math.sin(theta + offset)
            if fits(px, py) and all(math.hypot(px - q[0], py - q[1]) >= PLACE_SPACING_M - 1e-6 for q in places):
                places.append((px, py, _facing(px, py, x, y)))
            if len(places) == count:
                return places
    return places


def ring_places(footprint: BaseGeometry, count: int, fits: Callable[[float, float], bool]) -> list[Pose]:
    """``count`` places around ``footprint``, evenly spread over the part of the ring where a body
    fits (a bookshelf against a wall gets its places on the room's side), facing the object."""
    ring = footprint.buffer(RING_M, join_style="round").exterior
    length = ring.length
    samples = max(8, int(length / 0.05))
    distances = np.linspace(0.0, length, samples, endpoint=False)
    points = [ring.interpolate(d) for d in distances]
    usable = np.array([fits(p.x, p.y) for p in points])
    if not usable.any():
        return []
    # Spread over the usable arc length (start at the middle of the first usable run so a free
    # ring puts its first place on the object's +x side, not on a seam).
    positions = distances[usable]
    step = length / samples
    usable_length = len(positions) * step
    wanted = min(count, max(1, int(usable_length / PLACE_SPACING_M)))
    chosen = [positions[min(len(positions) - 1, int((k + 0.5) * len(positions) / wanted))] for k in range(wanted)]
    places = []
    for d in chosen:
        p = ring.interpolate(float(d))
        near = nearest_points(footprint, p)[0]
        places.append((p.x, p.y, _facing(p.x, p.y, near.x, near.y)))
    return places


def chat_place(partner: tuple[float, float], towards: tuple[float, float],
               fits: Callable[[float, float], bool]) -> tuple[Pose, Pose, tuple[float, float]] | None:
    """A pair conversation: where the newcomer stands, how the partner turns, and the o-space centre.

    The newcomer comes from ``towards``; the circle's centre lies between the two, on that side of
    the partner, or turned in 45 degree steps until the newcomer's place is free."""
    px, py = partner
    base = math.atan2(towards[1] - py, towards[0] - px) if math.hypot(towards[0] - px, towards[1] - py) > 1e-6 else 0.0
    for turn in (0.0, 0.785, -0.785, 1.571, -1.571, 2.356, -2.356, 3.142):
        a = base + turn
        cx, cy = px + CHAT_RADIUS_M * math.cos(a), py + CHAT_RADIUS_M * math.sin(a)
        nx, ny = px + 2 * CHAT_RADIUS_M * math.cos(a), py + 2 * CHAT_RADIUS_M * math.sin(a)
        if fits(nx, ny):
            return (nx, ny, _facing(nx, ny, cx, cy)), (px, py, _facing(px, py, cx, cy)), (cx, cy)
    return None


def join_circle(centre: tuple[float, float], members: Sequence[tuple[float, float]],
                fits: Callable[[float, float], bool]) -> Pose | None:
    """A place for one more on a conversation circle: in the widest gap between its members."""
    cx, cy = centre
    radius = max(CHAT_RADIUS_M, float(np.mean([math.hypot(x - cx, y - cy) for x, y in members])) if members else 0.0)
    angles = sorted(math.atan2(y - cy, x - cx) for x, y in members)
    if not angles:
        candidates = [0.0]
    else:
        gaps = [((angles[(i + 1) % len(angles)] - a) % (2 * math.pi) or 2 * math.pi, a) for i, a in enumerate(angles)]
        candidates = [a + gap / 2 for gap, a in sorted(gaps, reverse=True)]
    for a in candidates:
        x, y = cx + radius * math.cos(a), cy + radius * math.sin(a)
        if fits(x, y) and all(math.hypot(x - mx, y - my) >= PLACE_SPACING_M for mx, my in members):
            return (x, y, _facing(x, y, cx, cy))
    return None
