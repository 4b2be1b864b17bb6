"""The dynamic metrics of HuNavSim: how the robot moved among people who move, from both trajectories.

N. Pérez-Higueras, R. Otero, F. Caballero and L. Merino, "HuNavSim: A ROS 2 Human Navigation
Simulator for Benchmarking Human-Aware Robot Navigation", IEEE RA-L 8(11), 2023; definitions as in
its evaluator (hunav_evaluator/hunav_metrics.py and sfm.py), on the robot's samples with every
person's position and velocity at the same times (``people.csv``, interpolated when the times
differ).  With d the distance between the robot's and a person's centres, r the robot's radius and
r_p = 0.25 m a person's:

* ``time_to_goal_s``: last sample time minus the first.  ``path_length_m``: the polyline's length.
  ``cumulative_heading_changes_rad``: sum of |wrap(theta[k+1] - theta[k])|.
* ``min_distance_to_people_m``: min over samples and people of d - r (HuNavSim subtracts the
  robot's radius only).  ``avg_distance_to_closest_person_m``: mean over samples of the closest
  person's d - r - r_p.
* ``{intimate,personal,social}_intrusions_percent``: share of samples whose closest person has
  d - r in [0, 0.45), [0.45, 1.2), [1.2, 3.6) m (Hall's distances; below 0 counts as intimate);
  ``intrusions_per_person``: the same per person (that person's own distance).
* ``group_*_intrusions_percent``: the same with each group's centre instead of a person - the
  mean of its members' positions each moved 1.5 m along their heading (where their gazes meet);
  ``intrusions_per_group`` per group.  Groups are the ``group`` column of people.csv (people in one
  formation at an activity, or one conversation).
* ``social_force_on_robot``, ``social_force_on_people``: sums over samples of the moduli of the
  social forces (Helbing and Molnár's model as extended by Moussaïd et al. 2009, HuNavSim's
  parameters: A = 2.1, lambda = 2, gamma = 0.35, n = 2, n' = 3) the people exert on the robot and
  the robot exerts on each person; ``social_work``: per sample |sum of forces on the robot| + |the
  obstacle force on it| (10 exp(-(d_o - r) / 0.2) from the nearest wall or object) + the sum of the
  forces it exerts, summed over samples (HuNavSim's computeSocialWork).
* ``robot_on_person_collisions``, ``person_on_robot_collisions``: contacts (d - r - r_p < 0.02 m),
  each blamed on whichever of the two was moving toward the other faster.  HuNavSim counts every
  sample in contact; we count each contact once (its first sample), so a robot resting against a
  person is one collision, not one per 0.1 s.
* ``robot_intimate_entries``: how often the robot entered someone's intimate zone as the social
  map draws it (their personal space, role-scaled and stretched along their velocity, at the
  intimate level 0.8; personal_space.py, motion.py, zones.py), each entry blamed like a collision
  and counted only when the robot did the approaching: a person walking up to the robot is theirs.
* ``time_not_moving_s``: total time (each sample's interval to the next) in which the robot moved
  less than 1 cm/s and turned less than 0.01 rad/s; an interval over ``GAP_FACTOR`` times the
  median sampling is a gap between two missions (nothing was recorded) and does not count.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

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
BANDS: tuple[tuple[str, float, float], ...] = (("intimate", -math.inf, 0.45), ("personal", 0.45, 1.2),
                                               ("social", 1.2, 3.6))
GROUP_GAZE_M = 1.5
CONTACT_M = 0.02
STILL_MPS, STILL_RADPS = 0.01, 0.01
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

    def at(self, times: NDArray[np.float64]) -> PeopleTracks:
        """The tracks at ``times``: interpolated linearly (headings along the shorter turn), groups
        from the nearest earlier sample; constant beyond the recorded span."""
        if len(self.times) == len(times) and np.array_equal(self.times, times):
            return self
        idx = np.clip(np.searchsorted(self.times, times, side="right") - 1, 0, len(self.times) - 1)

        def lerp(values: NDArray[np.float64]) -> NDArray[np.float64]:
            return np.column_stack([np.interp(times, self.times, values[:, j]) for j in range(len(self.names))]) \
                if len(self.names) else np.zeros((len(times), 0))

        unwrapped = np.unwrap(self.theta, axis=0) if len(self.times) else self.theta
        return PeopleTracks(np.asarray(times, dtype=float), self.names, lerp(self.x), lerp(self.y),
                            wrap_angle(lerp(unwrapped)), lerp(self.vx), lerp(self.vy),
                            self.groups[idx], self.roles)


class DynamicMetrics(BaseModel):
    """HuNavSim's metrics of one run (module doc for each definition)."""

    model_config = ConfigDict(frozen=True)

    time_to_goal_s: float
    path_length_m: float
    cumulative_heading_changes_rad: float
    min_distance_to_people_m: float | None
    avg_distance_to_closest_person_m: float | None
    intimate_intrusions_percent: float
    personal_intrusions_percent: float
    social_intrusions_percent: float
    intrusions_per_person: dict[str, dict[str, float]]
    group_intimate_intrusions_percent: float
    group_personal_intrusions_percent: float
    group_social_intrusions_percent: float
    intrusions_per_group: dict[str, dict[str, float]]
    social_force_on_robot: float
    social_force_on_people: float
    social_work: float
    robot_on_person_collisions: int
    person_on_robot_collisions: int
    robot_intimate_entries: int
    time_not_moving_s: float

    def to_table(self) -> list[tuple[str, str]]:
        def metres(value: float | None) -> str:
            return "-" if value is None else f"{value:.2f}"

        return [
            ("time to goal (s)", f"{self.time_to_goal_s:.1f}"),
            ("path length (m)", f"{self.path_length_m:.2f}"),
            ("cumulative heading changes (rad)", f"{self.cumulative_heading_changes_rad:.2f}"),
            ("min distance to people (m)", metres(self.min_distance_to_people_m)),
            ("avg distance to closest person (m)", metres(self.avg_distance_to_closest_person_m)),
            ("intimate / personal / social intrusions (% of time)",
             f"{self.intimate_intrusions_percent:.1f} / {self.personal_intrusions_percent:.1f} / "
             f"{self.social_intrusions_percent:.1f}"),
            ("group intimate / personal / social intrusions (% of time)",
             f"{self.group_intimate_intrusions_percent:.1f} / {self.group_personal_intrusions_percent:.1f} / "
             f"{self.group_social_intrusions_percent:.1f}"),
            ("social force on robot / on people", f"{self.social_force_on_robot:.2f} / {self.social_force_on_people:.2f}"),
            ("social work", f"{self.social_work:.2f}"),
            ("collisions robot-on-person / person-on-robot",
             f"{self.robot_on_person_collisions} / {self.person_on_robot_collisions}"),
            ("intimate zone entries by the robot", str(self.robot_intimate_entries)),
            ("time not moving (s)", f"{self.time_not_moving_s:.1f}"),
        ]


