"""Gain tuning of the elastic band (seed section 5.4): cost G = aH + bD + cQ + dP, coordinate descent.

The seed sends the robot to 20 places for each sampled gain, scores every trajectory with G and
alternates between the two gains (one fixed, the other sampled over a range) until no sample
improves. Here the trajectories come from simulating band + controller on small synthetic
scenarios (`default_scenarios`: a corridor with a person, a doorway, an obstacle), so the search
is reproducible and runs in seconds.

Terms of G, per trajectory (our reading of Eqs. 17-20; the seed's Eq. 20 is mislabelled H):
* H (rad): cumulative heading change, the CHC of `metrics` (discrete Eq. 18).
* D (m): distance travelled (Eq. 19).
* Q (s): time to complete the path; a run that fails gets the scenario's time limit.
* P (m): mean over the samples of the distance to the nearest *visible* person (within sensor
  range, line of sight not blocked by an obstacle); samples that see nobody are left out and a run
  that never sees anybody has P = 0 (constant across gains, so it does not move the optimum).
  P rewards keeping away from people, so its weight d is **negative** by default: G is minimised.
* A failed run adds ``failure_penalty``: goal not reached within the time limit, or a collision,
  i.e. the robot's body within ``safety_margin_m`` (default 0.1 m) of an obstacle or person. The
  margin is ours: none of H, D, Q rewards clearance from walls, so without it the search would
  learn to graze them.
G of a gain pair is the sum over the scenarios. Default weights (a, b, c, d) = (1/rad, 1/m,
0.5/s, -1/m) are ours: the seed does not give them.

Search (`coordinate_descent`, generic and tested on a toy cost): each round samples every
coordinate in turn at ``samples`` evenly spaced values of its window with the others fixed, and
moves to the best sample; the first round's window is the whole range, and every later round
halves the windows around the current best point (a zooming grid search, the deterministic
stand-in for the seed's stochastic refinement). It stops when the windows are narrower than
``min_width_fraction`` of the ranges, after ``max_rounds`` rounds or ``max_evaluations`` costs.
Within one round the coordinates are visited in order, so the search can follow a valley that
is not aligned with the axes, one coordinate at a time.

Simulation simplifications: the laser sees every obstacle boundary point within range (no
occlusion; distances beyond the range are capped, which is all the band uses), people are static
discs, the robot is a disc of ``robot_radius_m`` and the controller's command is integrated exactly.
The global paths of the scenarios are drawn by hand (a coarse planner output), so tuning does
not depend on the grid planner.

What to expect: k_c above 125 saturates (see `elastic_band`), so every k_c >= 125 scores the same;
and since only the pass/fail margin rewards clearance, the best k_r is the smallest one that keeps
the margin in every scenario, an optimum at the edge of a constraint. For a robust choice raise
``safety_margin_m`` or add scenarios rather than trust the last digit.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import shapely
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field
from shapely.geometry.base import BaseGeometry

from agents.lib.control.control_law import DEFAULT_CONTROL, BandFollower, ControlParams, Drive, integrate
from agents.lib.control.elastic_band import (
    DEFAULT_PARAMS,
    ElasticBandParams,
    ObstacleField,
    band_from_path,
    step,
)
from agents.lib.metrics.metrics import cumulative_heading_change, distance_travelled

FloatArray = NDArray[np.float64]
GAINS: tuple[str, str] = ("k_c", "k_r")


class TuningError(ValueError):
    """Bad tuning input (bounds, start point, scenario); the message names the key."""


@dataclass(frozen=True)
class Scenario:
    """A synthetic navigation task: static obstacles (walls, furniture) and people seen by the
    laser, a start pose, a goal and the global path a planner would have produced (m, rad, s)."""

    name: str
    obstacles: tuple[BaseGeometry, ...]
    people: tuple[tuple[float, float], ...]
    start: tuple[float, float, float]
    goal: tuple[float, float]
    global_path: tuple[tuple[float, float], ...]
    time_limit_s: float


class SimulationParams(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")

    dt_s: float = Field(0.1, gt=0.0, description="control period")
    band_iterations_per_cycle: int = Field(2, ge=1)
    laser_spacing_m: float = Field(0.05, gt=0.0, description="spacing of simulated range points")
    robot_radius_m: float = Field(0.25, gt=0.0)
    safety_margin_m: float = Field(0.1, ge=0.0, description="closer than this to anything = collision")
    person_radius_m: float = Field(0.2, gt=0.0)
    drive: Drive = "differential"


class CostWeights(BaseModel):
    """Weights of G = aH + bD + cQ + dP (per rad, per m, per s, per m) and the failure penalty."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    a: float = 1.0
    b: float = 1.0
    c: float = 0.5
    d: float = -1.0
    failure_penalty: float = Field(100.0, ge=0.0)


