"""Rerun views of the social map the navigation used: the **decision** layer (``world/decision``).

What the navigation decided on is logged every time it builds a social map (each plan, replan,
recovery and wait for a blocked way), at the map's own time, with a stamp (``DecisionStamp``:
when the map was computed, when the path in use was planned, how old the people it saw were).
So at any instant the viewer shows exactly what the navigation last used, never a map kept from
an earlier plan; when the robot has no navigation task the layer is cleared (nothing was used).

* People's zones (intimate / personal / social) are vector outlines, logged at every map build:
  cheap (a few kB) and exact at their time.
* The raster image (walls as inflated, the objects' interaction spaces coloured by the seeds'
  R(t) bands, spaces forbidden while their activity runs) holds no people, so it is logged only
  when it changes (a band or an activity changed), not 5 times a second at 600 kB each.
* Each object's R is a label at the object itself (not on the ring of its space, which put the
  TV's "R=3.50" beside a resident).

Why a class image (SegmentationImage + AnnotationContext) and not a heat map: the seeds explain
the map in discrete bands (free, social, personal, intimate; R(t) in four colour intervals from
yellow to dark orange), and a person reading the recording should see exactly those bands.
Kept out of the maths modules: algorithms return data, this layer draws it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, cast

import numpy as np
import shapely

from agents.lib.agenda.chronemics import BAND_COLOURS_RGB, BAND_NAMES

FREE, SOCIAL, PERSONAL, FORBIDDEN, WALL = 0, 1, 2, 3, 4
BAND0 = 5
CLASSES: list[tuple[int, str, tuple[int, int, int, int]]] = [
    (FREE, "free", (0, 0, 0, 0)),
    (SOCIAL, "social zone (cost 2)", (120, 190, 255, 150)),
    (PERSONAL, "personal zone (cost 4)", (170, 90, 220, 170)),
    (FORBIDDEN, "forbidden (activity running, footprints)", (220, 40, 40, 200)),
    (WALL, "wall (inflated by the robot's radius)", (70, 70, 70, 255)),
    *[(BAND0 + i, f"interaction R {name}", (*rgb, 170)) for i, (name, rgb) in enumerate(zip(BAND_NAMES,
                                                                                           BAND_COLOURS_RGB,
                                                                                           strict=True))],
]
ZONE_COLOURS = {"intimate": (235, 50, 50), "personal": (180, 100, 235), "social": (70, 150, 255)}
ZONE_RADII = {"intimate": 0.035, "personal": 0.03, "social": 0.025}
PATH_RGB = (255, 255, 255)
BAND_RGB = (120, 220, 255)
OBJECT_LABEL_RGB = (255, 215, 120)
STAMP_RGB = (230, 230, 230)
WALL_RGB = (185, 185, 185)
ORDER_WALLS = 3.0
STALE_AFTER_S = 1.0       # people seen longer ago than this are stale belief: the stamp says so
# Draw order (bodies.py holds the other layers): image -10 < interaction 1 < zones 2 < path 20.
ORDER_IMAGE, ORDER_INTERACTION, ORDER_ZONES, ORDER_PATH, ORDER_LABELS = -10.0, 1.0, 2.0, 20.0, 25.0
DECISION = "world/decision"


@dataclass(frozen=True, slots=True)
class DecisionStamp:
    """When what the decision layer shows was computed (sim s of the day)."""

    map_s: float                      # the social map's time
    planned_s: float | None = None    # the path in use was planned then (None: no path: waiting)
    seen_s: float | None = None       # the people in the map were observed up to then

    def text(self) -> str:
        parts = [f"map {format_clock_s(self.map_s)}",
                 f"path {format_clock_s(self.planned_s)}" if self.planned_s is not None else "no path (waiting)"]
        if self.seen_s is not None:
            age = self.map_s - self.seen_s
            parts.append(f"people seen {format_clock_s(self.seen_s)}"
                         + (f" - STALE {age:.1f} s" if age > STALE_AFTER_S else ""))
        return " | ".join(parts)


def format_clock_s(seconds: float) -> str:
    """``HH:MM:SS`` (whole seconds, always with seconds: stamps are compared at a glance)."""
    hours, rest = divmod(int(seconds), 3600)
    return f"{hours:02d}:{rest // 60:02d}:{rest % 60:02d}"


def class_image(smap: Any) -> np.ndarray:
    """One uint8 class per cell: walls as the planner sees them, interaction spaces by R band
    (forbidden while their activity runs).  No people: their zones are the vector layer."""
    classes = np.full(smap.spec.shape, FREE, dtype=np.uint8)
    for space, mask in zip(smap.object_spaces, smap.interaction_cells, strict=True):
        if mask is None:
            continue
        rows, cols, cells = mask.rows, mask.cols, mask.mask
        region = classes[rows, cols]
        region[cells] = FORBIDDEN if space.forbidden else BAND0 + min(int(space.band), len(BAND_NAMES) - 1)
        classes[rows, cols] = region
    classes[~np.isfinite(smap.static)] = WALL
    return classes


def image_key(smap: Any) -> tuple[Any, ...]:
    """What the class image depends on: when this is unchanged the image is too."""
    return (id(smap.static), smap.spec.shape,
            tuple((s.name, int(s.band), bool(s.forbidden)) for s in smap.object_spaces))


def zone_rings(smap: Any) -> dict[str, list[np.ndarray]]:
    """The outlines of the cells the planner priced as each person zone (social cost 2, personal
    4, intimate not traversable), predictions of walkers included: exactly what the navigation
    searched on.  Why the grid and not the density contours (``SocialMap.zone_polygons``): the
    grid is what was used, and contouring three levels of the people's patches (only the window
    they cover) costs a few ms where re-contouring the density costs ~30 ms, too much five times
    a second in the lockstep navigation."""
    import contourpy

    patches = [p for p in (*smap.zone_patches, *smap.prediction_patches) if p.values.size]
    out: dict[str, list[np.ndarray]] = {zone: [] for zone in ("social", "personal", "intimate")}
    if not patches:
        return out
    r0 = min(p.rows.start for p in patches)
    r1 = max(p.rows.stop for p in patches)
    c0 = min(p.cols.start for p in patches)
    c1 = max(p.cols.stop for p in patches)
    # One free cell of padding all round, so every zone is a closed ring.
    level = np.zeros((r1 - r0 + 2, c1 - c0 + 2), dtype=np.float32)
    for patch in patches:
        values = patch.values
        band = np.where(~np.isfinite(values), 3.0, np.where(values >= 4.0, 2.0, np.where(values >= 2.0, 1.0, 0.0)))
        window = level[patch.rows.start - r0 + 1:patch.rows.stop - r0 + 1,
                       patch.cols.start - c0 + 1:patch.cols.stop - c0 + 1]
        np.maximum(window, band, out=window)
    spec = smap.spec
    generator = contourpy.contour_generator(z=level, name="serial", line_type="Separate")
    for zone, threshold in (("social", 0.5), ("personal", 1.5), ("intimate", 2.5)):
        # line_type="Separate" returns a list of (n, 2) float arrays (contourpy's LineType docs); its
        # stubs type lines() as the union over every line type
        for line in cast("list[np.ndarray]", generator.lines(threshold)):
            # padded column j is grid column c0 + j - 1, whose centre is x0 + (c0 + j - 0.5) * res
            xy = np.empty(line.shape, dtype=float)
            xy[:, 0] = spec.x0 + (line[:, 0] + c0 - 0.5) * spec.resolution
            xy[:, 1] = spec.y0 + (line[:, 1] + r0 - 0.5) * spec.resolution
            out[zone].append(xy.astype(np.float32))   # arrays: Rerun takes them as they are (tolist() cost most)
    return out


def _rings(geometry: Any) -> list[list[list[float]]]:
    polygons = getattr(geometry, "geoms", [geometry])
    rings: list[list[list[float]]] = []
    for polygon in polygons:
        if polygon.is_empty or not isinstance(polygon, shapely.Polygon):
            continue
        rings.append(np.asarray(polygon.exterior.coords).tolist())
        rings.extend(np.asarray(hole.coords).tolist() for hole in polygon.interiors)
    return rings


class DecisionLogger:
    """Logs the decision layer of one navigation agent (one per agent: it remembers the image)."""

    def __init__(self, rec: Any) -> None:
        self.rec = rec
        self._image_key: tuple[Any, ...] | None = None
        self._static_logged = False
        self._cleared = True

    def log_map(self, smap: Any, stamp: DecisionStamp, anchor: Sequence[float] | None = None) -> None:
        """The social map the navigation just built and used, at the recorder's current time (the
        caller sets it to ``smap.t_s``).  ``anchor``: where the stamp text goes (the building's
        top-left corner)."""
        rec = self.rec
        if not rec.enabled:
            return
        import rerun as rr

        self._cleared = False
        spec = smap.spec
        if not self._static_logged:
            rec.log(f"{DECISION}/cost", rr.AnnotationContext([(cid, label, colour) for cid, label, colour in CLASSES]),
                    static=True)
            rec.log(f"{DECISION}/cost", rr.Transform3D(translation=[spec.x0, spec.y0, 0.0],
                                                       scale=[spec.resolution, spec.resolution, 1.0]), static=True)
            footprints = [ring for space in smap.object_spaces for ring in _rings(space.footprint)]
            if footprints:
                rec.log("world/objects/footprint", rr.LineStrips2D(footprints, colors=[[150, 90, 40]], radii=0.03),
                        static=True)
            self._static_logged = True
        key = image_key(smap)
        changed = key != self._image_key
        if changed:
            rec.log(f"{DECISION}/cost", rr.SegmentationImage(class_image(smap), draw_order=ORDER_IMAGE))
            self._image_key = key
        rings_of = zone_rings(smap)
        names = [p.name for p in smap.people]
        for zone, colour in ZONE_COLOURS.items():
            rings = rings_of[zone]
            if rings:
                rec.log(f"{DECISION}/zones/{zone}",
                        rr.LineStrips2D(rings, colors=[colour], radii=ZONE_RADII[zone], draw_order=ORDER_ZONES),
                        rr.AnyValues(map_s=float(smap.t_s), people=names or [""]))
            else:
                rec.log(f"{DECISION}/zones/{zone}", rr.Clear(recursive=False),
                        rr.AnyValues(map_s=float(smap.t_s), people=names or [""]))
        self._log_objects(smap, outlines=changed)
        self.log_stamp(stamp, anchor)

    def log_stamp(self, stamp: DecisionStamp, anchor: Sequence[float] | None = None) -> None:
        """When the map and the path in use were computed: a text row (``AnyValues`` ``map_s``,
        ``planned_s`` = -1 without a path) and, at ``anchor``, a label on the map."""
        if not self.rec.enabled:
            return
        import rerun as rr

        text = stamp.text()
        self.rec.log(f"{DECISION}/stamp", rr.TextLog(text),
                     rr.AnyValues(map_s=float(stamp.map_s),
                                  planned_s=float(stamp.planned_s) if stamp.planned_s is not None else -1.0))
        if anchor is not None:
            self.rec.log(f"{DECISION}/stamp_label", rr.Points2D([list(anchor)], radii=0.01, colors=[STAMP_RGB],
                                                                  labels=[text], draw_order=ORDER_LABELS))

    def _log_objects(self, smap: Any, outlines: bool) -> None:
        """Each object's R at the object (every map: R creeps); the outlines of the interaction
        spaces in their band colour only when a band changed (they are fixed shapes)."""
        import rerun as rr

        strips, colours, anchors, labels = [], [], [], []
        for space in smap.object_spaces:
            band_rgb = BAND_COLOURS_RGB[min(int(space.band), len(BAND_COLOURS_RGB) - 1)]
            for ring in _rings(space.interaction):
                strips.append(ring)
                colours.append(band_rgb)
            centre = space.footprint.centroid
            anchors.append([float(centre.x), float(centre.y)])
            labels.append(f"{space.name} R={space.r:.1f}{' (active)' if space.active else ''}")
        if strips and outlines:
            self.rec.log(f"{DECISION}/objects/interaction",
                         rr.LineStrips2D(strips, colors=colours, radii=0.03, draw_order=ORDER_INTERACTION))
        if anchors:
            self.rec.log(f"{DECISION}/objects/labels",
                         rr.Points2D(anchors, radii=0.06, colors=[OBJECT_LABEL_RGB], labels=labels,
                                     draw_order=ORDER_LABELS))

    def log_path(self, points: Sequence[Sequence[float]]) -> None:
        """The global path adopted (at the recorder's current time)."""
        if self.rec.enabled and len(points) >= 2:
            import rerun as rr

            self.rec.log(f"{DECISION}/path", rr.LineStrips2D([list(map(list, points))], colors=[PATH_RGB],
                                                             radii=0.04, draw_order=ORDER_PATH))

    def log_band(self, points: Sequence[Sequence[float]]) -> None:
        """The elastic band being followed."""
        if self.rec.enabled and len(points) >= 2:
            import rerun as rr

            self.rec.log(f"{DECISION}/band", rr.LineStrips2D([list(map(list, points))], colors=[BAND_RGB],
                                                             radii=0.025, draw_order=ORDER_PATH + 1))

    def clear(self, why: str = "no navigation task") -> None:
        """The navigation uses no map now: nothing of an earlier decision stays on screen."""
        if not self.rec.enabled or self._cleared:
            return
        import rerun as rr

        # Each leaf cleared by name (not one recursive clear): readers of the recording's
        # dataframes see the clear at the entity itself, as the viewer does.
        for part in (*(f"zones/{zone}" for zone in ZONE_COLOURS), "objects/interaction", "objects/labels", "path",
                     "band", "stamp_label", "cost"):
            self.rec.log(f"{DECISION}/{part}", rr.Clear(recursive=False))
        self.rec.log(f"{DECISION}/stamp", rr.TextLog(why))
        self._image_key = None
        self._cleared = True


def log_walls(rec: Any, walls: list[list[list[float]]]) -> None:
    if rec.enabled:
        import rerun as rr

        # Light grey: the floor is black (free) or dark grey (inflated walls) and the viewer's background is dark.
        rec.log("world/map/walls", rr.LineStrips2D(walls, colors=[WALL_RGB], radii=0.06, draw_order=ORDER_WALLS),
                static=True)
