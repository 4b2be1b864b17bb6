"""Elastic band local planner: the global path as a chain of bubbles deformed by range data.

Seed section 5.3 (after Quinlan & Khatib): each band point carries a bubble whose radius is the
distance to the nearest obstacle seen by the range sensor; points are inserted or removed to keep
the spacing near half the robot length; an internal contraction force (Eq. 13) straightens the
band and an external repulsion force (Eqs. 14-15, discrete Jacobian of the distance field) pushes
it away from obstacles; every point then moves by their sum (Eq. 16). The first point follows
the robot and the last point (the goal) is fixed.

Units and scaling of the gains. Eq. 16 adds the forces directly to positions, so they must be
displacements; the seed gives the optimised gains k_c = 120 and k_r = 60 without units (its
RoboComp code works in millimetres). Here the displacement of one iteration is

    f_c = k_c * g * (u_prev + u_next)                 [m]   (Eq. 13)
    f_r = k_r * g * (D0 - D) * grad D   if D < D0     [m]   (Eq. 15)

with the gain unit ``g = gain_unit_fraction * robot_length_m`` (default 1/1000 of the robot
length). So **k_c is in thousandths of the robot length per iteration** (per unit of the Eq. 13
vector sum, which is at most 2) and **k_r is in thousandths of the robot length per iteration
per metre of intrusion inside D0** (|grad D| is 1 away from ridges). For a 1 m robot these are
the seed's millimetres. Why relative to the robot: the spacing is half the robot length, and a
unit-vector contraction moves a point the fraction ``2 k_c g / spacing = k_c / 250`` of the way to
the midpoint of its neighbours, whatever the robot size. The band relaxes without overshoot up
to k_c = 125 (half way, the critically damped step) and oscillates above it; the seed's tuned
k_c = 120 sits just under that limit. With the defaults (0.5 m robot) k_c = 120 moves a kink by
up to 0.12 m per iteration and k_r = 60 moves a point 0.5 m inside D0 by 0.015 m.

Readings of the seed (documented choices, not in its text):
* Eq. 14 as printed, ``(D(p - d) - D(p + d)) / 2d``, is **minus** the gradient; added as in
  Eq. 16 it would pull the band into obstacles. The RoboComp band it builds on subtracts the change
  vector; we use ``grad D`` so that f_r always pushes away from obstacles.
* Stability. Above k_c = 125 the contraction would overshoot the chord of the neighbours and
  zigzag (and diverge above 250), so its step is capped at ``contraction_limit`` (default 0.5)
  times the point's distance to the line through its neighbours: larger k_c saturate instead
  of oscillating. The total step of a point is also capped at ``max_step_m``. At the defaults,
  with evenly spaced points, neither cap is active.
* Spacing hysteresis: a new point is inserted when a gap exceeds ``spacing_m`` (half the robot
  length) and a point is removed (combined with its predecessor) when a gap falls under
  ``spacing_m / 2``; one threshold for both, as the seed's text reads, would insert and remove
  the same point forever.
* Range data are laser points already in the world frame; obstacles beyond ``max_radius_m`` (the
  sensor range) are not seen, and a point that sees nothing gets the fallback radius
  ``max_radius_m``. Occlusion is the caller's business (pass what the sensor returned).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray
from pydantic import BaseModel, ConfigDict, Field, model_validator
from scipy.spatial import cKDTree

from agents.lib.planning.paths import split_gaps
from scenes.geometry import project_on_segments

FloatArray = NDArray[np.float64]


class BandInputError(ValueError):
    """Bad input to the elastic band (path, range data or pose); the message names the argument."""


class ElasticBandParams(BaseModel):
    """Configuration of the band. Lengths in metres; see the module docstring for the gain units."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    k_c: float = Field(120.0, ge=0.0,
                       description="contraction gain, robot lengths/1000 per iteration (seed: 120)")
    k_r: float = Field(60.0, ge=0.0,
                       description="repulsion gain, robot lengths/1000 per iteration per m inside D0 "
                                   "(seed: 60)")
    gain_unit_fraction: float = Field(1e-3, gt=0.0, description="gain unit as a fraction of the robot length")
    robot_length_m: float = Field(0.5, gt=0.0, description="robot length; the spacing is half of it")
    influence_distance_m: float = Field(1.0, gt=0.0, description="D0 of Eq. 15")
    jacobian_delta_m: float = Field(0.02, gt=0.0, description="delta of Eq. 14")
    max_radius_m: float = Field(4.0, gt=0.0, description="sensor range and fallback bubble radius")
    contraction_limit: float = Field(0.5, gt=0.0, le=1.0,
                                     description="max contraction step / distance to the neighbours' chord")
    max_step_m: float = Field(0.1, gt=0.0, description="max displacement of a point per iteration")
    tolerance_m: float = Field(1e-3, gt=0.0, description="relax() stops when no point moves more")
    max_iterations: int = Field(200, ge=1, description="relax() iteration limit")

    @model_validator(mode="after")
    def _influence_within_range(self) -> ElasticBandParams:
        if self.influence_distance_m > self.max_radius_m:
            raise ValueError(f"influence_distance_m ({self.influence_distance_m}) must not exceed "
                             f"max_radius_m ({self.max_radius_m}): the sensor cannot see that far")
        return self

    @property
    def gain_unit_m(self) -> float:
        """Metres of displacement per unit of gain (g in the module docstring)."""
        return self.gain_unit_fraction * self.robot_length_m

    @property
    def spacing_m(self) -> float:
        """Largest gap between consecutive points: half the robot length (seed 5.3)."""
        return self.robot_length_m / 2.0

    @property
    def min_spacing_m(self) -> float:
        """Smallest gap before two points are combined."""
        return self.spacing_m / 2.0