def _bands(distances: NDArray[np.float64]) -> dict[str, float]:
    """Share (%) of the samples in each of Hall's bands (NaN: nobody there, counts in none)."""
    n = len(distances)
    if n == 0:
        return {name: 0.0 for name, _, _ in BANDS}
    return {name: 100.0 * float(np.sum((distances >= lo) & (distances < hi))) / n for name, lo, hi in BANDS}


def social_force(source_xy: NDArray[np.float64], source_v: NDArray[np.float64], target_xy: NDArray[np.float64],
                 target_v: NDArray[np.float64]) -> NDArray[np.float64]:
    """The social force ``source`` exerts on ``target`` (arrays of (..., 2)), HuNavSim's
    computeSocialForceTwoAgents vectorised."""
    diff = source_xy - target_xy
    distance = np.maximum(np.hypot(diff[..., 0], diff[..., 1]), 1e-9)
    direction = diff / distance[..., None]
    interaction = SF_LAMBDA * (target_v - source_v) + direction
    length = np.maximum(np.hypot(interaction[..., 0], interaction[..., 1]), 1e-9)
    interaction_dir = interaction / length[..., None]
    theta = np.arctan2(interaction_dir[..., 1], interaction_dir[..., 0]) - np.arctan2(direction[..., 1], direction[..., 0])
    theta = wrap_angle(theta)
    b = SF_GAMMA * length
    velocity_amount = -np.exp(-distance / b - (SF_N_PRIME * b * theta) ** 2)
    angle_amount = -np.sign(theta) * -np.exp(-distance / b - (SF_N * b * theta) ** 2)
    normal = np.stack([-interaction_dir[..., 1], interaction_dir[..., 0]], axis=-1)
    return SF_FACTOR * (velocity_amount[..., None] * interaction_dir + angle_amount[..., None] * normal)


