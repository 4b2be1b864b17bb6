"""Intimate, personal and social zones: the people's density on grid windows, its cost bands and
its contour polygons (seed sections 4.1 and 5.2.1).

Each group's density (groups.py) is evaluated only on a window around its members, large enough
that the density is below the social level outside it (so nothing is cut off), never on the full
grid. Costs come from comparing the density with the three levels (a lookup table: free, social,
personal, forbidden); polygons come from contourpy's filled contours of the same windows, so the
zone a cell's cost says and the polygon drawn around it agree to within a cell.

Default levels 0.8 (intimate), 0.4 (personal), 0.1 (social): the seeds give none; these are the
thresholds of the RoboComp social navigation code the seeds' experiments ran, and with the metric
scale of personal_space.py they reproduce Tables 1-2 (module doc there) and Hall's 0.45 m intimate
distance to the sides.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import cast

import contourpy
import numpy as np
import shapely
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field, model_validator
from shapely.geometry import MultiPolygon, Polygon
from shapely.geometry.base import BaseGeometry

from agents.lib.socialmap.grid import COST_DTYPE, CostPatch, GridSpec
from agents.lib.socialmap.groups import Group, group_density
from agents.lib.socialmap.personal_space import PersonalSpace, support_radius
from agents.lib.socialmap.types import Person

ZONE_NAMES: tuple[str, ...] = ("intimate", "personal", "social")


class ZoneParams(BaseModel):
    """Density levels that bound the zones (a zone is where the density is >= its level)."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    intimate: float = Field(0.8, gt=0, lt=1)
    personal: float = Field(0.4, gt=0, lt=1)
    social: float = Field(0.1, gt=0, lt=1)

    @model_validator(mode="after")
    def _nested(self) -> ZoneParams:
        if not self.intimate > self.personal > self.social:
            raise ValueError("zone levels must satisfy intimate > personal > social")
        return self

    def level(self, zone: str) -> float:
        if zone not in ZONE_NAMES:
            raise ValueError(f"unknown zone {zone!r}; expected one of {ZONE_NAMES}")
        return float(getattr(self, zone))


@dataclass(frozen=True, slots=True)
class DensityWindow:
    """One group's density on a window of the grid (cell centres)."""

    group: Group
    rows: slice
    cols: slice
    density: NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class GroupZones:
    """A group's zone regions. Each is the region where the density reaches that zone's level, so
    they are nested (intimate within personal within social); ``core`` is Eq. 8's J at phi."""

    names: tuple[str, ...]
    intimate: BaseGeometry
    personal: BaseGeometry
    social: BaseGeometry
    core: BaseGeometry
    phi: float

    def zone(self, name: str) -> BaseGeometry:
        if name not in ZONE_NAMES:
            raise ValueError(f"unknown zone {name!r}; expected one of {ZONE_NAMES}")
        return getattr(self, name)


def group_window(spec: GridSpec, people: Sequence[Person], spaces: Sequence[PersonalSpace], group: Group,
                 params: ZoneParams) -> tuple[slice, slice] | None:
    """The smallest window outside which ``group``'s density is below ``params.social`` (None: off
    the grid).  A member's Gaussian is below social / n outside its ``support_radius(social / n)``,
    so the sum of n members is below social outside the union of those discs."""
    members = group.members
    level = params.social / len(members)
    xmin = ymin = math.inf
    xmax = ymax = -math.inf
    for i in members:
        radius = support_radius(spaces[i], level) + spec.resolution
        xmin, xmax = min(xmin, people[i].x - radius), max(xmax, people[i].x + radius)
        ymin, ymax = min(ymin, people[i].y - radius), max(ymax, people[i].y + radius)
    return spec.window(xmin, ymin, xmax, ymax)


def density_windows(spec: GridSpec, people: Sequence[Person], spaces: Sequence[PersonalSpace],
                    groups: Sequence[Group], params: ZoneParams) -> list[DensityWindow]:
    """Each group's density on its ``group_window``."""
    windows: list[DensityWindow] = []
    for group in groups:
        window = group_window(spec, people, spaces, group, params)
        if window is None:
            continue
        rows, cols = window
        xs, ys = spec.xs(cols), spec.ys(rows)
        density = group_density(people, spaces, group.members, xs[np.newaxis, :], ys[:, np.newaxis])
        windows.append(DensityWindow(group=group, rows=rows, cols=cols, density=density))
    return windows