DEFAULT_PARAMS = ElasticBandParams()


@dataclass(frozen=True)
class ElasticBand:
    """An immutable band: points (N, 2) in the world frame, first = robot side, last = goal, and
    the bubble radius of each point (distance to the nearest seen obstacle, m)."""

    points: FloatArray
    radii: FloatArray

    def __post_init__(self) -> None:
        points = np.array(self.points, dtype=np.float64)
        radii = np.array(self.radii, dtype=np.float64)
        if points.ndim != 2 or points.shape[1] != 2 or len(points) < 2:
            raise BandInputError(f"band points: expected shape (N >= 2, 2), got {points.shape}")
        if radii.shape != (len(points),):
            raise BandInputError(f"band radii: expected shape ({len(points)},), got {radii.shape}")
        if not (np.all(np.isfinite(points)) and np.all(np.isfinite(radii))):
            raise BandInputError("band points/radii: must be finite")
        points.setflags(write=False)
        radii.setflags(write=False)
        object.__setattr__(self, "points", points)
        object.__setattr__(self, "radii", radii)

    def __len__(self) -> int:
        return len(self.points)

    @property
    def goal(self) -> FloatArray:
        return self.points[-1]

    @property
    def length_m(self) -> float:
        return float(np.hypot(*np.diff(self.points, axis=0).T).sum())


@dataclass(frozen=True)
class BandForces:
    """Per-point displacements of one iteration (m), for inspection and drawing (seed Fig. 12)."""

    contraction: FloatArray
    repulsion: FloatArray


@dataclass(frozen=True)
class RelaxResult:
    band: ElasticBand
    iterations: int
    converged: bool
    max_displacement_m: float


@dataclass(frozen=True)
class ObstacleField:
    """Nearest-obstacle distance D(x, y) over a set of range points, capped at the sensor range.

    Build it once per scan and pass it to `step` / `relax` instead of the raw array to avoid
    rebuilding the KD-tree on every call; its own ``max_range_m`` then applies."""

    points: FloatArray
    max_range_m: float
    _tree: cKDTree | None = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if not self.max_range_m > 0.0:
            raise BandInputError(f"max_range_m: must be > 0, got {self.max_range_m}")
        pts = _as_xy(self.points, "obstacles_xy", allow_empty=True)
        object.__setattr__(self, "points", pts)
        object.__setattr__(self, "_tree", cKDTree(pts) if len(pts) else None)

    def distance(self, xy: FloatArray) -> FloatArray:
        """D at each row of ``xy``: distance to the nearest obstacle point, or max_range_m."""
        if self._tree is None:
            return np.full(len(xy), self.max_range_m)
        dist, _ = self._tree.query(xy, k=1, distance_upper_bound=self.max_range_m)
        return np.minimum(dist, self.max_range_m)


Obstacles = ArrayLike | ObstacleField


def obstacle_field(obstacles: Obstacles, params: ElasticBandParams = DEFAULT_PARAMS) -> ObstacleField:
    """Wrap raw laser points (M, 2) in an ObstacleField (returned unchanged if it already is one)."""
    if isinstance(obstacles, ObstacleField):
        return obstacles
    return ObstacleField(_as_xy(obstacles, "obstacles_xy", allow_empty=True), params.max_radius_m)


def band_from_path(path_xy: ArrayLike, obstacles: Obstacles = (),
                   params: ElasticBandParams = DEFAULT_PARAMS) -> ElasticBand:
    """Start a band from a global path (N >= 2 waypoints, m): resampled to the band spacing."""
    path = _as_xy(path_xy, "path_xy")
    if len(path) < 2:
        raise BandInputError(f"path_xy: need at least 2 waypoints, got {len(path)}")
    field_ = obstacle_field(obstacles, params)
    points = resample(path, params.spacing_m, params.min_spacing_m)
    return ElasticBand(points, field_.distance(points))


