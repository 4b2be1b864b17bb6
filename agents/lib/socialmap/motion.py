"""Moving people on the social map: a personal space stretched along the velocity, and where they
will be over the next seconds.

**Stretch.**  Kirby's velocity-dependent asymmetric Gaussian (R. Kirby, "Social Robot Navigation",
PhD thesis, Carnegie Mellon University, 2010, ch. 6; also Kirby, Simmons and Forlizzi, "COMPANION",
RO-MAN 2009) orients a walking person's Gaussian along their direction of motion and sets its
front deviation to ``sigma_h = max(2 v, 0.5)`` m (v in m/s: the space reaches about two seconds of
walking ahead), the sides to 2/3 and the rear to 1/2 of it.  Our resting space (personal_space.py)
is exactly Kirby's at v <= 0.5 m/s: front 1.0, sides 0.67, rear 0.5 m.  We stretch the front only:
scaling the sides with speed as Kirby does makes a resident walking at 1 m/s 2.7 m wide at the
intimate level, wider than the centre's 2.4 m corridors, so the robot could never pass anyone
there; passing beside a walker is what people do too.  The front uses the role's scale like the
rest of the space: ``front = max(rest front, FRONT_GAIN_S x speed x scale)``.

**Prediction.**  A walking person (``moving_mps`` or faster) is predicted every ``step_s`` up to
``horizon_s`` (0.4 s and 4.8 s: the trajectory-prediction benchmark's question, docs/prediction.md):
at constant velocity, walkers slower than ``slowing_mps`` slowing to a stop (speed decaying with
``slowing_tau_s``); or - when the DSR says they are on their way to an activity's object
(``Person.destination``, through the doors ``Person.via``) and they walk within
``destination_cone_deg`` of the way there - along that way at their current speed, stopping at the
object's interaction range.  A prediction never passes a wall (it stops there).  Measured on real
pedestrians and simulated days with ``chronav predict evaluate`` (docs/prediction.md).  Each
predicted position adds the person's resting Gaussian scaled by a weight that falls linearly with
the prediction time, from ``weight`` at ``step_s`` to 0 past the horizon.  ``weight`` stays below
the intimate level, so predictions make the robot prefer to pass behind a walker (personal and
social costs) but never forbid a cell: the robot is not blocked by a future that may not happen.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
import shapely
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field
from shapely.geometry.base import BaseGeometry

from agents.lib.socialmap.grid import COST_DTYPE, CostPatch, GridSpec
from agents.lib.socialmap.personal_space import PersonalSpace, support_radius
from agents.lib.socialmap.types import Person
from agents.lib.socialmap.zones import ZoneParams

ARRIVED_RANGE_M = 1.8     # a participant this close to the activity's object has arrived (interactions.py)
WALL_CLEARANCE_M = 0.45   # a prediction stops this short of a wall: people keep about this much (crowd/routes.py)


class MotionParams(BaseModel):
    """How walking people shape the map (defaults: module doc)."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    # The tracker decides who stands for its detector's noise (tracking.still_threshold: 0.1 m/s at
    # the observer's 2 cm); here only HuNavSim's "not moving" threshold, so that the slow walkers a
    # perfect detector reports (UCY's drifting people) are predicted where they drift.
    moving_mps: float = Field(0.01, ge=0, description="slower than this a person counts as standing")
    front_gain_s: float = Field(2.0, ge=0, description="Kirby: front sigma = max(2 v, rest)")
    horizon_s: float = Field(4.8, ge=0, description="how far ahead people are predicted")
    step_s: float = Field(0.4, gt=0, description="time between predicted positions")
    weight: float = Field(0.6, ge=0, lt=1, description="peak density of the first prediction (< intimate)")
    slowing_mps: float = Field(0.5, ge=0, description="walkers slower than this are coming to a stop")
    # 8 s: without detection noise, 4 s made UCY's slow walkers 0.3 % worse than constant velocity
    # (docs/prediction.md); with the observer's noise 8 s costs 0.1 %
    slowing_tau_s: float = Field(8.0, ge=0, description="time constant of their speed's decay")
    destination_cone_deg: float = Field(60.0, ge=0, le=180,
                                        description="follow the activity's object only when walking within this of it")


def speed(person: Person) -> float:
    return math.hypot(person.vx, person.vy)


