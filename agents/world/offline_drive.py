"""``chronav path --controller NAME``: drive a local controller along a planned path, offline.

Why: a researcher checking a controller wants to see it follow chronav's path before a full run.
This is cheap (no agents, no Zenoh): the controller gets the ControlInput the navigation agent
gives it (the path ahead, the people of the map's time with their velocities, the walls and
object footprints as segments) and its command is integrated exactly (control_law.integrate)
every ``DRIVE_DT_S``.  Two simplifications: the "laser scan" is the walls' and footprints' points
within the laser's range, 5 cm apart, without occlusion (what pushes the elastic band off
walls), and the people stand where the map has them.  A check of the controller on the path,
not a simulation of the day (``chronav launch --controller`` is that).  The path's metrics (Psi,
d_min) are measured on the driven trajectory too (agents/world/offline.py).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from agents.lib.control import controllers
from agents.lib.control.control_law import DiffCommand, OmniCommand, integrate
from agents.lib.control.protocol import ControlInput, RobotLimits
from agents.lib.socialmap.social_map import SocialMap
from agents.world.control_view import obstacle_segments, segment_points
from agents.world.navigation import NavigationMaps

DRIVE_DT_S = 0.1
SCAN_SPACING_M = 0.05
TIME_FACTOR = 4.0     # the drive gives up after this x the path's time at cruise speed (plus a minute)


@dataclass(frozen=True)
class Drive:
    """What the controller did: trajectory rows t, x, y, theta (s, m, m, rad), whether it
    reached the goal, and the refusal (plug-in, package, reason) if it was refused."""

    trajectory: np.ndarray
    reached: bool
    refused: str | None

    def as_dict(self) -> dict[str, object]:
        t = self.trajectory
        length = float(np.hypot(*np.diff(t[:, 1:3], axis=0).T).sum()) if len(t) > 1 else 0.0
        return {"reached": self.reached, "refused": self.refused, "time_s": float(t[-1, 0] - t[0, 0]),
                "length_m": length, "points": t[:, 1:3].round(3).tolist()}


def limits_of(nav: NavigationMaps) -> RobotLimits:
    robot = nav.scene.robot
    return RobotLimits(radius_m=robot.radius, max_speed_mps=robot.max_speed,
                       max_angular_speed_radps=robot.max_angular_speed, max_accel_mps2=robot.max_acceleration,
                       drive="omni" if robot.kinematics == "omnidirectional" else "differential")


def drive(name: str, nav: NavigationMaps, smap: SocialMap, path: np.ndarray, t_s: float,
          goal_theta: float | None = None) -> Drive:
    """Drive controller ``name`` from the path's start along ``path`` on the map ``smap`` of ``t_s``."""
    limits = limits_of(nav)
    chosen = controllers.controller(name, limits)
    chosen.reset()
    people = np.asarray([[p.x, p.y, p.vx, p.vy, smap.params.grid.person_radius_m] for p in smap.people],
                        dtype=np.float64).reshape(-1, 5)
    obstacles = obstacle_segments(nav.scene, nav.walls_of_scene())
    wall_points = segment_points(obstacles, SCAN_SPACING_M)
    reach = nav.scene.robot.laser_range
    first = path[1] - path[0] if len(path) > 1 else np.zeros(2)
    pose = (float(path[0, 0]), float(path[0, 1]), math.atan2(float(first[1]), float(first[0])))
    length = float(np.hypot(*np.diff(path, axis=0).T).sum())
    steps = int((TIME_FACTOR * length / nav.cruise_speed_mps + 60.0) / DRIVE_DT_S)
    rows = [(t_s, *pose)]
    velocity = (0.0, 0.0, 0.0)
    for k in range(steps):
        nearest = int(np.argmin(np.hypot(path[:, 0] - pose[0], path[:, 1] - pose[1])))
        ahead = path[nearest:] if len(path) - nearest >= 2 else path[-2:]
        control_input = ControlInput(pose=pose, velocity=velocity, path=ahead, goal_theta=goal_theta, limits=limits,
                                     dt_s=DRIVE_DT_S, now_s=t_s + k * DRIVE_DT_S, people=people, obstacles=obstacles,
                                     scan=wall_points[np.hypot(wall_points[:, 0] - pose[0],
                                                               wall_points[:, 1] - pose[1]) < reach])
        try:
            out = controllers.command(chosen, name, control_input)
        except controllers.ControllerFailed as exc:
            return Drive(np.asarray(rows), False, str(exc))
        if out.reached:
            return Drive(np.asarray(rows), True, None)
        command = DiffCommand(out.vx, out.omega) if limits.drive == "differential" else \
            OmniCommand(out.vx, out.vy, out.omega)
        pose = integrate(pose, command, DRIVE_DT_S)
        velocity = (out.vx, out.vy if limits.drive == "omni" else 0.0, out.omega)
        rows.append((t_s + (k + 1) * DRIVE_DT_S, *pose))
    return Drive(np.asarray(rows), False, None)