def step(band: ElasticBand, obstacles: Obstacles, robot_pose: ArrayLike | None = None,
         params: ElasticBandParams = DEFAULT_PARAMS) -> ElasticBand:
    """One band update: follow the robot, keep the spacing, apply Eqs. 13-16 once.

    ``robot_pose`` (x, y[, theta]): the part of the band the robot has already passed is cut off
    and the first point is moved onto the robot. ``None`` keeps the first point where it is.
    """
    new_band, _ = _iterate(band, obstacle_field(obstacles, params), robot_pose, params)
    return new_band


def relax(band: ElasticBand, obstacles: Obstacles, params: ElasticBandParams = DEFAULT_PARAMS,
          max_iterations: int | None = None) -> RelaxResult:
    """Iterate `step` (robot fixed) until no point moves more than ``tolerance_m`` and the point
    count is stable, or until the iteration limit; says which happened."""
    field_ = obstacle_field(obstacles, params)
    limit = params.max_iterations if max_iterations is None else max_iterations
    moved = float("inf")
    for iteration in range(1, limit + 1):
        previous_count = len(band)
        band, moved = _iterate(band, field_, None, params)
        if moved < params.tolerance_m and len(band) == previous_count:
            return RelaxResult(band, iteration, True, moved)
    return RelaxResult(band, limit, False, moved)


def forces(band: ElasticBand, obstacles: Obstacles,
           params: ElasticBandParams = DEFAULT_PARAMS) -> BandForces:
    """The raw Eq. 13 and Eq. 15 displacements of every point (endpoints get zero), before the
    stability caps."""
    field_ = obstacle_field(obstacles, params)
    return BandForces(contraction_forces(band.points, params), repulsion_forces(band.points, field_, params))


def contraction_forces(points: FloatArray, params: ElasticBandParams = DEFAULT_PARAMS) -> FloatArray:
    """Eq. 13: k_c * (unit vector to the previous point + unit vector to the next point), in m."""
    out = np.zeros_like(points)
    if len(points) < 3:
        return out
    to_prev = points[:-2] - points[1:-1]
    to_next = points[2:] - points[1:-1]
    out[1:-1] = _unit(to_prev) + _unit(to_next)
    return out * (params.k_c * params.gain_unit_m)


def distance_gradient(points: FloatArray, field_: ObstacleField, delta_m: float) -> FloatArray:
    """Central-difference gradient of D (Eq. 14, with the sign that points away from obstacles)."""
    return _distance_and_gradient(points, field_, delta_m)[1]


def repulsion_forces(points: FloatArray, field_: ObstacleField,
                     params: ElasticBandParams = DEFAULT_PARAMS) -> FloatArray:
    """Eq. 15: k_r * (D0 - D) * grad D for interior points closer than D0 to an obstacle, in m."""
    out = np.zeros_like(points)
    if len(points) < 3:
        return out
    distance, grad = _distance_and_gradient(points[1:-1], field_, params.jacobian_delta_m)
    depth = np.maximum(params.influence_distance_m - distance, 0.0)
    out[1:-1] = grad * depth[:, None] * (params.k_r * params.gain_unit_m)
    return out


def _distance_and_gradient(points: FloatArray, field_: ObstacleField,
                           delta_m: float) -> tuple[FloatArray, FloatArray]:
    """D at the points and its central-difference gradient, from one batched nearest-point query."""
    offsets = np.array([[0.0, 0.0], [delta_m, 0.0], [-delta_m, 0.0], [0.0, delta_m], [0.0, -delta_m]])
    probes = (points[:, None, :] + offsets[None, :, :]).reshape(-1, 2)
    d = field_.distance(probes).reshape(len(points), 5)
    grad = np.column_stack([d[:, 1] - d[:, 2], d[:, 3] - d[:, 4]]) / (2.0 * delta_m)
    return d[:, 0], grad


def resample(points: FloatArray, spacing_m: float, min_spacing_m: float) -> FloatArray:
    """Keep gaps in [min_spacing_m, spacing_m]: drop interior points closer than min_spacing_m to
    the previous kept one, then split every gap longer than spacing_m evenly. Endpoints stay."""
    gaps = np.hypot(*np.diff(points, axis=0).T)
    if len(points) > 2 and np.any(gaps < min_spacing_m):
        points = _drop_close_points(points, min_spacing_m)
        gaps = np.hypot(*np.diff(points, axis=0).T)
    return split_gaps(points, np.maximum(np.ceil(gaps / spacing_m - 1e-9), 1).astype(np.int64))



