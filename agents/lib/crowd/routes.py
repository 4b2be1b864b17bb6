"""Walking routes for people: shortest paths through door gaps and around furniture.

Why a visibility graph and not the room graph alone: ORCA (orca.py) only avoids what is within a
second or two; it does not plan, so a person whose goal is behind a table walks into the table and
stays there.  The shortest route among polygonal obstacles runs from corner to corner of the
obstacles grown by the walker's clearance (Lozano-Perez and Wesley 1979), so its corners are the
door jambs and the table corners a person rounds.  With walls grown by ``WALL_CLEARANCE_M`` the
corners of a 1.2 m door's two jambs lie 0.1 m either side of its centre: people pass doors in the
middle, as they do.  A door narrower than twice that clearance is tried again with
``TIGHT_CLEARANCE_M`` (a body and a few centimetres).

The graph is built once per set of closed doors (a closed leaf is one more wall): every corner pair
that sees the other, all-pairs shortest paths by scipy's Dijkstra.  A query then only joins the
start and the goal to the corners they see (two vectorised shapely calls), so a route costs well
under a millisecond.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numba
import numpy as np
import shapely
from numpy.typing import NDArray
from shapely.geometry.base import BaseGeometry

WALL_CLEARANCE_M = 0.45     # people keep about this much between their centre and a wall or jamb
OBJECT_CLEARANCE_M = 0.4    # ... and a table's edge
TIGHT_CLEARANCE_M = 0.3     # the fallback through narrow doors: a 0.25 m body and 5 cm
CORNER_OFFSET_M = 0.05      # corners sit this much outside the grown obstacles, so edges along them see
BODY_RADIUS_M = 0.25        # a start or goal only needs the body clear (a slot at a table by a wall)

Point = tuple[float, float]


class NoRoute(Exception):
    """No walkable route between two points (closed doors, or a goal inside furniture)."""


@numba.njit(cache=True, nogil=True)
def _clear_of(lines: NDArray[np.float64], segments: NDArray[np.float64], clearance: float) -> NDArray[np.bool_]:
    """For each leg (L, 2, 2): does it keep ``clearance`` from every edge of ``segments`` (S, 2, 2)?

    Why compiled: a route query tests ~100 candidate legs against ~100 wall and furniture edges and
    a day has thousands of queries; with an early exit at the first edge too close this is
    microseconds where shapely's prepared geometries took milliseconds."""
    out = np.ones(lines.shape[0], dtype=np.bool_)
    limit = clearance * clearance
    for i in range(lines.shape[0]):
        ax, ay, bx, by = lines[i, 0, 0], lines[i, 0, 1], lines[i, 1, 0], lines[i, 1, 1]
        ux, uy = bx - ax, by - ay
        uu = max(ux * ux + uy * uy, 1e-18)
        for j in range(segments.shape[0]):
            cx, cy, dx, dy = segments[j, 0, 0], segments[j, 0, 1], segments[j, 1, 0], segments[j, 1, 1]
            vx, vy = dx - cx, dy - cy
            vv = max(vx * vx + vy * vy, 1e-18)
            s1 = ux * (cy - ay) - uy * (cx - ax)
            s2 = ux * (dy - ay) - uy * (dx - ax)
            s3 = vx * (ay - cy) - vy * (ax - cx)
            s4 = vx * (by - cy) - vy * (bx - cx)
            if s1 * s2 < 0.0 and s3 * s4 < 0.0:
                out[i] = False
                break
            best = 1e300
            for px, py, qx, qy, wx, wy, ww in ((ax, ay, cx, cy, vx, vy, vv), (bx, by, cx, cy, vx, vy, vv),
                                               (cx, cy, ax, ay, ux, uy, uu), (dx, dy, ax, ay, ux, uy, uu)):
                t = ((px - qx) * wx + (py - qy) * wy) / ww
                t = min(1.0, max(0.0, t))
                ex, ey = px - qx - t * wx, py - qy - t * wy
                best = min(best, ex * ex + ey * ey)
            if best < limit:
                out[i] = False
                break
    return out


def polyline_segments(polylines: Sequence[Sequence[Point]]) -> NDArray[np.float64]:
    rows = [[a, b] for line in polylines for a, b in zip(line, line[1:], strict=False) if tuple(a) != tuple(b)]
    return np.asarray(rows, dtype=float).reshape(-1, 2, 2)


def polygon_segments(polygons: Sequence[BaseGeometry]) -> NDArray[np.float64]:
    rings = []
    for polygon in polygons:
        for part in getattr(polygon, "geoms", [polygon]):
            if part.is_empty:
                continue
            rings.append([tuple(c) for c in part.exterior.coords])
            rings.extend([tuple(c) for c in ring.coords] for ring in part.interiors)
    return polyline_segments(rings)


