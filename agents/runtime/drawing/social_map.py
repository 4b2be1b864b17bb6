"""Rerun views of the social map: cost layers in the seed's colour bands, zones, interaction spaces.

Why a class image (SegmentationImage + AnnotationContext) and not a heat map: the seeds explain
the map in discrete bands (free, social, personal, intimate; R(t) in four colour intervals from
yellow to dark orange), and a person reading the recording should see exactly those bands.
Kept out of the maths modules: algorithms return data, this layer draws it.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import shapely

from agents.lib.agenda.chronemics import BAND_COLOURS_RGB, BAND_NAMES

FREE, SOCIAL, PERSONAL, FORBIDDEN, WALL = 0, 1, 2, 3, 4
BAND0 = 5
CLASSES: list[tuple[int, str, tuple[int, int, int, int]]] = [
    (FREE, "free", (0, 0, 0, 0)),
    (SOCIAL, "social zone (cost 2)", (120, 190, 255, 150)),
    (PERSONAL, "personal zone (cost 4)", (170, 90, 220, 170)),
    (FORBIDDEN, "forbidden (intimate, bodies, footprints)", (220, 40, 40, 200)),
    (WALL, "wall (inflated)", (70, 70, 70, 255)),
    *[(BAND0 + i, f"interaction R {name}", (*rgb, 170)) for i, (name, rgb) in enumerate(zip(BAND_NAMES,
                                                                                           BAND_COLOURS_RGB,
                                                                                           strict=True))],
]
ZONE_COLOURS = {"intimate": (220, 40, 40), "personal": (170, 90, 220), "social": (60, 140, 255)}


def class_image(smap: Any) -> np.ndarray:
    """One uint8 class per cell, people's zones drawn over interaction spaces (they cost more)."""
    classes = np.full(smap.spec.shape, FREE, dtype=np.uint8)
    for space, mask in zip(smap.object_spaces, smap.interaction_cells, strict=True):
        if mask is None:
            continue
        rows, cols, cells = mask.rows, mask.cols, mask.mask
        region = classes[rows, cols]
        region[cells] = BAND0 + min(int(space.band), len(BAND_NAMES) - 1)
        classes[rows, cols] = region
    people = smap.layer("people")
    classes[people == 2.0] = SOCIAL
    classes[people == 4.0] = PERSONAL
    classes[~np.isfinite(smap.physical) | ~np.isfinite(people)] = FORBIDDEN
    classes[~np.isfinite(smap.static)] = WALL
    return classes


def _rings(geometry: Any) -> list[list[list[float]]]:
    polygons = getattr(geometry, "geoms", [geometry])
    rings: list[list[list[float]]] = []
    for polygon in polygons:
        if polygon.is_empty or not isinstance(polygon, shapely.Polygon):
            continue
        rings.append(np.asarray(polygon.exterior.coords).tolist())
        rings.extend(np.asarray(hole.coords).tolist() for hole in polygon.interiors)
    return rings


def log_social_map(rec: Any, smap: Any) -> None:
    """Log the map at the recorder's current sim time (the caller sets it)."""
    if not rec.enabled:
        return
    import rerun as rr

    spec = smap.spec
    rec.log("world/map/cost", rr.AnnotationContext([(cid, label, colour) for cid, label, colour in CLASSES]),
            static=True)
    rec.log("world/map/cost", rr.Transform3D(translation=[spec.x0, spec.y0, 0.0],
                                             scale=[spec.resolution, spec.resolution, 1.0]), static=True)
    rec.log("world/map/cost", rr.SegmentationImage(class_image(smap), draw_order=-10.0))
    for zone, colour in ZONE_COLOURS.items():
        rings = _rings(smap.zone_polygons()[zone])
        rec.log(f"world/zones/{zone}", rr.LineStrips2D(rings, colors=[colour], radii=0.02) if rings else rr.Clear(
            recursive=False))
    strips, colours, labels = [], [], []
    for space in smap.object_spaces:
        for ring in _rings(space.interaction):
            strips.append(ring)
            colours.append(BAND_COLOURS_RGB[min(int(space.band), len(BAND_COLOURS_RGB) - 1)])
            labels.append(f"{space.name} R={space.r:.2f}{' (active)' if space.active else ''}")
    if strips:
        rec.log("world/objects/interaction", rr.LineStrips2D(strips, colors=colours, labels=labels, radii=0.03))
    footprints = [ring for space in smap.object_spaces for ring in _rings(space.footprint)]
    if footprints:
        rec.log("world/objects/footprint", rr.LineStrips2D(footprints, colors=[[110, 60, 30]], radii=0.03),
                static=True)


def log_walls(rec: Any, walls: list[list[list[float]]]) -> None:
    if rec.enabled:
        import rerun as rr

        rec.log("world/map/walls", rr.LineStrips2D(walls, colors=[[20, 20, 20]], radii=0.06), static=True)
