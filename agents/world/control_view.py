"""What a local controller sees of the world, as ControlInput's arrays (agents/lib/control/protocol.py).

Why here: the people come from the DSR (the observer's tracks) and the obstacles from the scene
(walls, closed doors, object footprints); the world model reads both, the controller library
sees plain numpy arrays only.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np
from numpy.typing import NDArray

from agents.lib.socialmap.types import Wall
from agents.world.building import footprint_polygons
from agents.world.vocabulary import NodeType
from dsr.protocols import GraphReader
from scenes.model import Scene


def tracked_people(graph: GraphReader, radius_m: float) -> NDArray[np.float64]:
    """(K, 5) x, y, vx, vy, radius of every person the DSR holds (world frame, m and m/s)."""
    rows = []
    for node in graph.nodes_of_type(NodeType.PERSON):
        try:
            x, y, _theta = graph.world_pose(node.id)
            vx, vy = _number(node.attrs.get("vx")), _number(node.attrs.get("vy"))
        except (KeyError, LookupError, ValueError, TypeError):
            continue
        rows.append((x, y, vx, vy, radius_m))
    return np.asarray(rows, dtype=np.float64).reshape(-1, 5)


def _number(value: object) -> float:
    """An attribute's number (a person not yet given a velocity stands still)."""
    return float(value) if isinstance(value, int | float) else 0.0


def obstacle_segments(scene: Scene, walls: Sequence[Wall]) -> NDArray[np.float64]:
    """(M, 4) x1, y1, x2, y2: every wall polyline's segments (closed doors included when the
    caller's ``walls`` holds their leaves) and every object footprint's edges."""
    segments: list[tuple[float, float, float, float]] = []
    for wall in walls:
        segments.extend(_pairs(wall.points))
    for polygon in footprint_polygons(scene):
        segments.extend(_pairs(list(polygon.exterior.coords)))
    return np.asarray(segments, dtype=np.float64).reshape(-1, 4)


def _pairs(points: Iterable[Sequence[float]]) -> list[tuple[float, float, float, float]]:
    pts = [(float(p[0]), float(p[1])) for p in points]
    return [(a[0], a[1], b[0], b[1]) for a, b in zip(pts, pts[1:], strict=False)]


def segment_points(segments: NDArray[np.float64], spacing_m: float) -> NDArray[np.float64]:
    """(P, 2) points along every segment, at most ``spacing_m`` apart (ends included)."""
    out = []
    for x1, y1, x2, y2 in segments:
        n = max(1, int(np.ceil(np.hypot(x2 - x1, y2 - y1) / spacing_m)))
        f = np.linspace(0.0, 1.0, n + 1)[:, None]
        out.append(np.hstack([x1 + f * (x2 - x1), y1 + f * (y2 - y1)]))
    return np.vstack(out) if out else np.zeros((0, 2))