def oriented(person: Person, params: MotionParams) -> Person:
    """A walking person's space points where they walk, not where they look."""
    if speed(person) < params.moving_mps:
        return person
    return replace(person, theta=math.atan2(person.vy, person.vx))


def stretched(space: PersonalSpace, person: Person, scale: float, params: MotionParams) -> PersonalSpace:
    """Kirby's front stretch (module doc); a standing person keeps their resting space."""
    v = speed(person)
    if v < params.moving_mps:
        return space
    return space.with_side("front", max(space.front_m, params.front_gain_s * v * scale))


@dataclass(frozen=True, slots=True)
class Prediction:
    """One person's predicted positions (``times`` s from now) and their weights."""

    name: str
    times: NDArray[np.float64]
    points: NDArray[np.float64]    # (T, 2)
    weights: NDArray[np.float64]


def predict(person: Person, params: MotionParams, walls: BaseGeometry | None) -> Prediction | None:
    """Where a walking person will be (module doc); None for a standing one."""
    return predict_many([person], params, walls)[0]


def predict_many(people: Sequence[Person], params: MotionParams,
                 walls: BaseGeometry | None) -> list[Prediction | None]:
    """``predict`` for many people at once (one numpy pass, one vectorised wall test): an observer
    cycle predicts everyone it tracks, and per-person numpy and shapely calls cost more than the
    arithmetic."""
    out: list[Prediction | None] = [None] * len(people)
    if not people or params.horizon_s <= 0:
        return out
    times = np.arange(params.step_s, params.horizon_s + 1e-9, params.step_s)
    if len(times) == 0:
        return out
    xy = np.array([(p.x, p.y) for p in people], dtype=np.float64)
    velocity = np.array([(p.vx, p.vy) for p in people], dtype=np.float64)
    speeds = np.hypot(velocity[:, 0], velocity[:, 1])
    walking = np.flatnonzero(speeds >= max(params.moving_mps, 1e-9))
    if len(walking) == 0:
        return out
    direction = velocity[walking] / speeds[walking, None]
    reach = speeds[walking, None] * times[None, :]                                   # (W, T)
    slow = speeds[walking] < params.slowing_mps
    if slow.any() and params.slowing_tau_s > 0:
        # Slow walkers come to a stop: speed v exp(-t / tau), so they cover v tau (1 - exp(-t / tau)).
        tau = params.slowing_tau_s
        reach[slow] = speeds[walking][slow, None] * tau * (1.0 - np.exp(-times[None, :] / tau))
    routes: dict[int, NDArray[np.float64]] = {}
    for row, i in enumerate(walking.tolist()):
        route = route_for(people[i], direction[row], params)
        if route is not None:
            routes[row], limit = route
            reach[row] = np.minimum(reach[row], limit)
            continue
        heading = heading_for(people[i], direction[row], params)
        if heading is not None and not _blocked(people[i], heading, walls):
            direction[row], limit = heading
            reach[row] = np.minimum(reach[row], limit)
    points = xy[walking, None, :] + reach[:, :, None] * direction[:, None, :]         # (W, T, 2)
    for row, polyline in routes.items():
        points[row] = along(polyline, reach[row])
    keep = np.ones(reach.shape, dtype=bool)
    if walls is not None and not walls.is_empty:
        paths = shapely.linestrings(np.stack([xy[walking], points[:, -1]], axis=1))
        for row, polyline in routes.items():
            paths[row] = shapely.LineString(polyline)
        for row in np.flatnonzero(shapely.intersects(paths, walls)).tolist():
            path = paths[row]
            hit = path.intersection(walls)
            crossings = [shapely.Point(c) for part in getattr(hit, "geoms", [hit]) for c in part.coords]
            blocked = min(path.project(point) for point in crossings)
            keep[row] = reach[row] < max(0.0, blocked - WALL_CLEARANCE_M)
    weights = params.weight * (1.0 - times / (params.horizon_s + params.step_s))
    for row, i in enumerate(walking.tolist()):
        if keep[row].any():
            mask = keep[row]
            out[i] = Prediction(people[i].name, times[mask], points[row][mask], weights[mask])
    return out


