"""The metrics among moving people: how the robot moved among people who move, from both trajectories.

Two sets of definitions (``chronav metrics --definitions``):

* ``published`` (default, ``dynamic_metrics``): the definitions as the papers give them, each metric's
  name, unit, source and one-line definition in metric_catalog.py and docs/metrics.md.  Distances are
  between body edges (centre distance minus the robot's and the person's radii) clipped at 0, the
  social force is lightsfm's (Moussaid et al. 2009 as implemented in lightsfm, HuNavSim's
  parameters), |w| decides whether the robot turns, groups are taken afresh at every sample and have
  two or more members, and a contact is one collision however many samples it lasts.
* ``hunav`` (``hunav_metrics``): HuNavSim's evaluator (robotics-upo/hunav_sim,
  hunav_evaluator/hunav_metrics.py and sfm.py, ROS 2 humble) reproduced on chronav's samples,
  quirks included, keyed by HuNavSim's own metric names, so a chronav run can be set beside
  HuNavSim results.  The quirks are listed in docs/metrics.md.

A sample is one robot sample (trajectory.csv) with every person's position and velocity at the same
time (people.csv, interpolated when the times differ).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import shapely
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict
from shapely.geometry.base import BaseGeometry

from agents.lib.socialmap.motion import MotionParams, oriented, stretched
from agents.lib.socialmap.personal_space import PersonalSpace, PersonalSpaceParams, asymmetric_gaussian
from agents.lib.socialmap.roles import RoleParams
from agents.lib.socialmap.types import Person
from scenes.angles import wrap_angle

PERSON_RADIUS_M = 0.25
NO_TRACKS = "no people: no people.csv (--people) or nobody in it"
NOBODY_THERE = "no people: nobody in people.csv was there at the trajectory's times"
BANDS: tuple[tuple[str, float, float], ...] = (("intimate", -math.inf, 0.45), ("personal", 0.45, 1.2),
                                               ("social", 1.2, 3.6))
GROUP_GAZE_M = 1.5
CONTACT_M = 0.02
STILL_MPS, STILL_RADPS = 0.01, 0.02     # HuNavSim's thresholds for 'not moving'
HUNAV_RADIUS_M = 0.35      # HuNavSim's default robot and agent radius
GOAL_RADIUS_M = 0.1        # the controller's goal tolerance (control.py)
GOAL_SLACK_M = 0.05        # HuNavSim's goal_reached: distance - goal radius < 0.05 m
GAP_FACTOR = 5.0            # an interval this many times the median sampling is a gap between missions
# HuNavSim's social force model (hunav_evaluator/sfm.py)
SF_FACTOR, SF_LAMBDA, SF_GAMMA, SF_N, SF_N_PRIME = 2.1, 2.0, 0.35, 2.0, 3.0
OBSTACLE_FACTOR, OBSTACLE_SIGMA_M = 10.0, 0.2


@dataclass(frozen=True)
class PeopleTracks:
    """People's trajectories: ``times`` (T,), ``names`` (N,), and (T, N) arrays of x, y, theta, vx,
    vy and group labels ("" outside any group); NaN where a person was not recorded."""

    times: NDArray[np.float64]
    names: tuple[str, ...]
    x: NDArray[np.float64]
    y: NDArray[np.float64]
    theta: NDArray[np.float64]
    vx: NDArray[np.float64]
    vy: NDArray[np.float64]
    groups: NDArray[np.object_]
    roles: tuple[str, ...] = ()         # per name ("" unknown: a resident's space)

    @property
    def present(self) -> NDArray[np.bool_]:
        """(T, N): who is there at each time (a person is absent where people.csv has no row of them)."""
        return np.isfinite(self.x)

    def at(self, times: NDArray[np.float64]) -> PeopleTracks:
        """The tracks at ``times``: interpolated linearly between two samples (headings along the
        shorter turn), groups from the earlier sample.  A person is at a time only if present at the
        samples on both sides of it (or at the sample itself): absent (NaN, group "") before they
        arrive, after they leave and beyond the recorded span.

        Why not hold them at their last place: a replayed person who has left the plaza, or has not
        entered it yet, is nowhere, and metrics that counted them there measured ghosts."""
        times = np.asarray(times, dtype=np.float64)
        if len(self.times) == len(times) and np.array_equal(self.times, times):
            return self
        shape = (len(times), len(self.names))
        if len(self.times) == 0 or not self.names:
            nan = np.full(shape, np.nan)
            return PeopleTracks(times, self.names, nan, nan.copy(), nan.copy(), nan.copy(), nan.copy(),
                                np.full(shape, "", dtype=object), self.roles)
        last = len(self.times) - 1
        i = np.clip(np.searchsorted(self.times, times, side="right") - 1, 0, last)
        j = np.minimum(i + 1, last)
        span = self.times[j] - self.times[i]
        w = np.where(span > 0, (times - self.times[i]) / np.where(span > 0, span, 1.0), 0.0)[:, None]
        on_sample = (times == self.times[i])[:, None]
        outside = ((times < self.times[0]) | (times > self.times[-1]))[:, None]

        def lerp(values: NDArray[np.float64], step: NDArray[np.float64] | None = None) -> NDArray[np.float64]:
            a, b = values[i], values[j]
            out = np.where(on_sample, a, a + (b - a if step is None else step) * w)   # NaN at either side: absent
            return np.where(outside, np.nan, out)

        theta = wrap_angle(lerp(self.theta, wrap_angle(self.theta[j] - self.theta[i])))
        x = lerp(self.x)
        groups = np.where(np.isfinite(x), self.groups[i], "")
        return PeopleTracks(times, self.names, x, lerp(self.y), theta, lerp(self.vx), lerp(self.vy),
                            groups, self.roles)


class DynamicMetrics(BaseModel):
    """The metrics among moving people of one run, ``--definitions published`` (module doc; each
    field's definition, unit and source: metric_catalog.py).  None = not measurable, ``missing``
    says why."""

    model_config = ConfigDict(frozen=True)

    min_distance_to_people_m: float | None
    max_distance_to_people_m: float | None
    avg_distance_to_closest_person_m: float | None
    intimate_intrusions_percent: float
    personal_intrusions_percent: float
    social_intrusions_percent: float
    intrusions_per_person: dict[str, dict[str, float]]
    group_intimate_intrusions_percent: float
    group_personal_intrusions_percent: float
    group_social_intrusions_percent: float
    intrusions_per_group: dict[str, dict[str, float]]
    robot_on_person_collisions: int
    person_on_robot_collisions: int
    robot_intimate_entries: int
    time_not_moving_s: float
    avg_robot_linear_speed_mps: float | None
    avg_robot_angular_speed_radps: float | None
    avg_acceleration_mps2: float | None
    avg_jerk_mps3: float | None
    avg_pedestrian_speed_mps: float | None
    avg_closest_pedestrian_speed_mps: float | None
    social_force_on_robot: float
    social_force_on_people: float
    obstacle_force_on_robot: float
    obstacle_force_on_people: float | None
    social_work: float
    completed: bool | None = None
    minimum_distance_to_target_m: float | None = None
    final_distance_to_target_m: float | None = None
    missing: dict[str, str] = {}


def _bands(distances: NDArray[np.float64]) -> dict[str, float]:
    """Share (%) of the samples in each of Hall's bands (NaN: nobody there, counts in none)."""
    n = len(distances)
    if n == 0:
        return {name: 0.0 for name, _, _ in BANDS}
    return {name: 100.0 * float(np.sum((distances >= lo) & (distances < hi))) / n for name, lo, hi in BANDS}


def social_force(source_xy: NDArray[np.float64], source_v: NDArray[np.float64], target_xy: NDArray[np.float64],
                 target_v: NDArray[np.float64], *, swapped_atan2: bool = False) -> NDArray[np.float64]:
    """The social force ``source`` exerts on ``target`` (arrays of (..., 2)): lightsfm's
    computeSocialForce for one pair, vectorised.  ``swapped_atan2`` reproduces HuNavSim's
    evaluator (sfm.py), which takes the interaction direction's angle as atan2(x, y)."""
    diff = source_xy - target_xy
    distance = np.maximum(np.hypot(diff[..., 0], diff[..., 1]), 1e-9)
    direction = diff / distance[..., None]
    interaction = SF_LAMBDA * (target_v - source_v) + direction
    length = np.maximum(np.hypot(interaction[..., 0], interaction[..., 1]), 1e-9)
    interaction_dir = interaction / length[..., None]
    ix, iy = interaction_dir[..., 0], interaction_dir[..., 1]
    # lightsfm: theta = interactionDirection.angleTo(diffDirection)
    theta = np.arctan2(direction[..., 1], direction[..., 0]) - (np.arctan2(ix, iy) if swapped_atan2
                                                                 else np.arctan2(iy, ix))
    theta = np.where(theta > math.pi, theta - 2 * math.pi, np.where(theta < -math.pi, theta + 2 * math.pi, theta))
    b = SF_GAMMA * length
    velocity_amount = -np.exp(-distance / b - (SF_N_PRIME * b * theta) ** 2)
    angle_amount = -np.sign(theta) * np.exp(-distance / b - (SF_N * b * theta) ** 2)
    normal = np.stack([-iy, ix], axis=-1)
    return SF_FACTOR * (velocity_amount[..., None] * interaction_dir + angle_amount[..., None] * normal)


@dataclass(frozen=True)
class _Robot:
    """The robot's samples and what is derived from them once for both definitions."""

    t: NDArray[np.float64]
    xy: NDArray[np.float64]
    theta: NDArray[np.float64]
    dt: NDArray[np.float64]             # (N-1,)
    gap: NDArray[np.bool_]              # (N-1,) an interval that is a gap between missions
    velocity: NDArray[np.float64]       # (N, 2) toward the next sample (the last repeats)
    omega: NDArray[np.float64]          # (N,) signed turn rate toward the next sample (the last repeats)

    @classmethod
    def of(cls, traj: NDArray[np.float64]) -> _Robot:
        t, xy, theta = traj[:, 0], traj[:, 1:3], traj[:, 3]
        n = len(t)
        dt = np.diff(t)
        # A trajectory of several missions has gaps (the robot was parked, nothing recorded): an
        # interval much longer than the usual sampling is not time spent navigating.
        gap = dt > GAP_FACTOR * float(np.median(dt)) if len(dt) else np.zeros(0, dtype=bool)
        velocity, omega = np.zeros((n, 2)), np.zeros(n)
        if n > 1:
            safe = np.where(dt > 0, dt, 1.0)
            turn = wrap_angle(np.diff(theta))
            velocity[:-1] = np.where(dt[:, None] > 0, np.diff(xy, axis=0) / safe[:, None], 0.0)
            omega[:-1] = np.where(dt > 0, turn / safe, 0.0)
            velocity[-1], omega[-1] = velocity[-2], omega[-2]
        return cls(t, xy, theta, dt, gap, velocity, omega)

    @property
    def speed(self) -> NDArray[np.float64]:
        return np.hypot(self.velocity[:, 0], self.velocity[:, 1])


def _nearest_obstacle_force(obstacles: BaseGeometry | None, x: NDArray[np.float64], y: NDArray[np.float64],
                            radius_m: float) -> NDArray[np.float64]:
    """|obstacle force| of the nearest wall or object point: 10 exp(-(d - radius) / 0.2) (0 without obstacles)."""
    if obstacles is None or obstacles.is_empty:
        return np.zeros(np.shape(x))
    flat_x, flat_y = np.ravel(x), np.ravel(y)
    there = np.isfinite(flat_x) & np.isfinite(flat_y)
    distance = np.full(flat_x.shape, np.nan)        # NaN: nobody there (a person who is absent)
    distance[there] = shapely.distance(obstacles, shapely.points(np.column_stack([flat_x[there], flat_y[there]])))
    return (OBSTACLE_FACTOR * np.exp(-(distance - radius_m) / OBSTACLE_SIGMA_M)).reshape(np.shape(x))


def _target(robot: _Robot, goal_xy: tuple[float, float] | None, goal_radius_m: float,
            missing: dict[str, str]) -> dict[str, Any]:
    """completed / minimum / final distance to the target (None and a reason without a goal)."""
    if goal_xy is None:
        for key in ("completed", "minimum_distance_to_target_m", "final_distance_to_target_m"):
            missing[key] = "no target: the mission has no goal point (give --goal X,Y)"
        return {}
    distance = np.hypot(robot.xy[:, 0] - goal_xy[0], robot.xy[:, 1] - goal_xy[1])
    return {"completed": bool(distance[-1] - goal_radius_m < GOAL_SLACK_M),
            "minimum_distance_to_target_m": float(distance.min()),
            "final_distance_to_target_m": float(distance[-1])}


def _motion(robot: _Robot) -> dict[str, float | None]:
    """Average speeds, acceleration and jerk of the robot (published definitions; gaps excluded)."""
    if len(robot.dt) == 0:
        return {"avg_robot_linear_speed_mps": None, "avg_robot_angular_speed_radps": None,
                "avg_acceleration_mps2": None, "avg_jerk_mps3": None}
    moving = (robot.dt > 0) & ~robot.gap
    speed = robot.speed[:-1][moving]
    turn = np.abs(robot.omega[:-1][moving])
    v = robot.speed
    ok = moving[:-1] & moving[1:] if len(moving) > 1 else np.zeros(0, dtype=bool)
    # a_k between the speeds of intervals k and k+1, over the time between their midpoints
    mid = (robot.dt[:-1] + robot.dt[1:]) / 2.0
    accel = np.where(ok, (v[1:-1] - v[:-2]) / np.where(ok, mid, 1.0), np.nan)
    jerk_ok = ok[:-1] & ok[1:] if len(ok) > 1 else np.zeros(0, dtype=bool)
    jerk = (accel[1:] - accel[:-1])[jerk_ok] / robot.dt[1:-1][jerk_ok] if jerk_ok.any() else np.zeros(0)
    return {"avg_robot_linear_speed_mps": float(speed.mean()) if speed.size else None,
            "avg_robot_angular_speed_radps": float(turn.mean()) if turn.size else None,
            "avg_acceleration_mps2": float(np.nanmean(np.abs(accel))) if ok.any() else None,
            "avg_jerk_mps3": float(np.abs(jerk).mean()) if jerk.size else None}


def _closest(edge: NDArray[np.float64]) -> NDArray[np.float64]:
    """Per sample the smallest of a (T, N) array over the people there (NaN: nobody there)."""
    return np.fmin.reduce(edge, axis=1)          # fmin skips NaN (and, unlike nanmin, does not warn on an all-NaN row)


def _mean_over_present(values: NDArray[np.float64]) -> NDArray[np.float64]:
    """Per sample the mean of a (T, N) array over the people there; 0 where nobody is (a sum over
    samples then counts only the samples with people)."""
    there = np.isfinite(values)
    count = there.sum(axis=1)
    return np.where(count > 0, np.where(there, values, 0.0).sum(axis=1) / np.maximum(count, 1), 0.0)


def dynamic_metrics(traj: NDArray[np.float64], tracks: PeopleTracks | None, robot_radius_m: float,
                    obstacles: BaseGeometry | None = None, intimate_level: float | None = 0.8, *,
                    person_radius_m: float = PERSON_RADIUS_M, goal_xy: tuple[float, float] | None = None,
                    goal_radius_m: float = GOAL_RADIUS_M) -> DynamicMetrics:
    """The published definitions of the robot's ``traj`` (N, 4: t, x, y, theta) among ``tracks``."""
    robot = _Robot.of(traj)
    xy, n = robot.xy, len(robot.t)
    missing: dict[str, str] = {}
    still = np.zeros(0, dtype=bool)
    if len(robot.dt):
        step = np.hypot(*np.diff(xy, axis=0).T)
        turn = np.abs(wrap_angle(np.diff(robot.theta)))
        with np.errstate(divide="ignore", invalid="ignore"):
            speed = np.where(robot.dt > 0, step / robot.dt, 0.0)
            omega = np.where(robot.dt > 0, turn / robot.dt, 0.0)
        still = (speed < STILL_MPS) & (omega < STILL_RADPS) & ~robot.gap
    base: dict[str, Any] = {"time_not_moving_s": float(robot.dt[still].sum()) if still.size else 0.0,
                            **_motion(robot), **_target(robot, goal_xy, goal_radius_m, missing)}
    for key in ("avg_robot_linear_speed_mps", "avg_robot_angular_speed_radps", "avg_acceleration_mps2",
                "avg_jerk_mps3"):
        if base[key] is None:
            missing[key] = "too few samples (speeds need 2, acceleration 3, jerk 4 in one mission)"
    obstacle_on_robot = _nearest_obstacle_force(obstacles, xy[:, 0], xy[:, 1], robot_radius_m)
    people = tracks.at(robot.t) if tracks is not None and tracks.names else None
    if people is None or not people.present.any():
        why = NO_TRACKS if people is None else NOBODY_THERE
        for key in ("min_distance_to_people_m", "max_distance_to_people_m", "avg_distance_to_closest_person_m",
                    "avg_pedestrian_speed_mps", "avg_closest_pedestrian_speed_mps", "obstacle_force_on_people"):
            missing[key] = why
        return DynamicMetrics(**base, min_distance_to_people_m=None, max_distance_to_people_m=None,
                              avg_distance_to_closest_person_m=None, intimate_intrusions_percent=0.0,
                              personal_intrusions_percent=0.0, social_intrusions_percent=0.0,
                              intrusions_per_person={}, group_intimate_intrusions_percent=0.0,
                              group_personal_intrusions_percent=0.0, group_social_intrusions_percent=0.0,
                              intrusions_per_group={}, avg_pedestrian_speed_mps=None,
                              avg_closest_pedestrian_speed_mps=None, social_force_on_robot=0.0,
                              social_force_on_people=0.0, obstacle_force_on_robot=float(obstacle_on_robot.sum()),
                              obstacle_force_on_people=None, social_work=float(obstacle_on_robot.sum()),
                              robot_on_person_collisions=0, person_on_robot_collisions=0,
                              robot_intimate_entries=0, missing=missing)
    pxy = np.stack([people.x, people.y], axis=-1)            # (T, N, 2); NaN: not there
    pv = np.stack([people.vx, people.vy], axis=-1)
    pspeed = np.hypot(people.vx, people.vy)
    centre = np.hypot(pxy[..., 0] - xy[:, None, 0], pxy[..., 1] - xy[:, None, 1])   # (T, N)
    edge = np.maximum(centre - robot_radius_m - person_radius_m, 0.0)   # body edges, clipped: no overlap < 0
    closest_j = np.argmin(np.nan_to_num(centre, nan=np.inf), axis=1)
    closest = _closest(edge)
    per_person = {name: _bands(edge[:, j]) for j, name in enumerate(people.names)}
    group_distance, per_group = _regrouped(people, xy, robot_radius_m)
    groups = _bands(group_distance)
    # social forces (lightsfm) and the obstacle forces
    robot_xy = np.broadcast_to(xy[:, None, :], pxy.shape)
    robot_v = np.broadcast_to(robot.velocity[:, None, :], pv.shape)
    on_robot = np.nan_to_num(social_force(pxy, pv, robot_xy, robot_v))       # each person on the robot
    on_people = np.nan_to_num(social_force(robot_xy, robot_v, pxy, pv))      # the robot on each person
    on_robot_mod = np.hypot(on_robot[..., 0], on_robot[..., 1])
    on_people_mod = np.hypot(on_people[..., 0], on_people[..., 1])
    total_on_robot = on_robot.sum(axis=1)
    work = np.hypot(total_on_robot[:, 0], total_on_robot[:, 1]) + obstacle_on_robot + on_people_mod.sum(axis=1)
    obstacle_on_people = _nearest_obstacle_force(obstacles, people.x, people.y, person_radius_m)
    robot_hits, person_hits = _collisions(xy, robot.velocity, pxy, pv, centre - robot_radius_m - person_radius_m)
    inside = _intimate(people, xy, intimate_level) if intimate_level is not None else np.zeros_like(centre, dtype=bool)
    entries, _ = _collisions(xy, robot.velocity, pxy, pv, np.where(inside, -1.0, np.inf))
    shares = _bands(closest)
    return DynamicMetrics(
        **base,
        min_distance_to_people_m=float(np.nanmin(edge)), max_distance_to_people_m=float(np.nanmax(edge)),
        avg_distance_to_closest_person_m=float(np.nanmean(closest)),
        intimate_intrusions_percent=shares["intimate"], personal_intrusions_percent=shares["personal"],
        social_intrusions_percent=shares["social"], intrusions_per_person=per_person,
        group_intimate_intrusions_percent=groups["intimate"], group_personal_intrusions_percent=groups["personal"],
        group_social_intrusions_percent=groups["social"], intrusions_per_group=per_group,
        avg_pedestrian_speed_mps=float(np.nanmean(pspeed)),
        avg_closest_pedestrian_speed_mps=float(np.nanmean(pspeed[np.arange(n), closest_j])),
        social_force_on_robot=float(on_robot_mod.sum()), social_force_on_people=float(on_people_mod.sum()),
        obstacle_force_on_robot=float(obstacle_on_robot.sum()),
        obstacle_force_on_people=float(_mean_over_present(obstacle_on_people).sum()),
        social_work=float(work.sum()), robot_on_person_collisions=robot_hits, person_on_robot_collisions=person_hits,
        robot_intimate_entries=entries, missing=missing)


def _regrouped(people: PeopleTracks, xy: NDArray[np.float64],
               robot_radius_m: float) -> tuple[NDArray[np.float64], dict[str, dict[str, float]]]:
    """Per sample the distance from the robot's edge to the closest group centre (NaN: no group),
    groups taken afresh at every sample and of two or more members; and per group its Hall shares."""
    n = len(xy)
    group_distance = np.full(n, np.nan)
    per_group_distances: dict[str, list[float]] = {}
    for k in range(n):
        labels: dict[str, list[int]] = {}
        for j, label in enumerate(people.groups[k]):
            if label:
                labels.setdefault(str(label), []).append(j)
        for label, members in labels.items():
            if len(members) < 2:
                continue
            gaze = np.column_stack([people.x[k, members] + GROUP_GAZE_M * np.cos(people.theta[k, members]),
                                    people.y[k, members] + GROUP_GAZE_M * np.sin(people.theta[k, members])])
            cx, cy = gaze.mean(axis=0)
            d = max(0.0, math.hypot(cx - xy[k, 0], cy - xy[k, 1]) - robot_radius_m)   # clipped like every distance
            per_group_distances.setdefault(label, []).append(d)
            group_distance[k] = d if np.isnan(group_distance[k]) else min(group_distance[k], d)
    per_group = {}
    for label, distances in sorted(per_group_distances.items()):
        counts = _bands(np.asarray(distances))
        per_group[label] = {band: share * len(distances) / n for band, share in counts.items()}
    return group_distance, per_group


def hunav_metrics(traj: NDArray[np.float64], tracks: PeopleTracks | None, *,
                  robot_radius_m: float = HUNAV_RADIUS_M, person_radius_m: float = HUNAV_RADIUS_M,
                  goal_xy: tuple[float, float] | None = None, goal_radius_m: float = GOAL_RADIUS_M,
                  obstacles: BaseGeometry | None = None) -> tuple[dict[str, float | bool | None], dict[str, str]]:
    """HuNavSim's evaluator (hunav_metrics.py and sfm.py, ROS 2 humble) on chronav's samples, quirks
    included (docs/metrics.md lists them), keyed by HuNavSim's own metric names; and, per metric
    left None, why.  A sample is one robot sample with every person interpolated to its time."""
    robot = _Robot.of(traj)
    xy, n = robot.xy, len(robot.t)
    v, w = robot.speed, robot.omega
    missing: dict[str, str] = {}
    total = float(robot.t[-1] - robot.t[0])
    out: dict[str, float | bool | None] = {
        "time_to_reach_goal": total,
        "path_length": float(np.hypot(*np.diff(xy, axis=0).T).sum()) if n > 1 else 0.0,
        # normalize_angle(yaw[i] - yaw[i+1]) to (-pi, pi]: the same magnitude as chronav's wrap
        "cumulative_heading_changes": float(np.abs(wrap_angle(robot.theta[:-1] - robot.theta[1:])).sum())
        if n > 1 else 0.0,
        # quirk: abs(angular_vel < 0.02) - a clockwise turn (w < 0) counts as not moving; step = total / N
        "time_not_moving": total / n * float(np.sum((v < 0.01) & (w < 0.02))),
        "avg_robot_linear_speed": float(v.mean()),
        "avg_robot_angular_speed": float(np.abs(w).mean()),
    }
    dv = np.diff(v)
    nonzero = robot.dt != 0
    accel = np.where(nonzero, dv / np.where(nonzero, robot.dt, 1.0), 0.0)
    out["avg_acceleration"] = float(accel.sum()) / n              # signed, over N samples (not N - 1)
    out["avg_overacceleration"] = float(np.where(nonzero, accel / np.where(nonzero, robot.dt, 1.0), 0.0).sum()) / n
    target = _target(robot, goal_xy, goal_radius_m, missing)
    out["completed"] = target.get("completed")
    out["minimum_distance_to_target"] = target.get("minimum_distance_to_target_m")
    out["final_distance_to_target"] = target.get("final_distance_to_target_m")
    for ours, theirs in (("completed", "completed"), ("minimum_distance_to_target_m", "minimum_distance_to_target"),
                         ("final_distance_to_target_m", "final_distance_to_target")):
        if ours in missing:
            missing[theirs] = missing.pop(ours)
    out["obstacle_force_on_robot"] = 0.0     # quirk: HuNavSim's pipeline never fills the robot's closest_obs
    people_keys = ("avg_distance_to_closest_person", "minimum_distance_to_people", "maximum_distance_to_people",
                   "intimate_space_intrusions", "personal_space_intrusions", "social_space_intrusions",
                   "group_intimate_space_intrusions", "group_personal_space_intrusions",
                   "group_social_space_intrusions", "robot_on_person_collision", "person_on_robot_collision",
                   "avg_pedestrian_velocity", "avg_closest_pedestrian_velocity", "social_force_on_agents",
                   "social_force_on_robot", "social_work", "obstacle_force_on_agents")
    people = tracks.at(robot.t) if tracks is not None and tracks.names else None
    if people is None or not people.present.any():
        for key in people_keys:
            out[key] = None
            missing[key] = NO_TRACKS if people is None else NOBODY_THERE
        return out, missing
    # A sample's agents are the people there (HuNavSim's agents message of that time): NaN = absent.
    pxy = np.stack([people.x, people.y], axis=-1)
    pv = np.stack([people.vx, people.vy], axis=-1)
    pspeed = np.hypot(people.vx, people.vy)
    centre = np.hypot(pxy[..., 0] - xy[:, None, 0], pxy[..., 1] - xy[:, None, 1])
    edge = centre - robot_radius_m - person_radius_m
    closest = np.maximum(_closest(edge), 0.0)         # NaN: nobody there (HuNavSim's 10000, in no band)
    out["avg_distance_to_closest_person"] = float(np.nansum(closest)) / n     # samples without anyone add 0
    out["minimum_distance_to_people"] = float(np.nanmin(np.maximum(edge, 0.0)))
    out["maximum_distance_to_people"] = float(np.nanmax(centre - robot_radius_m))     # quirk: robot radius only
    for band, lo, hi in (("intimate", -math.inf, 0.45), ("personal", 0.45, 1.2), ("social", 1.2, 3.6)):
        out[f"{band}_space_intrusions"] = 100.0 * float(np.sum((closest >= lo) & (closest < hi))) / n
    group_closest = _first_sample_groups(people, xy, robot_radius_m)
    for band, lo, hi in (("intimate", -math.inf, 0.45), ("personal", 0.45, 1.2), ("social", 1.2, 3.6)):
        out[f"group_{band}_space_intrusions"] = 0.0 if group_closest is None else \
            100.0 * float(np.sum((group_closest >= lo) & (group_closest < hi))) / n
    robot_hits, person_hits = _hunav_collisions(robot, people, pspeed, edge)
    out["robot_on_person_collision"], out["person_on_robot_collision"] = robot_hits, person_hits
    first = int(people.present[0].sum())     # quirk: the sum over samples / (N x the people at the first sample)
    out["avg_pedestrian_velocity"] = float(np.nansum(pspeed)) / (n * first) if first else None
    if not first:
        missing["avg_pedestrian_velocity"] = ("nobody at the first sample: HuNavSim divides by the number of "
                                              "people there (it would divide by zero)")
    nearest = pspeed[np.arange(n), np.argmin(np.nan_to_num(edge, nan=np.inf), axis=1)]
    out["avg_closest_pedestrian_velocity"] = float(np.nansum(nearest)) / n     # nobody there: an Agent() of speed 0
    robot_xy = np.broadcast_to(xy[:, None, :], pxy.shape)
    robot_v = np.broadcast_to(robot.velocity[:, None, :], pv.shape)
    on_robot = np.nan_to_num(social_force(pxy, pv, robot_xy, robot_v, swapped_atan2=True))
    on_people = np.nan_to_num(social_force(robot_xy, robot_v, pxy, pv, swapped_atan2=True))
    on_people_mod = np.hypot(on_people[..., 0], on_people[..., 1])
    out["social_force_on_robot"] = float(np.hypot(on_robot[..., 0], on_robot[..., 1]).sum())
    out["social_force_on_agents"] = float(on_people_mod.sum())
    total_on_robot = on_robot.sum(axis=1)
    out["social_work"] = float((np.hypot(total_on_robot[:, 0], total_on_robot[:, 1]) + on_people_mod.sum(axis=1)).sum())
    obstacle_on_people = _nearest_obstacle_force(obstacles, people.x, people.y, person_radius_m)
    out["obstacle_force_on_agents"] = float(_mean_over_present(obstacle_on_people).sum())   # nobody there: skipped
    if obstacles is None or obstacles.is_empty:
        missing["obstacle_force_on_agents"] = "0: no walls or objects given"
    return out, missing


def _first_sample_groups(people: PeopleTracks, xy: NDArray[np.float64],
                         robot_radius_m: float) -> NDArray[np.float64] | None:
    """HuNavSim's group distances: the group ids of the first sample (one-member groups included),
    at every sample the closest of their centres (members there moved 1.5 m along their heading,
    averaged) minus the robot's radius; 10000 m when none of them has members at that sample
    (HuNavSim would divide by zero there).  None without groups."""
    ids = list(dict.fromkeys(str(g) for g in people.groups[0] if g))
    if not ids:
        return None
    out = np.full(len(xy), 10000.0)
    for k in range(len(xy)):
        for label in ids:
            members = [j for j, g in enumerate(people.groups[k]) if str(g) == label]
            if not members:
                continue
            cx = float(np.mean(people.x[k, members] + GROUP_GAZE_M * np.cos(people.theta[k, members])))
            cy = float(np.mean(people.y[k, members] + GROUP_GAZE_M * np.sin(people.theta[k, members])))
            out[k] = min(out[k], math.hypot(xy[k, 0] - cx, xy[k, 1] - cy) - robot_radius_m)
    return out


def _hunav_collisions(robot: _Robot, people: PeopleTracks, pspeed: NDArray[np.float64],
                      edge: NDArray[np.float64]) -> tuple[int, int]:
    """HuNavSim's collisions: every sample with edge < 0.02 m counts, blamed by comparing the
    robot's bearing in the person's frame (atan2(y, x)) with the person's in the robot's frame
    (taken as atan2(x, y): quirk) and the two linear speeds."""
    robot_hits = person_hits = 0
    v = robot.speed
    for k, j in zip(*np.nonzero(edge < CONTACT_M), strict=True):
        rx, ry = robot.xy[k]
        ax, ay, ayaw = people.x[k, j], people.y[k, j], people.theta[k, j]
        dx, dy = rx - ax, ry - ay
        alpha = abs(math.atan2(-dx * math.sin(ayaw) + dy * math.cos(ayaw), dx * math.cos(ayaw) + dy * math.sin(ayaw)))
        yaw = robot.theta[k]
        alpha2 = abs(math.atan2(-dx * math.cos(yaw) - dy * math.sin(yaw), dx * math.sin(yaw) - dy * math.cos(yaw)))
        vr, va = v[k], pspeed[k, j]
        if alpha < alpha2 and vr != va:
            robot_hits += 1
        elif alpha > alpha2 and vr != va:
            person_hits += 1
        elif alpha == alpha2 and vr == va:
            robot_hits += 1
            person_hits += 1
    return robot_hits, person_hits


def _intimate(people: PeopleTracks, xy: NDArray[np.float64], level: float = 0.8) -> NDArray[np.bool_]:
    """(T, N): the robot's centre inside each person's intimate zone - their personal space as the
    social map draws it (role-scaled, stretched along their velocity: personal_space.py,
    motion.py) at or above the intimate level, from where they truly are."""
    motion, space_params, roles = MotionParams(), PersonalSpaceParams(), RoleParams()
    out = np.zeros(people.x.shape, dtype=bool)
    for j, name in enumerate(people.names):
        role = people.roles[j] if j < len(people.roles) and people.roles[j] in roles.scales else "resident"
        scale = roles.scales[role]
        rest = PersonalSpace.from_params(space_params, scale)
        for k in np.flatnonzero(np.isfinite(people.x[:, j])):      # only where they are
            person = Person(name, float(people.x[k, j]), float(people.y[k, j]), float(people.theta[k, j]),
                            vx=float(people.vx[k, j]), vy=float(people.vy[k, j]))
            walking = oriented(person, motion)
            space = stretched(rest, walking, scale, motion)
            out[k, j] = float(asymmetric_gaussian(space, walking.x, walking.y, walking.theta, xy[k, 0], xy[k, 1])) >= level
    return out


def _collisions(xy: NDArray[np.float64], velocity: NDArray[np.float64], pxy: NDArray[np.float64],
                pv: NDArray[np.float64], gap: NDArray[np.float64]) -> tuple[int, int]:
    """Contacts (gap < CONTACT_M), each counted once at its first sample and blamed on whoever
    approached the other faster there."""
    robot_hits = person_hits = 0
    touching = np.nan_to_num(gap, nan=np.inf) < CONTACT_M                  # (T, N)
    onset = touching & ~np.vstack([np.zeros((1, touching.shape[1]), dtype=bool), touching[:-1]])
    for k, j in zip(*np.nonzero(onset), strict=True):
        towards = pxy[k, j] - xy[k]
        norm = float(np.hypot(*towards)) or 1.0
        u = towards / norm
        robot_closing = float(velocity[k] @ u)
        person_closing = float(pv[k, j] @ -u)
        if robot_closing >= person_closing:
            robot_hits += 1
        else:
            person_hits += 1
    return robot_hits, person_hits


def tracks_from_rows(rows: Sequence[tuple]) -> PeopleTracks:
    """(t, name, x, y, theta, vx, vy, group[, role]) rows, any order of names within a time, into tracks."""
    times = sorted({row[0] for row in rows})
    names = tuple(sorted({row[1] for row in rows}))
    index_t = {t: i for i, t in enumerate(times)}
    index_n = {name: j for j, name in enumerate(names)}
    shape = (len(times), len(names))
    arrays: Mapping[str, NDArray[np.float64]] = {key: np.full(shape, np.nan) for key in ("x", "y", "theta", "vx", "vy")}
    groups = np.full(shape, "", dtype=object)
    roles = {name: "" for name in names}
    for t, name, x, y, theta, vx, vy, group, *role in rows:
        i, j = index_t[t], index_n[name]
        if role:
            roles[name] = role[0]
        for key, value in zip(("x", "y", "theta", "vx", "vy"), (x, y, theta, vx, vy), strict=True):
            arrays[key][i, j] = value
        groups[i, j] = group
    # a person missing at some time is absent there (NaN): PeopleTracks.present
    return PeopleTracks(np.asarray(times, dtype=float), names, arrays["x"], arrays["y"], arrays["theta"],
                        arrays["vx"], arrays["vy"], groups, tuple(roles[n] for n in names))