@dataclass(frozen=True)
class RouteGraph:
    """Corners of the grown obstacles and the shortest distances between them, for one clearance."""

    clearance_m: float
    walls: NDArray[np.float64]       # (S, 2, 2) wall edges, building outline included
    furniture: NDArray[np.float64]   # (F, 2, 2) footprint edges
    corners: NDArray[np.float64]     # (N, 2)
    distance: NDArray[np.float64]    # (N, N) shortest corner-to-corner distance (inf: not connected)
    predecessor: NDArray[np.int32]
    building: BaseGeometry
    footprints: BaseGeometry

    @classmethod
    def build(cls, building: BaseGeometry, walls: Sequence[Sequence[Point]], footprints: Sequence[BaseGeometry],
              clearance_m: float) -> RouteGraph:
        # scipy.sparse loads with the first graph, not at import: scenes whose people stay put
        # (a building map's) build none, and `chronav path` on them need not pay for it.
        from scipy.sparse import csr_matrix
        from scipy.sparse.csgraph import shortest_path

        wall_lines = [shapely.LineString(w) for w in walls if len(w) >= 2]
        wall_geom = shapely.union_all(wall_lines) if wall_lines else shapely.GeometryCollection()
        furniture_geom = shapely.union_all(list(footprints)) if footprints else shapely.GeometryCollection()
        object_clearance = min(OBJECT_CLEARANCE_M, clearance_m)
        # Corners: mitred growth keeps a rectangle's corners as 4 vertices (rounded growth would add 8).
        grown = shapely.union_all([wall_geom.buffer(clearance_m + CORNER_OFFSET_M, cap_style="square",
                                                    join_style="mitre", mitre_limit=2.0),
                                   furniture_geom.buffer(object_clearance + CORNER_OFFSET_M, join_style="mitre",
                                                         mitre_limit=2.0, quad_segs=2)])
        points = []
        for polygon in getattr(grown, "geoms", [grown]):
            if polygon.is_empty or polygon.geom_type != "Polygon":
                continue
            for ring in (polygon.exterior, *polygon.interiors):
                points.extend(np.asarray(ring.coords)[:-1].tolist())
        candidates = np.unique(np.round(np.asarray(points, dtype=float).reshape(-1, 2), 6), axis=0)
        wall_segments = np.concatenate([polyline_segments(walls), polygon_segments([building])])
        furniture_segments = polygon_segments(list(footprints))
        shapely.prepare(building)
        shapely.prepare(furniture_geom)
        graph = cls(clearance_m, wall_segments, furniture_segments, np.zeros((0, 2)), np.zeros((0, 0)),
                    np.zeros((0, 0), dtype=np.int32), building, furniture_geom)
        if len(candidates):
            inside = shapely.contains_xy(building, candidates[:, 0], candidates[:, 1])
            candidates = candidates[inside]
            keep = graph._clear(np.stack([candidates, candidates], axis=1), clearance_m)
            candidates = candidates[keep]
        n = len(candidates)
        if n == 0:
            return graph
        i, j = np.triu_indices(n, k=1)
        free = graph._clear(np.stack([candidates[i], candidates[j]], axis=1), clearance_m)
        i, j = i[free], j[free]
        lengths = np.hypot(*(candidates[i] - candidates[j]).T)
        adjacency = csr_matrix((np.concatenate([lengths, lengths]), (np.concatenate([i, j]), np.concatenate([j, i]))),
                               shape=(n, n))
        distance, predecessor = shortest_path(adjacency, method="D", directed=False, return_predecessors=True)
        return cls(clearance_m, wall_segments, furniture_segments, candidates, distance,
                   predecessor.astype(np.int32), building, furniture_geom)

    def _clear(self, lines: NDArray[np.float64], clearance: float) -> NDArray[np.bool_]:
        """Legs (L, 2, 2) that keep ``clearance`` from walls and the object clearance from furniture."""
        object_clearance = min(OBJECT_CLEARANCE_M, clearance)
        lines = np.ascontiguousarray(lines, dtype=np.float64)
        ok = _clear_of(lines, self.walls, clearance - 1e-9)
        if len(self.furniture):
            # (A leg wholly inside a footprint would cross none of its edges, but every leg ends at a
            # corner, a start or a goal, and none of those is inside furniture.)
            ok &= _clear_of(lines, self.furniture, object_clearance - 1e-9)
        return ok

    def _sees(self, origin: Point, targets: NDArray[np.float64]) -> NDArray[np.bool_]:
        """Which ``targets`` a body at ``origin`` walks to in a straight line.

        The end at ``origin`` (a start or a goal) may be closer to a wall than the clearance (a
        place at a table by the wall): within ``clearance`` of it a body's width suffices; beyond,
        the leg keeps the clearance (it must not squeeze through a door's edge)."""
        if len(targets) == 0:
            return np.zeros(0, dtype=bool)
        origin_xy = np.broadcast_to(np.asarray(origin, dtype=float), targets.shape)
        lines = np.stack([origin_xy, targets], axis=1)
        ok = self._clear(lines, BODY_RADIUS_M)
        offset = targets - origin_xy
        length = np.hypot(offset[:, 0], offset[:, 1])
        away = np.minimum(1.0, (self.clearance_m + 0.05) / np.maximum(length, 1e-9))
        rest = np.stack([origin_xy + offset * away[:, None], targets], axis=1)
        far = length > self.clearance_m + 0.05
        ok[far] &= self._clear(rest[far], self.clearance_m)
        return ok

    def route(self, start: Point, goal: Point) -> tuple[list[Point], float]:
        """Waypoints after ``start`` up to ``goal`` (included) and the route's length; NoRoute if none."""
        straight = float(np.hypot(goal[0] - start[0], goal[1] - start[1]))
        if straight < 1e-9 or self._sees_both(start, goal):
            return [goal], straight
        if len(self.corners) == 0:
            raise NoRoute(f"no route from ({start[0]:.2f}, {start[1]:.2f}) to ({goal[0]:.2f}, {goal[1]:.2f})")
        from_start = np.flatnonzero(self._sees(start, self.corners))
        to_goal = np.flatnonzero(self._sees(goal, self.corners))
        if len(from_start) == 0 or len(to_goal) == 0:
            raise NoRoute(f"no route from ({start[0]:.2f}, {start[1]:.2f}) to ({goal[0]:.2f}, {goal[1]:.2f})")
        head = np.hypot(*(self.corners[from_start] - np.asarray(start)).T)
        tail = np.hypot(*(self.corners[to_goal] - np.asarray(goal)).T)
        total = head[:, None] + self.distance[np.ix_(from_start, to_goal)] + tail[None, :]
        best = np.unravel_index(int(np.argmin(total)), total.shape)
        length = float(total[best])
        if not np.isfinite(length):
            raise NoRoute(f"no route from ({start[0]:.2f}, {start[1]:.2f}) to ({goal[0]:.2f}, {goal[1]:.2f})")
        first, last = int(from_start[best[0]]), int(to_goal[best[1]])
        chain = [last]
        while chain[-1] != first:
            chain.append(int(self.predecessor[first, chain[-1]]))
        waypoints = [(float(self.corners[k, 0]), float(self.corners[k, 1])) for k in reversed(chain)]
        return [*waypoints, goal], length

    def _sees_both(self, start: Point, goal: Point) -> bool:
        """The straight leg, relaxed at both ends (a start and a goal may both be near walls)."""
        a, b = np.asarray(start, dtype=float), np.asarray(goal, dtype=float)
        length = float(np.hypot(*(b - a)))
        if not self._clear(np.asarray([[a, b]]), BODY_RADIUS_M)[0]:
            return False
        margin = self.clearance_m + 0.05
        if length <= 2 * margin:
            return True
        u = (b - a) / length
        return bool(self._clear(np.asarray([[a + u * margin, b - u * margin]]), self.clearance_m)[0])

    def free(self, x: float, y: float) -> bool:
        """A body fits at (x, y): inside the building, clear of walls and furniture by a body."""
        if not shapely.contains_xy(self.building, x, y) or shapely.intersects_xy(self.footprints, x, y):
            return False
        point = np.asarray([[[x, y], [x, y]]], dtype=float)
        return bool(self._clear(point, BODY_RADIUS_M)[0])


@dataclass(frozen=True)
class Router:
    """Routes with the comfortable clearance, through narrow doors with the tight one."""

    graphs: tuple[RouteGraph, ...]

    @classmethod
    def build(cls, building: BaseGeometry, walls: Sequence[Sequence[Point]],
              footprints: Sequence[BaseGeometry]) -> Router:
        return cls(tuple(RouteGraph.build(building, walls, footprints, c) for c in (WALL_CLEARANCE_M,
                                                                                     TIGHT_CLEARANCE_M)))

    def route(self, start: Point, goal: Point) -> tuple[list[Point], float]:
        for graph in self.graphs:
            try:
                return graph.route(start, goal)
            except NoRoute:
                continue
        raise NoRoute(f"no route from ({start[0]:.2f}, {start[1]:.2f}) to ({goal[0]:.2f}, {goal[1]:.2f}): "
                      "walls, closed doors or furniture close it off")

    def free(self, x: float, y: float) -> bool:
        """A body fits at (x, y): inside the building, clear of walls and furniture."""
        return self.graphs[-1].free(x, y)
