"""Occupancy-grid maps in the ROS map_server format: a ``.yaml`` naming a ``.pgm``/``.png`` image.

Why here, with the scene: a care home's robot already has a map of its building, built with SLAM
and saved by ``map_saver``; a chronav scene may stand on it (``map: building.yaml``).  The file is
scene input, so it is read and checked with the scene, and every layer above (the simulator's
laser and bumper, the social map, the executive's free space) derives its walls from the one
:class:`OccupancyMap` read here.

Reading follows Nav2's ``nav2_map_server/src/map_io.cpp`` exactly, so a map means to chronav what
it means to Nav2:

* ``shade`` is the mean of the pixel's colour channels over the maximum value (grey images: the
  grey value / 255); in ``trinary`` mode an alpha channel is averaged in with the colours.
* ``occ = shade`` when ``negate`` is set, ``1 - shade`` otherwise (white is free by default).
* ``trinary``: 100 (occupied) if ``occ > occupied_thresh``, 0 (free) if ``occ < free_thresh``,
  else -1 (unknown).  ``scale``: the same, but a pixel that is not fully opaque is unknown and the
  values in between are ``rint((occ - free) / (occupied - free) * 100)``.  ``raw``: the value is
  ``round(shade * 255)`` when in 0..100, else unknown (``negate`` and the thresholds are ignored).
* The image's top row is the map's last row: row 0 of :attr:`OccupancyMap.values` is the bottom
  one, at ``origin`` y (map_server's ``origin`` is the lower-left corner of the lower-left pixel).

Which cells are walls follows Nav2's static layer with its defaults (``lethal_threshold`` 100,
``trinary_costmap`` true): a cell is occupied when its value is 100; unknown cells (-1) are walls
too unless the scene says ``unknown: free``.  Images are read with Pillow (PGM with header
comments, binary or ASCII, 8 or 16 bit; PNG grey, grey+alpha, RGB, RGBA or palette).
"""

from __future__ import annotations

import io
import math
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np
import yaml
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from scenes.files import read_bounded
from scenes.limits import GRID_CELLS
from scenes.yamlio import SourceError, load_located_file, validate_located

OCCUPIED = 100         # nav_msgs/OccupancyGrid: occupied
FREE = 0
UNKNOWN = -1
MAX_MAP_CELLS = 25_000_000   # 5000 x 5000: a 250 m x 250 m building at 5 cm
# A map cell is one cell of the scene's grid; finer or coarser than these is a mistake in the file
# (1e-200 m divided by zero, 1e300 m overflowed), and a corner further away is not a building.
MIN_MAP_RESOLUTION_M = 0.001
MAX_MAP_RESOLUTION_M = 10.0
MAX_MAP_ORIGIN_M = 100_000.0
MAX_MAP_IMAGE_BYTES = 256 * 1024 * 1024   # larger than any image of MAX_MAP_CELLS pixels
YAW_TOLERANCE_RAD = 1e-9


