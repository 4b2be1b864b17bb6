"""Adaptive personal space (the blog seed): shrink one side of a person's space near a wall.

For each person, rays go ahead, behind, left and right to the walls (d_i). With d_r the robot's
diameter plus a safety margin, d_s = d_i - d_r is the room left between the person and a robot
hugging the wall. If d_min < d_s < d_max and that side's contour reaches beyond d_s, the side's
sigma is set so that the contour lies exactly at d_s: sigma = d_s / sqrt(2 ln(1/level))
(personal_space.sigma_for_contour; the seed fitted 1.2 x^-0.97 instead).

Why the two bounds: below d_min the robot could only pass by coming closer than the intimate
distance, so the space is kept and the gap stays expensive or closed; above d_max there is room
enough and nothing changes. Defaults are our choice (the blog gives no numbers): d_min = 0.45 m
(Hall's intimate distance), d_max = 1.2 m (Hall's personal distance), margin 0.1 m.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import shapely
from pydantic import BaseModel, ConfigDict, Field, model_validator
from shapely.geometry.base import BaseGeometry

from agents.lib.socialmap.occupancy import OccupancyLayer
from agents.lib.socialmap.personal_space import PersonalSpace, contour_distance, sigma_for_contour
from agents.lib.socialmap.types import Person

SIDES: tuple[str, ...] = ("front", "rear", "left", "right")
_SIDE_ANGLES: tuple[float, ...] = (0.0, math.pi, math.pi / 2.0, -math.pi / 2.0)


class AdaptiveParams(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)

    enabled: bool = True
    robot_diameter_m: float | None = Field(
        None, gt=0, description="the robot body's diameter (d_r = it + margin_m); None: twice the grid's "
                                "robot_radius_m. A scene's maps give the body's, not the planning radius: "
                                "that one already holds a clearance margin, which counted again left no room "
                                "to adapt in a 1.6 m corridor (issue 43)")
    margin_m: float = Field(0.1, ge=0, description="added to the robot diameter to give d_r")
    d_min_m: float = Field(0.45, ge=0, description="no adaptation when d_s <= d_min")
    d_max_m: float = Field(1.2, gt=0, description="no adaptation when d_s >= d_max")
    zone: str = Field("personal", description="whose contour is moved to d_s: intimate|personal|social")

    @model_validator(mode="after")
    def _order(self) -> AdaptiveParams:
        if self.d_max_m <= self.d_min_m:
            raise ValueError("d_max_m must be greater than d_min_m")
        if self.zone not in ("intimate", "personal", "social"):
            raise ValueError(f"zone must be intimate, personal or social, got {self.zone!r}")
        return self


@dataclass(frozen=True, slots=True)
class Adaptation:
    """What the adaptation did to one person: the new space and, per side, d_i and d_s."""

    space: PersonalSpace
    wall_distance_m: tuple[float, float, float, float]   # front, rear, left, right (inf: no wall)
    adapted: tuple[str, ...]                             # the sides whose sigma was shrunk


def wall_distances(people: Sequence[Person], walls: BaseGeometry | None, max_range_m: float) -> np.ndarray:
    """(n, 4) distances from each person to the first wall ahead, behind, left and right; inf when
    no wall lies within ``max_range_m``."""
    out = np.full((len(people), 4), np.inf)
    if not people or walls is None or walls.is_empty:
        return out
    everyone = np.array([[p.x, p.y] for p in people], dtype=np.float64)
    shapely.prepare(walls)
    # A ray of max_range_m from a person farther than that from every wall meets none: only the
    # others' rays are cast (most of a crowd in the open, at every replan).
    near = np.flatnonzero(shapely.dwithin(walls, shapely.points(everyone), max_range_m * (1 + 1e-9) + 1e-9))
    if not len(near):
        return out
    starts = everyone[near]
    headings = np.array([[people[i].theta + a for a in _SIDE_ANGLES] for i in near.tolist()], dtype=np.float64)
    ends_x = starts[:, :1] + max_range_m * np.cos(headings)
    ends_y = starts[:, 1:] + max_range_m * np.sin(headings)
    coords = np.empty((len(near) * 4, 2, 2))
    coords[:, 0, :] = np.repeat(starts, 4, axis=0)
    coords[:, 1, 0] = ends_x.ravel()
    coords[:, 1, 1] = ends_y.ravel()
    rays = shapely.linestrings(coords)
    hits = shapely.intersection(rays, walls)
    origins = shapely.points(coords[:, 0, :])
    distances = shapely.distance(origins, hits)
    distances = np.where(shapely.is_empty(hits) | np.isnan(distances), np.inf, distances)
    out[near] = distances.reshape(len(near), 4)
    return out


def adapt_space(space: PersonalSpace, distances: Sequence[float], level: float,
                robot_diameter_m: float, params: AdaptiveParams) -> Adaptation:
    """Shrink the sides of ``space`` whose ``level`` contour would leave the robot no room."""
    d_r = robot_diameter_m + params.margin_m
    adapted: list[str] = []
    for side, d_i in zip(SIDES, distances, strict=True):
        d_s = d_i - d_r
        if not params.d_min_m < d_s < params.d_max_m:
            continue
        current = getattr(space, f"{side}_m")
        if contour_distance(current, level) <= d_s:
            continue
        space = space.with_side(side, float(sigma_for_contour(float(d_s), level)))
        adapted.append(side)
    # one distance per side (front, rear, left, right): a 4-tuple that mypy sees as tuple[float, ...]
    return Adaptation(space=space, wall_distance_m=tuple(float(d) for d in distances),  # type: ignore[arg-type]
                      adapted=tuple(adapted))


def occupancy_distances(people: Sequence[Person], occupancy: OccupancyLayer | None, max_range_m: float) -> np.ndarray:
    """Like :func:`wall_distances`, against the wall cells of a building map."""
    out = np.full((len(people), 4), np.inf)
    if occupancy is None:
        return out
    for i, person in enumerate(people):
        out[i] = occupancy.ray_ranges(person.x, person.y, np.asarray(_SIDE_ANGLES) + person.theta, max_range_m)
    return out


def adapt_spaces(people: Sequence[Person], spaces: Sequence[PersonalSpace], walls: BaseGeometry | None,
                 level: float, robot_diameter_m: float, params: AdaptiveParams,
                 occupancy: OccupancyLayer | None = None) -> list[Adaptation]:
    """Adapt every person's space (rays cast in one vectorised shapely call against the polylines,
    and on the grid against a building map's wall cells, ``occupancy``)."""
    if not params.enabled:
        return [Adaptation(space=s, wall_distance_m=(math.inf,) * 4, adapted=()) for s in spaces]
    max_range = robot_diameter_m + params.margin_m + params.d_max_m
    distances = np.minimum(wall_distances(people, walls, max_range), occupancy_distances(people, occupancy, max_range))
    return [adapt_space(space, row, level, robot_diameter_m, params) for space, row in zip(spaces, distances, strict=True)]