@dataclass(frozen=True)
class SimulatedRun:
    """``collided``: the robot's body came within ``safety_margin_m`` of an obstacle or person
    (the run stops there). ``min_clearance_m``: smallest centre-to-obstacle distance seen."""

    trajectory: FloatArray  # (N, 4): t, x, y, theta
    reached: bool
    collided: bool
    min_clearance_m: float


@dataclass(frozen=True)
class CostTerms:
    H: float
    D: float
    Q: float
    P: float
    failed: bool

    def cost(self, weights: CostWeights) -> float:
        g = weights.a * self.H + weights.b * self.D + weights.c * self.Q + weights.d * self.P
        return g + (weights.failure_penalty if self.failed else 0.0)


@dataclass(frozen=True)
class DescentResult:
    best: dict[str, float]
    best_cost: float
    start: dict[str, float]
    start_cost: float
    evaluations: int
    rounds: int
    history: list[tuple[dict[str, float], float]] = field(repr=False)


@dataclass(frozen=True)
class TuningResult:
    descent: DescentResult
    terms: dict[str, CostTerms]  # per scenario, at the best gains

    @property
    def gains(self) -> dict[str, float]:
        return self.descent.best


def default_scenarios() -> list[Scenario]:
    """Corridor with a person stepping onto the planned path, a doorway approached at an angle
    (the straight line cuts the jamb) and an open room with a box the global path hugs."""
    wall = 0.1
    corridor = Scenario(
        name="corridor_person",
        obstacles=(shapely.box(0.0, 1.2, 10.0, 1.2 + wall), shapely.box(0.0, -1.2 - wall, 10.0, -1.2)),
        people=((5.0, 0.25),),
        start=(0.5, 0.0, 0.0), goal=(9.5, 0.0),
        global_path=((0.5, 0.0), (9.5, 0.0)),
        time_limit_s=40.0,
    )
    doorway = Scenario(
        name="doorway",
        obstacles=(shapely.box(5.0, 0.5, 5.0 + wall, 4.0), shapely.box(5.0, -4.0, 5.0 + wall, -0.5)),
        people=(),
        start=(1.0, -1.0, 0.0), goal=(9.0, 3.0),
        global_path=((1.0, -1.0), (4.3, 0.0), (5.8, 0.0), (9.0, 3.0)),
        time_limit_s=40.0,
    )
    obstacle = Scenario(
        name="obstacle",
        obstacles=(shapely.box(4.5, -0.5, 5.5, 0.5),),
        people=(),
        start=(0.5, 0.2, 0.0), goal=(9.5, 0.2),
        global_path=((0.5, 0.2), (4.2, 0.9), (5.8, 0.9), (9.5, 0.2)),
        time_limit_s=40.0,
    )
    return [corridor, doorway, obstacle]


def simulated_laser_points(scenario: Scenario, sim: SimulationParams) -> FloatArray:
    """Boundary points of every obstacle and person disc, ``laser_spacing_m`` apart (world frame)."""
    discs = [shapely.Point(p).buffer(sim.person_radius_m, quad_segs=16) for p in scenario.people]
    chunks = [np.zeros((0, 2))]
    for geom in (*scenario.obstacles, *discs):
        boundary = shapely.segmentize(geom.boundary, sim.laser_spacing_m)
        chunks.append(shapely.get_coordinates(boundary))
    return np.unique(np.vstack(chunks), axis=0)