def dynamic_metrics(traj: NDArray[np.float64], tracks: PeopleTracks | None, robot_radius_m: float,
                    obstacles: BaseGeometry | None = None, intimate_level: float | None = 0.8) -> DynamicMetrics:
    """HuNavSim's metrics of the robot's ``traj`` (N, 4: t, x, y, theta) among ``tracks``."""
    t, xy, theta = traj[:, 0], traj[:, 1:3], traj[:, 3]
    n = len(t)
    dt = np.diff(t)
    step = np.hypot(*np.diff(xy, axis=0).T) if n > 1 else np.zeros(0)
    turn = np.abs(wrap_angle(np.diff(theta))) if n > 1 else np.zeros(0)
    with np.errstate(divide="ignore", invalid="ignore"):
        speed = np.where(dt > 0, step / dt, 0.0)
        omega = np.where(dt > 0, turn / dt, 0.0)
    # A trajectory of several missions has gaps (the robot was parked, nothing recorded): an interval
    # much longer than the usual sampling is not time spent standing still while navigating.
    gap = dt > GAP_FACTOR * float(np.median(dt)) if len(dt) else np.zeros(0, dtype=bool)
    still = (speed < STILL_MPS) & (omega < STILL_RADPS) & ~gap
    # The robot's velocity at each sample: toward the next one (the last repeats the one before).
    velocity = np.zeros((n, 2))
    if n > 1:
        safe = np.where(dt > 0, dt, 1.0)[:, None]
        velocity[:-1] = np.where(dt[:, None] > 0, np.diff(xy, axis=0) / safe, 0.0)
        velocity[-1] = velocity[-2]
    base = {"time_to_goal_s": float(t[-1] - t[0]), "path_length_m": float(step.sum()),
            "cumulative_heading_changes_rad": float(turn.sum()), "time_not_moving_s": float(dt[still].sum())}
    obstacle_force = np.zeros(n)
    if obstacles is not None and not obstacles.is_empty:
        clearance = shapely.distance(obstacles, shapely.points(xy)) - robot_radius_m
        obstacle_force = OBSTACLE_FACTOR * np.exp(-clearance / OBSTACLE_SIGMA_M)
    if tracks is None or not tracks.names:
        return DynamicMetrics(**base, min_distance_to_people_m=None, avg_distance_to_closest_person_m=None,
                              intimate_intrusions_percent=0.0, personal_intrusions_percent=0.0,
                              social_intrusions_percent=0.0, intrusions_per_person={},
                              group_intimate_intrusions_percent=0.0, group_personal_intrusions_percent=0.0,
                              group_social_intrusions_percent=0.0, intrusions_per_group={},
                              social_force_on_robot=0.0, social_force_on_people=0.0,
                              social_work=float(obstacle_force.sum()), robot_on_person_collisions=0,
                              person_on_robot_collisions=0, robot_intimate_entries=0)
    people = tracks.at(t)
    pxy = np.stack([people.x, people.y], axis=-1)            # (T, N, 2)
    pv = np.stack([people.vx, people.vy], axis=-1)
    centre = np.hypot(pxy[..., 0] - xy[:, None, 0], pxy[..., 1] - xy[:, None, 1])   # (T, N)
    edge = centre - robot_radius_m
    closest = np.nanmin(edge, axis=1)
    per_person = {name: _bands(edge[:, j]) for j, name in enumerate(people.names)}
    # groups: label -> members at each sample
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
            d = math.hypot(cx - xy[k, 0], cy - xy[k, 1]) - robot_radius_m
            per_group_distances.setdefault(label, []).append(d)
            group_distance[k] = d if np.isnan(group_distance[k]) else min(group_distance[k], d)
    groups = _bands(group_distance)
    per_group = {}
    for label, distances in sorted(per_group_distances.items()):
        counts = _bands(np.asarray(distances))
        per_group[label] = {band: share * len(distances) / n for band, share in counts.items()}
    # social forces
    robot_xy = np.broadcast_to(xy[:, None, :], pxy.shape)
    robot_v = np.broadcast_to(velocity[:, None, :], pv.shape)
    on_robot = np.nan_to_num(social_force(pxy, pv, robot_xy, robot_v))       # each person on the robot
    on_people = np.nan_to_num(social_force(robot_xy, robot_v, pxy, pv))      # the robot on each person
    on_robot_mod = np.hypot(on_robot[..., 0], on_robot[..., 1])
    on_people_mod = np.hypot(on_people[..., 0], on_people[..., 1])
    total_on_robot = on_robot.sum(axis=1)
    work = np.hypot(total_on_robot[:, 0], total_on_robot[:, 1]) + obstacle_force + on_people_mod.sum(axis=1)
    robot_hits, person_hits = _collisions(xy, velocity, pxy, pv, centre - robot_radius_m - PERSON_RADIUS_M)
    inside = _intimate(people, xy, intimate_level) if intimate_level is not None else np.zeros_like(centre, dtype=bool)
    entries, _ = _collisions(xy, velocity, pxy, pv, np.where(inside, -1.0, np.inf))
    shares = _bands(closest)
    return DynamicMetrics(
        **base,
        min_distance_to_people_m=float(np.nanmin(edge)),
        avg_distance_to_closest_person_m=float(np.nanmean(closest - PERSON_RADIUS_M)),
        intimate_intrusions_percent=shares["intimate"], personal_intrusions_percent=shares["personal"],
        social_intrusions_percent=shares["social"], intrusions_per_person=per_person,
        group_intimate_intrusions_percent=groups["intimate"], group_personal_intrusions_percent=groups["personal"],
        group_social_intrusions_percent=groups["social"], intrusions_per_group=per_group,
        social_force_on_robot=float(on_robot_mod.sum()), social_force_on_people=float(on_people_mod.sum()),
        social_work=float(work.sum()), robot_on_person_collisions=robot_hits, person_on_robot_collisions=person_hits,
        robot_intimate_entries=entries)


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
        for k in range(len(xy)):
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
    # a person missing at some time keeps their last known state (they were out of the file's rows)
    for key in arrays:
        values = arrays[key]
        for j in range(len(names)):
            column = values[:, j]
            known = ~np.isnan(column)
            if known.any() and not known.all():
                idx = np.where(known, np.arange(len(column)), -1)
                np.maximum.accumulate(idx, out=idx)
                first = int(np.argmax(known))
                idx[idx < 0] = first
                values[:, j] = column[idx]
    return PeopleTracks(np.asarray(times, dtype=float), names, arrays["x"], arrays["y"], arrays["theta"],
                        arrays["vx"], arrays["vy"], groups, tuple(roles[n] for n in names))
