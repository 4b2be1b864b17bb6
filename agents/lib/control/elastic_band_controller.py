"""chronav's local controller: the elastic band deformed by the laser, followed by the control law.

Why a controller object: the navigation agent drives whichever local controller a run names
(``--controller NAME``, registry group ``chronav.controllers``); this one keeps its band between
cycles, as navground's behaviours keep their own state, so the agent holds no band of its own.

Per cycle: the band (made from the path ahead after a ``reset``) follows the robot and is pushed
by the laser returns (``ControlInput.scan``, elastic_band.step); a band the map says cuts a wall
(``wall_check``, given by the agent, which has the map) is dropped for the path ahead; the
control law (control_law.BandFollower) turns it into a command within the robot's limits.
The acceleration limit starts from the robot's commanded velocity after a reset, so adopting a
new path in motion keeps the speed and a restart from rest starts from rest.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from agents.lib.control import elastic_band as eb
from agents.lib.control.control_law import BandFollower, ControlParams, DiffCommand, OmniCommand
from agents.lib.control.protocol import ControlCommand, ControlInput, FloatArray, RobotLimits

#: (band points (N, 2), robot pose) -> does the band cut a wall?  The agent's map-based check.
WallCheck = Callable[[FloatArray, tuple[float, float, float]], bool]
ESCAPE_SKIP_M = 0.5   # a band restarted off a wall skips the path this near the robot
LOOKAHEAD_M = 0.45   # carrot distance the navigation agent has always used (control_law's default 0.6)


class ElasticBandController:
    """Elastic band deformed by the laser, followed by chronav's control law (the seeds' method)."""

    #: it sees people only through the laser: the agent need not read them from the DSR each cycle
    reads_people = False

    def __init__(self, limits: RobotLimits) -> None:
        self.limits = limits
        self.band_params = eb.ElasticBandParams(robot_length_m=2 * limits.radius_m)
        params = ControlParams(max_speed_mps=limits.max_speed_mps,
                               max_angular_speed_radps=limits.max_angular_speed_radps,
                               max_accel_mps2=limits.max_accel_mps2, lookahead_m=LOOKAHEAD_M)
        self.follower = BandFollower("omni" if limits.drive == "omni" else "differential", params)
        self.band: eb.ElasticBand | None = None
        self.wall_check: WallCheck | None = None
        self._fresh = True

    def use_wall_check(self, check: WallCheck) -> None:
        """Let the agent's map judge the band (it sees walls only through the laser, and its
        contraction can slide it across a door jamb seen edge-on)."""
        self.wall_check = check

    @property
    def band_points(self) -> FloatArray | None:
        """The band as it stands, for the recording's drawing (None before the first command)."""
        return None if self.band is None else self.band.points

    def reset(self) -> None:
        self.band = None
        self._fresh = True

    def command(self, control_input: ControlInput) -> ControlCommand:
        pose = control_input.pose
        ahead = _from_robot(pose, control_input.path)
        if self._fresh:
            vx, vy, omega = control_input.velocity
            if vx == 0.0 and vy == 0.0 and omega == 0.0:
                self.follower.reset()
            self._fresh = False
        if self.band is None:
            self.band = eb.band_from_path(ahead, (), self.band_params)
        try:
            band = eb.step(self.band, control_input.scan, robot_pose=pose, params=self.band_params)
        except eb.BandInputError:
            band = self.band
        if self.wall_check is not None and self.wall_check(band.points, pose):
            # Restart from the path beyond the robot's own half metre (it may stand in an inflated
            # cell, which is why it is escaping): what the map judged free.
            band = eb.band_from_path(_from_robot(pose, _beyond(pose, control_input.path, ESCAPE_SKIP_M)), (),
                                     self.band_params)
        self.band = band
        out = self.follower.command(pose, band.points, control_input.dt_s, goal_theta=control_input.goal_theta)
        cmd = out.command
        if isinstance(cmd, DiffCommand):
            vx, vy, omega = cmd.v, 0.0, cmd.omega
        else:
            assert isinstance(cmd, OmniCommand)
            vx, vy, omega = cmd.vx, cmd.vy, cmd.omega
        return ControlCommand(vx=float(vx), vy=float(vy), omega=float(omega), reached=out.reached,
                              distance_to_goal_m=float(out.distance_to_goal_m))


def _from_robot(pose: tuple[float, float, float], path: FloatArray) -> FloatArray:
    """The path ahead starting at the robot (its first point is the robot when they coincide)."""
    robot = np.asarray([[pose[0], pose[1]]], dtype=np.float64)
    if len(path) == 0:
        return np.vstack([robot, robot])
    if float(np.hypot(*(path[0] - robot[0]))) < 1e-9:
        return np.asarray(path, dtype=np.float64)
    return np.vstack([robot, path])


def _beyond(pose: tuple[float, float, float], path: FloatArray, skip_m: float) -> FloatArray:
    """The path from its first point farther than ``skip_m`` from the robot (its goal at least)."""
    far = np.hypot(path[:, 0] - pose[0], path[:, 1] - pose[1]) > skip_m
    return path[int(np.argmax(far)):] if np.any(far) else path[-1:]