def simulate(scenario: Scenario, band_params: ElasticBandParams = DEFAULT_PARAMS,
             control: ControlParams = DEFAULT_CONTROL,
             sim: SimulationParams | None = None) -> SimulatedRun:
    """Drive the robot from the start to the goal with band + controller; stop on arrival,
    collision or time limit."""
    sim = sim or SimulationParams()
    field_ = ObstacleField(simulated_laser_points(scenario, sim), band_params.max_radius_m)
    path = np.vstack([scenario.start[:2], scenario.global_path, scenario.goal])
    band = band_from_path(path, field_, band_params)
    follower = BandFollower(sim.drive, control)
    pose = tuple(float(v) for v in scenario.start)
    rows = [(0.0, *pose)]
    reached = collided = False
    clearance = float(field_.distance(np.asarray([pose[:2]]))[0])
    steps = int(math.ceil(scenario.time_limit_s / sim.dt_s))
    for k in range(1, steps + 1):
        for _ in range(sim.band_iterations_per_cycle):
            band = step(band, field_, pose, band_params)
        out = follower.command(pose, band, sim.dt_s)
        if out.reached:
            reached = True
            break
        pose = integrate(pose, out.command, sim.dt_s)
        rows.append((k * sim.dt_s, *pose))
        clearance = min(clearance, float(field_.distance(np.asarray([pose[:2]]))[0]))
        if clearance < sim.robot_radius_m + sim.safety_margin_m:
            collided = True
            break
    return SimulatedRun(np.asarray(rows, dtype=np.float64), reached, collided, clearance)


def cost_terms(run: SimulatedRun, scenario: Scenario, sensor_range_m: float) -> CostTerms:
    """H, D, Q and P of one simulated run (see the module docstring)."""
    traj = run.trajectory
    failed = run.collided or not run.reached
    q = scenario.time_limit_s if failed else float(traj[-1, 0] - traj[0, 0])
    return CostTerms(H=cumulative_heading_change(traj), D=distance_travelled(traj), Q=q,
                     P=mean_visible_person_distance(traj[:, 1:3], scenario, sensor_range_m),
                     failed=failed)


def mean_visible_person_distance(xy: FloatArray, scenario: Scenario, sensor_range_m: float) -> float:
    """Seed Eq. 20: mean over samples of the distance to the nearest visible person (m)."""
    if not scenario.people:
        return 0.0
    people = np.asarray(scenario.people, dtype=np.float64)
    dist = np.hypot(xy[:, None, 0] - people[None, :, 0], xy[:, None, 1] - people[None, :, 1])
    visible = dist <= sensor_range_m
    if scenario.obstacles:
        walls = shapely.union_all(scenario.obstacles)
        shapely.prepare(walls)
        starts = np.repeat(xy, len(people), axis=0)
        ends = np.tile(people, (len(xy), 1))
        sight = shapely.linestrings(np.stack([starts, ends], axis=1))
        visible &= ~shapely.intersects(walls, sight).reshape(len(xy), len(people))
    nearest = np.where(visible, dist, np.inf).min(axis=1)
    seen = np.isfinite(nearest)
    return float(nearest[seen].mean()) if seen.any() else 0.0


def evaluate_gains(gains: Mapping[str, float], scenarios: Sequence[Scenario],
                   weights: CostWeights | None = None,
                   band_params: ElasticBandParams = DEFAULT_PARAMS,
                   control: ControlParams = DEFAULT_CONTROL,
                   sim: SimulationParams | None = None) -> tuple[float, dict[str, CostTerms]]:
    """G of one gain pair: the sum of the per-scenario trajectory costs, and the terms."""
    weights = weights or CostWeights()
    unknown = set(gains) - set(GAINS)
    if unknown:
        raise TuningError(f"gains: unknown gain(s) {sorted(unknown)}; tunable gains are {list(GAINS)}")
    # model_validate, not model_copy(update=...): a negative gain must be rejected, not simulated.
    params = ElasticBandParams.model_validate({**band_params.model_dump(), **gains})
    terms = {s.name: cost_terms(simulate(s, params, control, sim), s, params.max_radius_m)
             for s in scenarios}
    return float(sum(t.cost(weights) for t in terms.values())), terms