def route_for(person: Person, direction: NDArray[np.float64],
              params: MotionParams) -> tuple[NDArray[np.float64], float] | None:
    """The polyline through the doors ``via`` to the person's destination, and how far along it they
    go (to the object's interaction range), when they walk within ``destination_cone_deg`` of its
    next leg (a door they are passing, within 0.5 m, counts as passed); else None."""
    if person.destination is None or not person.via:
        return None
    here = np.array([person.x, person.y])
    vertices = np.array([here, *person.via, person.destination], dtype=np.float64)
    legs = np.diff(vertices, axis=0)
    lengths = np.hypot(legs[:, 0], legs[:, 1])
    total = float(lengths.sum())
    if total <= ARRIVED_RANGE_M:
        return None
    first = 1 if lengths[0] < 0.5 and len(legs) > 1 else 0
    if lengths[first] <= 0 or float(legs[first] @ direction) < lengths[first] * math.cos(
            math.radians(params.destination_cone_deg)):
        return None
    return vertices, total - ARRIVED_RANGE_M + 0.5


def along(vertices: NDArray[np.float64], distances: NDArray[np.float64]) -> NDArray[np.float64]:
    """Points at arc lengths ``distances`` along a polyline (its end beyond its length)."""
    legs = np.diff(vertices, axis=0)
    cumulative = np.concatenate([[0.0], np.cumsum(np.hypot(legs[:, 0], legs[:, 1]))])
    return np.stack([np.interp(distances, cumulative, vertices[:, 0]),
                     np.interp(distances, cumulative, vertices[:, 1])], axis=1)


def _blocked(person: Person, heading: tuple[NDArray[np.float64], float], walls: BaseGeometry | None) -> bool:
    """Whether a wall stands between the person and where the line to their destination ends:
    then they walk round it through a door, which their own heading shows better than the line."""
    if walls is None or walls.is_empty:
        return False
    toward, limit = heading
    end = (person.x + toward[0] * limit, person.y + toward[1] * limit)
    return bool(shapely.intersects(shapely.LineString([(person.x, person.y), end]), walls))


def heading_for(person: Person, direction: NDArray[np.float64],
                params: MotionParams) -> tuple[NDArray[np.float64], float] | None:
    """The straight line to the person's destination (the DSR's activity object) and how far along
    it they go (to its interaction range), or None to keep their own velocity: when they have none,
    have arrived, or walk elsewhere - more than ``destination_cone_deg`` off the line to it.

    A wall on that line (the object is in another room) keeps their own heading too (``_blocked``):
    they are on their way to a door.

    Why the cone: the DSR names an activity's object as soon as it is upcoming (45 minutes ahead);
    a resident wandering in the meantime is not walking there yet, and bending her prediction
    toward the object pointed it behind her (center_day, res_dora at 09:30:06:
    tests/unit/test_prediction.py)."""
    if person.destination is None:
        return None
    dx, dy = person.destination[0] - person.x, person.destination[1] - person.y
    distance = math.hypot(dx, dy)
    if distance <= ARRIVED_RANGE_M:
        return None
    toward = np.array([dx, dy]) / distance
    if float(toward @ direction) < math.cos(math.radians(params.destination_cone_deg)):
        return None
    return toward, distance - ARRIVED_RANGE_M + 0.5


def prediction_patches(spec: GridSpec, predictions: Sequence[tuple[Prediction, PersonalSpace, float]],
                       zones: ZoneParams, social_cost: float, personal_cost: float) -> list[CostPatch]:
    """Cost patches of the predicted positions: each the resting Gaussian (facing the motion)
    times its weight, banded like the zones (never intimate: weights stay below its level)."""
    from agents.lib.socialmap.banded import banded_gaussians    # numba: only when someone walks

    table = np.array([0.0, social_cost, personal_cost, math.inf], dtype=COST_DTYPE)
    levels = np.array([zones.social, zones.personal, zones.intimate])
    patches = []
    for prediction, space, theta in predictions:
        windows, centres = [], []
        for (x, y), w in zip(prediction.points.tolist(), prediction.weights.tolist(), strict=True):
            if w <= zones.social:
                continue
            radius = support_radius(space, zones.social / w) + spec.resolution
            window = spec.window(x - radius, y - radius, x + radius, y + radius)
            if window is None:
                continue
            rows, cols = window
            windows.append(window)
            centres.append((x, y, w, spec.xs(cols), spec.ys(rows)))
        for (rows, cols), values in zip(windows, banded_gaussians(space, theta, centres, levels, table), strict=True):
            patches.append(CostPatch(rows, cols, values))
    return patches