def band_patches(windows: Sequence[DensityWindow], params: ZoneParams, social_cost: float,
                 personal_cost: float) -> list[CostPatch]:
    """Cost patches: social cost >= social level, personal >= personal level, inf >= intimate."""
    table = np.array([0.0, social_cost, personal_cost, math.inf], dtype=COST_DTYPE)
    patches = []
    for window in windows:
        d = window.density
        index = ((d >= params.social).astype(np.int8) + (d >= params.personal) + (d >= params.intimate))
        patches.append(CostPatch(window.rows, window.cols, table[index]))
    return patches


def zone_patches(spec: GridSpec, people: Sequence[Person], spaces: Sequence[PersonalSpace],
                 groups: Sequence[Group], params: ZoneParams, social_cost: float,
                 personal_cost: float) -> list[CostPatch]:
    """``band_patches(density_windows(...))``, the same patches cell for cell, without the densities:
    each group's window banded by the compiled kernel (banded.py), which skips the exponentials of
    the cells far below the social level (most of a window).  Why: at every replan of a crowd the
    densities were built only to be banded (the map's zone polygons need them, on demand only)."""
    from agents.lib.socialmap.banded import banded_group    # numba: loaded with the first map

    table = np.array([0.0, social_cost, personal_cost, math.inf], dtype=COST_DTYPE)
    levels = np.array([params.social, params.personal, params.intimate])
    patches = []
    for group in groups:
        window = group_window(spec, people, spaces, group, params)
        if window is None:
            continue
        rows, cols = window
        members = group.members
        patches.append(CostPatch(rows, cols, banded_group([spaces[i] for i in members],
                                                          [(people[i].x, people[i].y, people[i].theta) for i in members],
                                                          spec.xs(cols), spec.ys(rows), levels, table)))
    return patches


def _filled_polygons(xs: NDArray[np.float64], ys: NDArray[np.float64], z: NDArray[np.float64],
                     level: float) -> BaseGeometry:
    """The region z >= level as shapely polygons (holes kept), from contourpy."""
    if z.size == 0 or float(z.max()) < level or len(xs) < 2 or len(ys) < 2:
        return MultiPolygon()
    generator = contourpy.contour_generator(xs, ys, z, fill_type=contourpy.FillType.OuterOffset)
    # OuterOffset fills come back as (points, offsets); the stubs type every fill type's tuple at once
    points_list, offsets_list = cast("tuple[list[NDArray[np.float64]], list[NDArray[np.uint32]]]",
                                     generator.filled(level, math.inf))
    polygons = []
    for points, offsets in zip(points_list, offsets_list, strict=True):
        rings = [points[offsets[i]:offsets[i + 1]] for i in range(len(offsets) - 1)]
        if len(rings[0]) >= 4:
            polygons.append(Polygon(rings[0], [r for r in rings[1:] if len(r) >= 4]))
    if not polygons:
        return MultiPolygon()
    return shapely.union_all(polygons) if len(polygons) > 1 else polygons[0]


def contour_zones(spec: GridSpec, windows: Sequence[DensityWindow], params: ZoneParams) -> list[GroupZones]:
    """Zone polygons of every group (only its window is contoured)."""
    zones = []
    for window in windows:
        xs, ys = spec.xs(window.cols), spec.ys(window.rows)
        z = window.density
        group = window.group
        core = _filled_polygons(xs, ys, z, group.phi) if len(group.members) > 1 else MultiPolygon()
        zones.append(GroupZones(names=group.names,
                                intimate=_filled_polygons(xs, ys, z, params.intimate),
                                personal=_filled_polygons(xs, ys, z, params.personal),
                                social=_filled_polygons(xs, ys, z, params.social),
                                core=core, phi=group.phi))
    return zones