def _drop_close_points(points: FloatArray, min_spacing_m: float) -> FloatArray:
    """Greedy: keep an interior point only if it is min_spacing_m from the last kept one (the
    dropped point is combined into its predecessor); the endpoints always stay."""
    kept = [points[0]]
    for p in points[1:-1]:
        if np.hypot(*(p - kept[-1])) >= min_spacing_m:
            kept.append(p)
    while len(kept) > 1 and np.hypot(*(points[-1] - kept[-1])) < min_spacing_m:
        kept.pop()
    kept.append(points[-1])
    return np.asarray(kept, dtype=np.float64)


def is_connected(band: ElasticBand, clearance_m: float = 0.0) -> bool:
    """True when every bubble shrunk by ``clearance_m`` (e.g. the robot radius) is non-empty and
    consecutive bubbles overlap: the band is then a free corridor (Quinlan & Khatib)."""
    free = band.radii - clearance_m
    gaps = np.hypot(*np.diff(band.points, axis=0).T)
    return bool(np.all(free > 0.0) and np.all(free[:-1] + free[1:] > gaps))


def _iterate(band: ElasticBand, field_: ObstacleField, robot_pose: ArrayLike | None,
             params: ElasticBandParams) -> tuple[ElasticBand, float]:
    points = band.points
    if robot_pose is not None:
        points = _cut_behind(points, _robot_xy(robot_pose), params.spacing_m)
    points = resample(points, params.spacing_m, params.min_spacing_m)
    displacement = _limited_contraction(points, params) + repulsion_forces(points, field_, params)
    norms = np.hypot(*displacement.T)
    too_long = norms > params.max_step_m
    displacement[too_long] *= (params.max_step_m / norms[too_long])[:, None]
    new_points = points + displacement
    moved = min(float(norms.max(initial=0.0)), params.max_step_m)
    return ElasticBand(new_points, field_.distance(new_points)), moved


def _limited_contraction(points: FloatArray, params: ElasticBandParams) -> FloatArray:
    """Eq. 13 with each step capped at ``contraction_limit`` times the point's distance to the
    line through its neighbours, so that no point is thrown past that chord (no zigzag)."""
    f_c = contraction_forces(points, params)
    if len(points) < 3:
        return f_c
    chord = points[2:] - points[:-2]
    rel = points[1:-1] - points[:-2]
    chord_len = np.hypot(*chord.T)
    cross = np.abs(chord[:, 0] * rel[:, 1] - chord[:, 1] * rel[:, 0])
    to_chord = np.where(chord_len > 1e-12, cross / np.maximum(chord_len, 1e-12), np.hypot(*rel.T))
    cap = params.contraction_limit * to_chord
    norm = np.hypot(*f_c[1:-1].T)
    over = norm > cap
    scale = np.ones_like(norm)
    scale[over] = cap[over] / norm[over]
    f_c[1:-1] *= scale[:, None]
    return f_c


def _cut_behind(points: FloatArray, robot: FloatArray, slack_m: float) -> FloatArray:
    """Replace the part of the band up to the robot's projection on it by the robot position.

    Only the stretch the robot can have covered since the last update is searched (arc length up
    to twice its distance from the first point, plus ``slack_m``), so that a band that comes back
    near the robot later (a U-turn) is not short-circuited."""
    a, b = points[:-1], points[1:]
    seg = b - a
    seg_len = np.hypot(*seg.T)
    arc_start = np.concatenate([[0.0], np.cumsum(seg_len)[:-1]])
    reach = 2.0 * float(np.hypot(*(robot - points[0]))) + slack_m
    n = max(1, int(np.count_nonzero(arc_start <= reach)))
    k = int(np.argmin(project_on_segments(robot, a[:n], b[:n]).distance))
    return np.vstack([robot, points[k + 1:]])


def _robot_xy(robot_pose: ArrayLike) -> FloatArray:
    pose = np.asarray(robot_pose, dtype=np.float64).ravel()
    if pose.size not in (2, 3) or not np.all(np.isfinite(pose)):
        raise BandInputError(f"robot_pose: expected finite (x, y[, theta]), got {pose.tolist()}")
    return pose[:2]


def _as_xy(values: ArrayLike, argument: str, allow_empty: bool = False) -> FloatArray:
    try:
        xy = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise BandInputError(f"{argument}: not numeric ({exc})") from exc
    if xy.size == 0 and allow_empty:
        return np.zeros((0, 2))
    if xy.ndim != 2 or xy.shape[1] != 2:
        raise BandInputError(f"{argument}: expected shape (N, 2), got {xy.shape}")
    bad = np.flatnonzero(~np.isfinite(xy).all(axis=1))
    if bad.size:
        raise BandInputError(f"{argument}: row {int(bad[0])} is not finite: {xy[bad[0]].tolist()}")
    return xy


def _unit(vectors: FloatArray) -> FloatArray:
    norms = np.hypot(*vectors.T)
    return vectors / np.maximum(norms, 1e-12)[:, None]