def coordinate_descent(cost: Callable[[dict[str, float]], float], start: Mapping[str, float],
                       bounds: Mapping[str, tuple[float, float]], samples: int = 7,
                       max_rounds: int = 30, shrink: float = 0.5, min_width_fraction: float = 1e-3,
                       max_evaluations: int | None = None) -> DescentResult:
    """Minimise ``cost`` over a box by sampling one coordinate at a time (see module docstring)."""
    _check_descent_input(start, bounds, samples, shrink)
    names = list(bounds)
    x = {k: float(start[k]) for k in names}
    cache: dict[tuple[float, ...], float] = {}
    history: list[tuple[dict[str, float], float]] = []

    def evaluate(point: dict[str, float]) -> float:
        key = tuple(round(point[k], 12) for k in names)
        if key not in cache:
            cache[key] = float(cost(dict(point)))
            history.append((dict(point), cache[key]))
        return cache[key]

    def budget_left() -> bool:
        return max_evaluations is None or len(cache) < max_evaluations

    start_cost = best_cost = evaluate(x)
    widths = {k: bounds[k][1] - bounds[k][0] for k in names}
    rounds = 0
    while rounds < max_rounds and budget_left():
        rounds += 1
        for k in names:
            lo, hi = bounds[k]
            a, b = (lo, hi) if rounds == 1 else (max(lo, x[k] - widths[k] / 2), min(hi, x[k] + widths[k] / 2))
            for value in np.linspace(a, b, samples):
                if not budget_left():
                    break
                trial = {**x, k: float(value)}
                c = evaluate(trial)
                if c < best_cost:
                    best_cost, x = c, trial
        widths = {k: w * shrink for k, w in widths.items()}
        if all(widths[k] < min_width_fraction * (bounds[k][1] - bounds[k][0]) for k in names):
            break
    return DescentResult(best=x, best_cost=best_cost, start={k: float(start[k]) for k in names},
                         start_cost=start_cost, evaluations=len(cache), rounds=rounds, history=history)


def tune_gains(scenarios: Sequence[Scenario] | None = None,
               start: Mapping[str, float] | None = None,
               bounds: Mapping[str, tuple[float, float]] | None = None,
               weights: CostWeights | None = None,
               band_params: ElasticBandParams = DEFAULT_PARAMS,
               control: ControlParams = DEFAULT_CONTROL,
               sim: SimulationParams | None = None,
               samples: int = 5, max_rounds: int = 6,
               max_evaluations: int | None = None) -> TuningResult:
    """Search k_c and k_r minimising G over the scenarios, starting from ``start`` (default: the
    seed's 120/60) within ``bounds`` (default k_c in [0, 250], k_r in [0, 300]). A gain in
    ``start`` but not in ``bounds`` stays fixed at its start value."""
    scenarios = list(scenarios) if scenarios is not None else default_scenarios()
    start = dict(start or {"k_c": band_params.k_c, "k_r": band_params.k_r})
    bounds = dict(bounds or {"k_c": (0.0, 250.0), "k_r": (0.0, 300.0)})
    for argument, keys in (("bounds", bounds), ("start", start)):
        unknown = set(keys) - set(GAINS)
        if unknown:
            raise TuningError(f"{argument}: unknown gain(s) {sorted(unknown)}; "
                              f"tunable gains are {list(GAINS)}")

    terms_seen: dict[tuple[tuple[str, float], ...], dict[str, CostTerms]] = {}

    def g(gains: dict[str, float]) -> float:
        cost, terms = evaluate_gains({**start, **gains}, scenarios, weights, band_params, control, sim)
        terms_seen[tuple(sorted(gains.items()))] = terms
        return cost

    descent = coordinate_descent(g, start, bounds, samples=samples, max_rounds=max_rounds,
                                 max_evaluations=max_evaluations)
    best_terms = terms_seen.get(tuple(sorted(descent.best.items())))
    if best_terms is None:  # only if the best point came from a rounded cache hit
        best_terms = evaluate_gains({**start, **descent.best}, scenarios, weights, band_params,
                                    control, sim)[1]
    return TuningResult(descent, best_terms)


def _check_descent_input(start: Mapping[str, float], bounds: Mapping[str, tuple[float, float]],
                         samples: int, shrink: float) -> None:
    if not bounds:
        raise TuningError("bounds: nothing to search")
    for k, (lo, hi) in bounds.items():
        if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
            raise TuningError(f"bounds[{k!r}]: need finite lo < hi, got ({lo}, {hi})")
        if k not in start:
            raise TuningError(f"start: missing {k!r}")
        if not lo <= start[k] <= hi:
            raise TuningError(f"start[{k!r}] = {start[k]} is outside its bounds ({lo}, {hi})")
    if samples < 2:
        raise TuningError(f"samples: need at least 2 per coordinate, got {samples}")
    if not 0.0 < shrink < 1.0:
        raise TuningError(f"shrink: must be in (0, 1), got {shrink}")
