"""The map's layers as cost patches (grid.py composes them): bodies, object footprints and object
interaction spaces. Walls and rooms are the static grid (grid.static_grid); the people's zones come
from zones.band_patches.
"""

from __future__ import annotations

from collections.abc import Sequence
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from shapely.geometry import Polygon

from agents.lib.socialmap.grid import BLOCKED, COST_DTYPE, CostPatch, GridSpec, disc_patch, geometry_mask
from agents.lib.socialmap.objects import ObjectGeometry, local_contains
from agents.lib.socialmap.types import Person, SocialObject
from scenes.geometry import Shape


@dataclass(frozen=True, slots=True)
class CellMask:
    """The cells of one shape, on its window of the grid."""

    rows: slice
    cols: slice
    mask: NDArray[np.bool_]

    def flat_indices(self, spec: GridSpec) -> NDArray[np.int64]:
        local_r, local_c = np.nonzero(self.mask)
        return (local_r + self.rows.start) * spec.cols + (local_c + self.cols.start)


def body_patches(spec: GridSpec, people: Sequence[Person], radius_m: float) -> list[CostPatch]:
    """Each person's body, inflated by the robot radius, is an obstacle (also for the baseline)."""
    patches = []
    for person in people:
        patch = disc_patch(spec, person.x, person.y, radius_m, BLOCKED)
        if patch is not None:
            patches.append(patch)
    return patches


def shape_mask(spec: GridSpec, obj: SocialObject, shape: Shape, polygon: Polygon, inflate_m: float = 0.0) -> CellMask | None:
    """The cells of one of ``obj``'s shapes (grown by ``inflate_m``), on its window of the grid."""
    xmin, ymin, xmax, ymax = polygon.bounds
    window = spec.window(xmin - inflate_m, ymin - inflate_m, xmax + inflate_m, ymax + inflate_m)
    if window is None:
        return None
    rows, cols = window
    dx = spec.xs(cols)[np.newaxis, :] - obj.x
    dy = spec.ys(rows)[:, np.newaxis] - obj.y
    cos_t, sin_t = math.cos(obj.theta), math.sin(obj.theta)
    mask = local_contains(shape, dx * cos_t + dy * sin_t, dy * cos_t - dx * sin_t, inflate_m)
    if mask is None:   # no closed form: let shapely decide
        found = geometry_mask(spec, polygon.buffer(inflate_m))
        return None if found is None else CellMask(*found)
    return CellMask(rows, cols, mask)


def footprint_patches(spec: GridSpec, objects: Sequence[SocialObject], geometries: Sequence[ObjectGeometry],
                      inflate_m: float) -> list[CostPatch]:
    """Object footprints (optionally inflated by the robot radius) are obstacles."""
    patches = []
    for obj, geometry in zip(objects, geometries, strict=True):
        found = shape_mask(spec, obj, obj.footprint, geometry.footprint, inflate_m)
        if found is not None:
            patches.append(CostPatch(found.rows, found.cols, np.where(found.mask, BLOCKED, 0.0).astype(COST_DTYPE)))
    return patches


def interaction_masks(spec: GridSpec, objects: Sequence[SocialObject],
                      geometries: Sequence[ObjectGeometry]) -> list[CellMask | None]:
    """The cells of each object's interaction space (None when it lies outside the grid)."""
    return [shape_mask(spec, obj, obj.interaction, geometry.interaction)
            for obj, geometry in zip(objects, geometries, strict=True)]


def interaction_patches(masks: Sequence[CellMask | None], costs: Sequence[float]) -> list[CostPatch]:
    """Each interaction space at one cost (its R(t), or inf while active if forbidden)."""
    patches = []
    for mask, cost in zip(masks, costs, strict=True):
        if mask is not None:
            patches.append(CostPatch(mask.rows, mask.cols, np.where(mask.mask, cost, 0.0).astype(COST_DTYPE)))
    return patches
