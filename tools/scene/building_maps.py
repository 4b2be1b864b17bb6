"""Synthetic building maps in the ROS map_server format: the shipped ward and the benchmark's large floor.

Why synthetic: the shipped scene needs a map that can be committed (a 0.2 MB PGM) and the
benchmark a 100 m x 60 m floor at 5 cm; both are drawn here the way map_saver writes a SLAM map
(walls black, floor 254, unexplored 205, a ``# CREATOR`` comment in the PGM header) so the reader
meets what it meets in the field.  ``scenes/maps/ward.pgm`` was written by ``python -m
tools.scene.building_maps ward scenes/maps/ward.yaml``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

WALL, FREE, UNKNOWN = 0, 254, 205


class Floor:
    """A map being drawn in metres; ``pixels`` top row first, as in the image."""

    def __init__(self, width_m: float, height_m: float, resolution: float) -> None:
        self.resolution = resolution
        self.pixels: NDArray[np.uint8] = np.full((round(height_m / resolution), round(width_m / resolution)),
                                                 UNKNOWN, dtype=np.uint8)

    def _box(self, x0: float, y0: float, x1: float, y1: float) -> tuple[slice, slice]:
        rows = self.pixels.shape[0]
        r = self.resolution
        return (slice(rows - round(y1 / r), rows - round(y0 / r)), slice(round(x0 / r), round(x1 / r)))

    def fill(self, x0: float, y0: float, x1: float, y1: float, value: int) -> None:
        self.pixels[self._box(x0, y0, x1, y1)] = value

    def room(self, x0: float, y0: float, x1: float, y1: float, wall: float = 0.15) -> None:
        """A walled rectangle: walls ``wall`` thick centred on its edges, floor inside."""
        h = wall / 2
        self.fill(x0 - h, y0 - h, x1 + h, y1 + h, WALL)
        self.fill(x0 + h, y0 + h, x1 - h, y1 - h, FREE)

    def door(self, x: float, y: float, width: float, vertical_wall: bool, wall: float = 0.15) -> None:
        """An opening of ``width`` centred at (x, y) in a wall running along y (vertical) or x."""
        h, w = wall, width / 2
        if vertical_wall:
            self.fill(x - h, y - w, x + h, y + w, FREE)
        else:
            self.fill(x - w, y - h, x + w, y + h, FREE)

    def write(self, yaml_path: Path, origin: tuple[float, float] = (0.0, 0.0)) -> None:
        """``<name>.pgm`` (binary, with a map_saver-like comment) and the map_server yaml."""
        yaml_path = Path(yaml_path)
        rows, cols = self.pixels.shape
        header = f"P5\n# CREATOR: chronav tools/scene/building_maps.py {self.resolution:.3f} m/pix\n{cols} {rows}\n255\n"
        yaml_path.with_suffix(".pgm").write_bytes(header.encode("ascii") + self.pixels.tobytes())
        yaml_path.write_text(f"image: {yaml_path.with_suffix('.pgm').name}\nmode: trinary\n"
                             f"resolution: {self.resolution}\norigin: [{origin[0]}, {origin[1]}, 0.0]\n"
                             "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n", encoding="utf-8")


def ward(resolution: float = 0.05) -> Floor:
    """A 30 m x 16 m care-home ward: a corridor (y 6.8..9.2) between a lounge, a dining room and a
    nurse station (north) and four bedrooms with a bathroom (south); doors 1.2 m wide."""
    floor = Floor(31.0, 17.0, resolution)
    ox, oy = 0.5, 0.5                                   # the building inside an unexplored margin
    floor.room(ox, oy + 6.3, ox + 30, oy + 8.7)         # corridor
    for x in (0.0, 6.0, 12.0, 18.0, 24.0):
        floor.room(ox + x, oy, ox + x + 6.0, oy + 6.3)  # bedrooms 1-4 and the bathroom
        floor.door(ox + x + 3.0, oy + 6.3, 1.2, vertical_wall=False)
    floor.room(ox, oy + 8.7, ox + 14.0, oy + 16.0)      # lounge
    floor.room(ox + 14.0, oy + 8.7, ox + 24.0, oy + 16.0)   # dining room
    floor.room(ox + 24.0, oy + 8.7, ox + 30.0, oy + 16.0)   # nurse station
    floor.door(ox + 5.0, oy + 8.7, 1.6, vertical_wall=False)
    floor.door(ox + 19.0, oy + 8.7, 1.6, vertical_wall=False)
    floor.door(ox + 27.0, oy + 8.7, 1.2, vertical_wall=False)
    floor.door(ox + 14.0, oy + 12.0, 1.2, vertical_wall=True)   # lounge <-> dining room
    # Furniture the SLAM laser saw: a sofa and shelves in the lounge, the nurses' desk, beds.
    floor.fill(ox + 1.0, oy + 14.8, ox + 4.0, oy + 15.7, 0)
    floor.fill(ox + 10.0, oy + 15.5, ox + 13.5, oy + 15.85, 0)
    floor.fill(ox + 25.0, oy + 13.5, ox + 28.5, oy + 14.3, 0)
    for x in (0.0, 6.0, 12.0, 18.0):
        floor.fill(ox + x + 0.3, oy + 0.3, ox + x + 1.3, oy + 2.3, 0)
    return floor


def large_floor(width_m: float = 100.0, height_m: float = 60.0, resolution: float = 0.05) -> Floor:
    """The benchmark's floor: two 2.4 m corridors along x linked by three across, rooms of 6 m x 8 m
    on both sides of the long corridors with a 1.2 m door each, and a hall in the middle."""
    floor = Floor(width_m, height_m, resolution)
    corridors_y = (height_m * 0.3, height_m * 0.7)
    crossings_x = (width_m * 0.25, width_m * 0.5, width_m * 0.75)
    hall = (width_m * 0.4, corridors_y[0] + 1.2, width_m * 0.6, corridors_y[1] - 1.2)
    floor.room(0.5, 0.5, width_m - 0.5, height_m - 0.5)
    floor.fill(0.6, 0.6, width_m - 0.6, height_m - 0.6, UNKNOWN)    # unexplored inside the outer wall
    for cy in corridors_y:
        floor.fill(0.6, cy - 1.2, width_m - 0.6, cy + 1.2, FREE)
    for cx in crossings_x:
        floor.fill(cx - 1.2, 0.6, cx + 1.2, height_m - 0.6, FREE)
    floor.fill(*hall, FREE)
    x = 1.0
    while x + 6.0 < width_m - 1.0:
        for cy in corridors_y:
            for side in (-1, 1):
                y0, y1 = (cy + 1.2, cy + 9.2) if side > 0 else (cy - 9.2, cy - 1.2)
                crossing = any(x - 1.3 < cx < x + 7.3 for cx in crossings_x)
                in_hall = x + 6.0 > hall[0] - 0.2 and x < hall[2] + 0.2 and y1 > hall[1] and y0 < hall[3]
                if y0 < 0.6 or y1 > height_m - 0.6 or crossing or in_hall:
                    continue
                floor.room(x, y0, x + 6.0, y1)
                floor.door(x + 3.0, y0 if side > 0 else y1, 1.2, vertical_wall=False)
        x += 6.0
    return floor


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("kind", choices=("ward", "large"))
    parser.add_argument("out", type=Path, help="map yaml to write (the .pgm goes beside it)")
    options = parser.parse_args(argv)
    (ward() if options.kind == "ward" else large_floor()).write(options.out)


if __name__ == "__main__":
    main()