class MapYaml(BaseModel):
    """The map_server metadata file (Nav2 requires every key but ``mode``)."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    image: str = Field(min_length=1, description="image file, relative to the yaml")
    resolution: float = Field(ge=MIN_MAP_RESOLUTION_M, le=MAX_MAP_RESOLUTION_M, description="metres per pixel")
    origin: tuple[float, float, float] = Field(description="[x, y, yaw] of the lower-left pixel's corner")
    negate: bool = Field(description="0: white is free; 1: black is free")
    occupied_thresh: float = Field(ge=0.0, le=1.0)
    free_thresh: float = Field(ge=0.0, le=1.0)
    mode: Literal["trinary", "scale", "raw"] = "trinary"

    @field_validator("resolution")
    @classmethod
    def _finite_resolution(cls, value: float) -> float:
        if not math.isfinite(value):
            raise ValueError("must be a finite number")
        return value

    @field_validator("negate", mode="before")
    @classmethod
    def _negate(cls, value: Any) -> Any:
        """map_server accepts 0/1 or a boolean."""
        if value in (0, 1) and not isinstance(value, float):
            return bool(value)
        if isinstance(value, bool):
            return value
        raise ValueError("negate is 0 or 1")

    @field_validator("origin")
    @classmethod
    def _origin(cls, value: tuple[float, float, float]) -> tuple[float, float, float]:
        if not all(math.isfinite(v) for v in value):
            raise ValueError("origin must be three finite numbers [x, y, yaw]")
        if max(abs(value[0]), abs(value[1])) > MAX_MAP_ORIGIN_M:
            raise ValueError(f"origin [{value[0]:g}, {value[1]:g}] is more than {MAX_MAP_ORIGIN_M:,.0f} m from the "
                             "map frame's origin; a building map's corner is within a few hundred metres of it")
        if abs(value[2]) > YAW_TOLERANCE_RAD:
            raise ValueError(f"origin yaw is {value[2]:g} rad; chronav needs an unrotated map (yaw 0): "
                             "rotate the image instead")
        return value

    @model_validator(mode="after")
    def _thresholds(self) -> MapYaml:
        if self.free_thresh >= self.occupied_thresh:
            raise ValueError("free_thresh must be smaller than occupied_thresh")
        return self


@dataclass(frozen=True, eq=False)
class OccupancyMap:
    """A map as Nav2's map_server publishes it: OccupancyGrid values, bottom row first.

    ``values[row, col]`` is -1 (unknown), 0 (free) .. 100 (occupied); cell (row, col) spans
    x in [x0 + col res, x0 + (col + 1) res) and y in [y0 + row res, y0 + (row + 1) res)."""

    values: NDArray[np.int8]
    resolution: float
    x0: float
    y0: float
    yaml_path: Path
    image_path: Path
    mode: str = "trinary"

    @property
    def rows(self) -> int:
        return int(self.values.shape[0])

    @property
    def cols(self) -> int:
        return int(self.values.shape[1])

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """(xmin, ymin, xmax, ymax) in metres."""
        return (self.x0, self.y0, self.x0 + self.cols * self.resolution, self.y0 + self.rows * self.resolution)

    @property
    def occupied(self) -> NDArray[np.bool_]:
        return self.values >= OCCUPIED

    @property
    def unknown(self) -> NDArray[np.bool_]:
        return self.values < 0

    def blocked(self, unknown_is_wall: bool = True) -> NDArray[np.bool_]:
        """The walls: occupied cells, and unknown ones when ``unknown_is_wall``."""
        return (self.values >= OCCUPIED) | (self.values < 0) if unknown_is_wall else self.values >= OCCUPIED

    def cell_of(self, x: float, y: float) -> tuple[int, int] | None:
        """(row, col) of the cell containing (x, y), or None outside the map."""
        col = math.floor((x - self.x0) / self.resolution)
        row = math.floor((y - self.y0) / self.resolution)
        if 0 <= row < self.rows and 0 <= col < self.cols:
            return row, col
        return None

    def centre(self, row: int, col: int) -> tuple[float, float]:
        return (self.x0 + (col + 0.5) * self.resolution, self.y0 + (row + 0.5) * self.resolution)

    def pixel(self, row: int, col: int) -> tuple[int, int]:
        """(column, row) of the image pixel of a cell, counted from the image's top-left corner."""
        return col, self.rows - 1 - row

    def describe_cell(self, row: int, col: int) -> str:
        """How an error names a cell: its centre in metres and its pixel in the image."""
        x, y = self.centre(row, col)
        px, py = self.pixel(row, col)
        return f"the cell centred at ({x:.3f}, {y:.3f}) m, pixel ({px}, {py}) of {self.image_path.name}"


