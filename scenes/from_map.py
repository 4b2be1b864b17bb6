"""A starting scene from a building map: candidate rooms, doors between them and a robot pose.

Why this way: a SLAM map knows walls, not rooms; but rooms are where a building's free space
widens and doors where it narrows.  So the free space is cut at every passage narrower than
``door_width_m`` (cells closer than half of it to a wall are set aside); the connected components
that remain are the room cores.  Each free cell then joins the core that reaches it first when
flooding from the open middle of the rooms outwards, lowest "height" (minus the distance to the
walls) first: a watershed (Meyer's priority flood, compiled with numba; scipy's watershed_ift
floods across walls before filling the rooms), so two rooms meet at the narrowest point of the
passage between them, which is the candidate door.  Rooms reach two cells into the walls around them, so the simplified polygons
(``shapely.coverage_simplify``: neighbours keep one shared edge) still cover every free cell.

Everything is a candidate for a person to rename, merge or redraw: the output says so.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

import heapq

import numba
import numpy as np
import shapely
import yaml
from numpy.typing import NDArray
from scipy import ndimage

from scenes.occupancy import OccupancyMap

EIGHT = np.ones((3, 3), dtype=bool)
WALL_MARGIN_CELLS = 2        # rooms reach this far into the walls around them
MIN_DOOR_WIDTH_M = 0.6       # a narrower gap between two rooms is noise, not a door
MAX_DOOR_WIDTH_M = 20.0      # as a scene's door (scenes/model.py Door.width)


@dataclass(frozen=True)
class CandidateRoom:
    name: str
    polygon: list[tuple[float, float]]
    area_m2: float


@dataclass(frozen=True)
class CandidateDoor:
    name: str
    between: tuple[str, str]
    position: tuple[float, float]
    width: float


@dataclass(frozen=True)
class MapLayout:
    rooms: list[CandidateRoom]
    doors: list[CandidateDoor]
    robot: tuple[float, float, float]


class LayoutError(ValueError):
    """The map has no free space large enough for a room."""


def _cores(free: NDArray[np.bool_], distance_cells: NDArray[np.float64], half_door_cells: float,
           min_core_cells: int) -> tuple[NDArray[np.int32], int]:
    cores, count = ndimage.label(free & (distance_cells > half_door_cells), structure=EIGHT)
    if count:
        sizes = np.bincount(cores.ravel(), minlength=count + 1)
        small = sizes < min_core_cells
        small[0] = False
        cores[small[cores]] = 0
        cores, count = ndimage.label(cores > 0, structure=EIGHT)
    return cores.astype(np.int32), count


@numba.njit(cache=True)
def _flood(height: NDArray[np.float64], free: NDArray[np.bool_], labels: NDArray[np.int32]) -> None:  # pragma: no cover
    """Meyer's watershed in place: labelled cells flood their free 8-neighbours, lowest height first
    (ties first come, first served)."""
    rows, cols = labels.shape
    heap = [(0.0, 0, 0)]
    heap.pop()
    order = 0
    for r in range(rows):
        for c in range(cols):
            if labels[r, c] > 0:
                heapq.heappush(heap, (height[r, c], order, r * cols + c))
                order += 1
    while heap:
        _, _, index = heapq.heappop(heap)
        r, c = index // cols, index % cols
        for dr in (-1, 0, 1):
            for dc in (-1, 0, 1):
                nr, nc = r + dr, c + dc
                if (dr or dc) and 0 <= nr < rows and 0 <= nc < cols and labels[nr, nc] == 0 and free[nr, nc]:
                    labels[nr, nc] = labels[r, c]
                    heapq.heappush(heap, (height[nr, nc], order, nr * cols + nc))
                    order += 1


def _rooms(free: NDArray[np.bool_], distance_cells: NDArray[np.float64], cores: NDArray[np.int32],
           count: int, min_room_cells: int) -> NDArray[np.int32]:
    """Every free cell labelled with its room (0: none), by flooding from the cores."""
    labels = cores.copy()
    _flood(-distance_cells.astype(np.float64), free, labels)
    # Free components without a core (closets narrower than a door) are rooms of their own.
    components, n_components = ndimage.label(free, structure=EIGHT)
    orphan = np.ones(n_components + 1, dtype=bool)
    orphan[components[cores > 0]] = False
    orphan[0] = False
    lookup = np.zeros(n_components + 1, dtype=np.int32)
    lookup[orphan] = count + 1 + np.arange(int(orphan.sum()), dtype=np.int32)
    labels = np.where(orphan[components], lookup[components], labels)
    count += int(orphan.sum())
    sizes = np.bincount(labels.ravel(), minlength=count + 1)
    small = sizes < min_room_cells
    small[0] = False
    labels[small[labels]] = 0
    return labels


def _grow_into_walls(labels: NDArray[np.int32], free: NDArray[np.bool_]) -> NDArray[np.int32]:
    """Rooms reach WALL_MARGIN_CELLS into the walls around them (the nearest room takes each cell;
    chessboard distance, so that a room's corners stay square and its outline has few vertices)."""
    distance, (rows, cols) = ndimage.distance_transform_cdt(labels == 0, metric="chessboard", return_indices=True)
    grown = labels[rows, cols]
    return np.where((labels == 0) & ~free & (distance <= WALL_MARGIN_CELLS), grown, labels).astype(np.int32)


def _room_polygons(labels: NDArray[np.int32], occupancy: OccupancyMap, tolerance_cells: float) -> dict[int, shapely.Polygon]:
    """Each label's cells as one polygon, all simplified together as a coverage (neighbours keep one
    shared edge).  The faces come from polygonizing the unit cell edges between different labels,
    so every vertex two rooms share is a vertex of both (a coverage, as coverage_simplify needs)."""
    padded = np.pad(labels, 1)
    rows, cols = np.nonzero(padded[1:, :] != padded[:-1, :])         # horizontal edges at lattice y = row
    horizontal = np.column_stack([cols - 1, rows, cols, rows])
    rows, cols = np.nonzero(padded[:, 1:] != padded[:, :-1])         # vertical edges at lattice x = col
    vertical = np.column_stack([cols, rows - 1, cols, rows])
    segments = np.vstack([horizontal, vertical]).astype(np.float64).reshape(-1, 2, 2)
    faces = shapely.get_parts(shapely.polygonize(shapely.linestrings(segments)))
    points = shapely.get_coordinates(shapely.point_on_surface(faces))
    owner = labels[np.floor(points[:, 1]).astype(np.int64), np.floor(points[:, 0]).astype(np.int64)]
    order = sorted(set(owner.tolist()) - {0})
    merged = [shapely.union_all(faces[owner == label]) for label in order]
    simplified = shapely.coverage_simplify(merged, tolerance=tolerance_cells)
    res = occupancy.resolution
    polygons: dict[int, shapely.Polygon] = {}
    for label, geometry in zip(order, simplified, strict=True):
        parts = [g for g in shapely.get_parts(geometry) if isinstance(g, shapely.Polygon) and not g.is_empty]
        if parts:   # one outline per room: its holes are the map's walls (or rooms listed before it)
            ring = np.asarray(max(parts, key=lambda g: g.area).exterior.coords)
            polygons[label] = shapely.Polygon(np.column_stack([occupancy.x0 + ring[:, 0] * res,
                                                               occupancy.y0 + ring[:, 1] * res]))
    return polygons


def _doors(labels: NDArray[np.int32], free: NDArray[np.bool_], occupancy: OccupancyMap,
           names: dict[int, str]) -> list[CandidateDoor]:
    """Where two rooms' free cells touch: one door per connected stretch of their border."""
    res = occupancy.resolution
    free_labels = np.where(free, labels, 0)
    found: dict[tuple[int, int], list[tuple[int, int, float, float]]] = {}
    for axis in (0, 1):
        a = free_labels[:-1, :] if axis == 0 else free_labels[:, :-1]
        b = free_labels[1:, :] if axis == 0 else free_labels[:, 1:]
        rows, cols = np.nonzero((a > 0) & (b > 0) & (a != b))
        for row, col in zip(rows.tolist(), cols.tolist(), strict=True):
            la, lb = int(a[row, col]), int(b[row, col])
            if la not in names or lb not in names:
                continue
            x = occupancy.x0 + (col + (1.0 if axis == 1 else 0.5)) * res
            y = occupancy.y0 + (row + (1.0 if axis == 0 else 0.5)) * res
            found.setdefault((min(la, lb), max(la, lb)), []).append((row, col, x, y))
    doors: list[CandidateDoor] = []
    for (la, lb), cells in sorted(found.items()):
        points = np.array([(r, c) for r, c, _, _ in cells])
        r0, c0 = points.min(axis=0)
        window = np.zeros(tuple(points.max(axis=0) - (r0, c0) + 1), dtype=bool)
        window[points[:, 0] - r0, points[:, 1] - c0] = True
        parts, n_parts = ndimage.label(window, structure=EIGHT)
        part_of = parts[points[:, 0] - r0, points[:, 1] - c0]
        for part in range(1, n_parts + 1):
            xy = np.array([(x, y) for (_, _, x, y), p in zip(cells, part_of, strict=True) if p == part])
            span = float(np.max(np.hypot(*(xy[:, None, :] - xy[None, :, :]).transpose(2, 0, 1)))) + res
            if span < MIN_DOOR_WIDTH_M:
                continue
            mean = xy.mean(axis=0)
            x, y = xy[np.argmin(np.hypot(*(xy - mean).T))]
            doors.append(CandidateDoor(f"door_{len(doors) + 1}", (names[la], names[lb]),
                                       (round(float(x), 3), round(float(y), 3)), round(span, 2)))
    return doors


def layout_from_map(occupancy: OccupancyMap, *, unknown_is_wall: bool = True, door_width_m: float = 1.4,
                    min_room_area_m2: float = 2.0) -> MapLayout:
    """Candidate rooms (largest first), doors and a robot pose (the most open free spot)."""
    res = occupancy.resolution
    if not (math.isfinite(door_width_m) and 0 < door_width_m <= MAX_DOOR_WIDTH_M):
        raise LayoutError(f"a door width of {door_width_m:g} m; give one between 0 and {MAX_DOOR_WIDTH_M:g} m")
    free = ~occupancy.blocked(unknown_is_wall)
    if not free.any():
        raise LayoutError("the map has no free cell")
    map_area = occupancy.rows * occupancy.cols * res * res
    if not (math.isfinite(min_room_area_m2) and 0 < min_room_area_m2 <= map_area):
        raise LayoutError(f"no free area of at least {min_room_area_m2:g} m2 on the map: the whole map is "
                          f"{map_area:.4g} m2")
    distance_cells = ndimage.distance_transform_edt(free)   # to the nearest wall cell's centre
    cores, count = _cores(free, distance_cells, 0.5 * door_width_m / res + 0.5, max(4, round(0.25 / res ** 2)))
    labels = _rooms(free, distance_cells, cores, count, max(1, round(min_room_area_m2 / res ** 2)))
    if not labels.any():
        raise LayoutError(f"no free area of at least {min_room_area_m2:g} m2 on the map")
    areas = np.bincount(labels.ravel())
    order = [int(label) for label in np.argsort(-areas) if label and areas[label]]
    polygons = _room_polygons(_grow_into_walls(labels, free), occupancy, tolerance_cells=1.0)
    rooms: list[CandidateRoom] = []
    names: dict[int, str] = {}
    for label in order:
        polygon = polygons.get(label)
        if polygon is None or not polygon.is_valid:
            continue
        names[label] = f"room_{len(rooms) + 1}"
        coords = [(round(float(x), 3), round(float(y), 3)) for x, y in polygon.exterior.coords[:-1]]
        rooms.append(CandidateRoom(names[label], coords, round(float(areas[label]) * res * res, 1)))
    # A room inside another's hole is listed first, so that room_at() finds it and not the outer one.
    outlines = {room.name: shapely.Polygon(room.polygon) for room in rooms}
    inner = {room.name: shapely.Polygon(room.polygon).representative_point() for room in rooms}
    rooms.sort(key=lambda r: any(outlines[r.name].contains(p) for n, p in inner.items() if n != r.name))
    doors = _doors(labels, free, occupancy, names)
    best = np.where(np.isin(labels, list(names)), distance_cells, -1.0)
    row, col = np.unravel_index(int(np.argmax(best)), best.shape)
    x, y = occupancy.centre(int(row), int(col))
    return MapLayout(rooms=rooms, doors=doors, robot=(round(x, 3), round(y, 3), 0.0))


class _OneLineDumper(yaml.SafeDumper):
    """PyYAML's safe emitter, with every text that holds a line break or a control character
    double-quoted and escaped: each value stays on its line of the template."""


def _represent_text(dumper: yaml.SafeDumper, value: str) -> yaml.ScalarNode:
    style = '"' if any(not ch.isprintable() for ch in value) else None
    return dumper.represent_scalar("tag:yaml.org,2002:str", value, style=style)


_OneLineDumper.add_representer(str, _represent_text)


def _flow(value: object) -> str:
    """A value in YAML flow style on one line, written by the YAML emitter (never pasted text: a
    ``--name`` of ``x\nresolution: 0.1`` stays one quoted name, not a second key)."""
    text = yaml.dump(value, Dumper=_OneLineDumper, default_flow_style=True, width=float("inf"),
                     allow_unicode=True)
    return text.removesuffix("\n...\n").removesuffix("\n")


def scene_text(layout: MapLayout, map_yaml: Path, out: Path, name: str, unknown_is_wall: bool,
               door_width_m: float) -> str:
    """The starting scene as YAML, with commented examples to fill in."""
    reference = os.path.relpath(Path(map_yaml).resolve(), Path(out).resolve().parent)
    map_value = reference if unknown_is_wall else {"file": reference, "unknown": "free"}
    rooms = "\n".join(f"  - {{name: {r.name}, polygon: {_flow([list(p) for p in r.polygon])}}}   # {r.area_m2:g} m2"
                      for r in layout.rooms)
    doors = "\n".join(f"  - {{name: {d.name}, between: {_flow(list(d.between))}, position: {_flow(list(d.position))}, "
                      f"width: {d.width:g}}}" for d in layout.doors) or "  []"
    x, y, theta = layout.robot
    if not layout.rooms:
        raise LayoutError("no room could be drawn on the map")
    first = layout.rooms[0].name
    mission = (f"  - {{id: visit_{layout.rooms[1].name}, time: \"09:30\", goal: {{room: {layout.rooms[1].name}}}, "
               f"description: \"a first errand: from {first} to {layout.rooms[1].name}\"}}"
               if len(layout.rooms) > 1 else "  []")
    return f"""# A starting scene written by `chronav scene from-map {Path(map_yaml).name}`.
# Rooms are candidates: the map's free space cut at passages narrower than {door_width_m:g} m (the doors
# below are those passages). Rename, merge or redraw them, then fill in the commented examples.
# Check it with `chronav scene check` after every edit.
name: {_flow(name)}
description: {_flow(f"Scene on the building map {Path(map_yaml).name} (candidate rooms and doors to review).")}
map: {_flow(map_value)}
clock: {{date: 2026-11-25, timezone: Europe/Madrid, start: "09:00", end: "12:00", rate: 60, skip_idle: true}}

rooms:
{rooms}

doors:
{doors}

objects: []
# - name: tv
#   kind: tv
#   pose: [X, Y, THETA]                  # THETA: where the screen faces (rad)
#   footprint: {{shape: rectangle, length: 0.2, width: 1.2}}
#   interaction: {{shape: trapezoid, height: 2.8, near_width: 1.2, far_width: 3.2}}

people: []
# - {{name: resident_1, role: resident, pose: [X, Y, THETA]}}
# - name: nurse_1
#   role: staff
#   pose: [X, Y, THETA]
#   waypoints:
#     - {{time: "10:00", pose: [X, Y, THETA]}}

robot: {{name: robot, pose: {_flow([x, y, theta])}, radius: 0.3, kinematics: differential, max_speed: 0.6}}

agenda: []
# - {{id: serious_game, name: Serious game, object: tv, start: "10:30", end: "11:30", participants: [resident_1]}}

missions:
{mission}
# - {{id: to_the_tv, time: "10:45", goal: {{object: tv}}}}
# - {{id: greet, time: "11:00", goal: {{person: resident_1}}}}
"""