def _levels(image: Any, mode: str) -> tuple[NDArray[np.integer], int, NDArray[np.bool_] | None]:
    """Per pixel the sum of the channels map_io averages (shade = level / top), ``top``, and where
    the pixel is not fully opaque (None without an alpha channel).  Integers, so that the values
    come from a lookup table over the possible levels instead of float maths on every pixel."""
    if image.mode == "P":
        image = image.convert("RGBA" if "transparency" in image.info else "RGB")
    elif image.mode == "1":
        image = image.convert("L")
    elif image.mode == "PA":
        image = image.convert("RGBA")
    if image.mode in ("I;16", "I;16B", "I;16L", "I"):
        grey = np.clip(np.asarray(image, dtype=np.int64), 0, 65535)
        return grey, 65535, None
    if image.mode not in ("L", "LA", "RGB", "RGBA"):
        raise ValueError(f"unsupported image mode {image.mode!r}; save the map as 8-bit grey PGM or PNG")
    data = np.asarray(image)
    if image.mode == "L":
        return data, 255, None
    if image.mode == "RGB":
        return data.sum(axis=2, dtype=np.uint16), 3 * 255, None
    colours = 3 * data[..., 0].astype(np.uint16) if image.mode == "LA" else data[..., :3].sum(axis=2, dtype=np.uint16)
    alpha = data[..., -1]
    if mode == "trinary":   # map_io: "average in alpha with color channels in Trinary mode"
        return colours + alpha, 4 * 255, alpha < 255
    return colours, 3 * 255, alpha < 255


def occupancy_values(shade: NDArray[np.float64], transparent: NDArray[np.bool_] | None, meta: MapYaml) -> NDArray[np.int8]:
    """OccupancyGrid values of an image (top row first), as map_io computes them."""
    if meta.mode == "raw":
        percent = np.floor(shade * 255.0 + 0.5)   # std::round
        return np.where((percent >= 0) & (percent <= 100), percent, UNKNOWN).astype(np.int8)
    occ = shade if meta.negate else 1.0 - shade
    values = np.full(shade.shape, UNKNOWN, dtype=np.int8)
    if meta.mode == "scale":
        between = np.rint((occ - meta.free_thresh) / (meta.occupied_thresh - meta.free_thresh) * 100.0)
        values[:] = np.clip(between, 0, 100).astype(np.int8)
    values[occ < meta.free_thresh] = FREE
    values[occ > meta.occupied_thresh] = OCCUPIED
    if meta.mode == "scale" and transparent is not None:
        values[transparent] = UNKNOWN
    return values


def load_occupancy(yaml_path: str | Path) -> OccupancyMap:
    """Read a map_server map; SourceError naming the yaml (file:line: key) or the image otherwise."""
    from PIL import Image, UnidentifiedImageError

    yaml_path = Path(yaml_path)
    if not yaml_path.exists():
        raise SourceError(str(yaml_path), 1, 1, "", "no such map file")
    located = load_located_file(yaml_path)
    if not isinstance(located.data, dict):
        raise SourceError(str(yaml_path), 1, 1, "", "a map file must be a YAML mapping (image, resolution, "
                          "origin, negate, occupied_thresh, free_thresh, mode)")
    if "image" not in located.data and {"rooms", "robot", "walls", "map"} & set(located.data):
        # A chronav scene where a map_server yaml was expected: say so, not "unknown key 'name'".
        map_ref = located.data.get("map")
        hint = f" (this scene stands on map: {map_ref})" if isinstance(map_ref, str) else ""
        raise SourceError(str(yaml_path), 1, 1, "", "this is a chronav scene file, not a map_server map yaml "
                          f"(image, resolution, origin, ...){hint}; give the map's yaml, e.g. "
                          "scenes/maps/ward.yaml, as saved by map_saver")
    meta = validate_located(MapYaml, located)
    image_path = Path(meta.image)
    if not image_path.is_absolute():
        image_path = yaml_path.parent / image_path

    def image_error(message: str) -> SourceError:
        return located.error(("image",), f"{image_path}: {message}")

    if not image_path.exists():
        raise image_error("no such image file")
    try:   # a regular file (a FIFO would block Pillow forever), within a byte bound
        data = read_bounded(image_path, max_bytes=MAX_MAP_IMAGE_BYTES, what="map image")
    except SourceError as exc:
        raise image_error(exc.message) from None
    # Each pixel is a cell of the scene's grid, so a map of more cells than the grid may have could
    # never be used: refused from the image's header, before its pixels are decoded (a 35 KB PNG
    # can hold 5000 x 5000 of them).
    max_pixels = min(MAX_MAP_CELLS, GRID_CELLS.value())
    too_big = (f"chronav reads maps of 1 to {max_pixels:,} pixels, one grid cell each ({GRID_CELLS.env}); "
               "crop it or use a coarser resolution")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)
            image = Image.open(io.BytesIO(data))
        with image:
            width, height = image.size
            if width * height > max_pixels or width == 0 or height == 0:
                raise image_error(f"the image is {width:,} x {height:,} pixels; {too_big}")
            image.load()
            levels, top, transparent = _levels(image, meta.mode)
    except SourceError:
        raise
    except Image.DecompressionBombError:   # Pillow's own bound (179 million pixels) met in the header
        raise image_error(f"the image has more than {Image.MAX_IMAGE_PIXELS:,} pixels; {too_big}") from None
    except (UnidentifiedImageError, OSError, ValueError, SyntaxError) as exc:
        raise image_error(f"not a readable map image ({exc}); map_server images are PGM or PNG") from None
    lookup = occupancy_values(np.arange(top + 1, dtype=np.float64) / top, None, meta)
    values = lookup[levels]
    if meta.mode == "scale" and transparent is not None:
        values[transparent] = UNKNOWN
    x0, y0, _ = meta.origin
    return OccupancyMap(values=np.ascontiguousarray(values[::-1]), resolution=meta.resolution, x0=x0, y0=y0,
                        yaml_path=yaml_path, image_path=image_path, mode=meta.mode)


# ------------------------------------------------------------------------------------------- writing
def scale_pixels(values: NDArray[np.integer]) -> NDArray[np.uint8]:
    """Grey pixels that a ``mode: scale`` map with ``free_thresh: 0``, ``occupied_thresh: 1`` reads
    back as exactly ``values`` (0..100), as Nav2's map_saver writes them: (100 - v) / 100 of white."""
    values = np.asarray(values)
    if values.size and (values.min() < 0 or values.max() > 100):
        raise ValueError("scale pixels encode values 0..100")
    return np.rint((100.0 - values) / 100.0 * 255.0).astype(np.uint8)


def trinary_pixels(values: NDArray[np.integer]) -> NDArray[np.uint8]:
    """map_saver's trinary pixels: occupied 0 (black), free 254, unknown 205."""
    values = np.asarray(values)
    return np.where(values < 0, 205, np.where(values >= OCCUPIED, 0, 254)).astype(np.uint8)


def write_map(yaml_path: str | Path, values: NDArray[np.integer], resolution: float, origin: tuple[float, float],
              mode: Literal["trinary", "scale"] = "trinary", header: str = "") -> Path:
    """Write ``values`` (bottom row first) as a map_server map: ``<name>.pgm`` beside ``yaml_path``.

    ``trinary`` keeps occupied / free / unknown (thresholds 0.65 / 0.196: with map_saver's 0.25, its
    unknown grey 205 would read back as free); ``scale``
    keeps every value 0..100 exactly (thresholds 1 / 0).  ``header`` becomes comments atop the yaml."""
    from PIL import Image

    yaml_path = Path(yaml_path)
    values = np.asarray(values)
    pixels = trinary_pixels(values) if mode == "trinary" else scale_pixels(values)
    image_path = yaml_path.with_suffix(".pgm")
    Image.fromarray(np.ascontiguousarray(pixels[::-1]), mode="L").save(image_path)
    thresholds = (0.65, 0.196) if mode == "trinary" else (1.0, 0.0)
    meta = {"image": image_path.name, "mode": mode, "resolution": float(resolution),
            "origin": [float(origin[0]), float(origin[1]), 0.0], "negate": 0,
            "occupied_thresh": thresholds[0], "free_thresh": thresholds[1]}
    comments = "".join(f"# {line}\n" if line else "#\n" for line in header.splitlines())
    yaml_path.write_text(comments + yaml.safe_dump(meta, sort_keys=False, default_flow_style=None), encoding="utf-8")
    return image_path
