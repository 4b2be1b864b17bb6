"""A local controller: pure pursuit of a point 0.6 m ahead on the path, slowing near people.

Implements chronav's LocalController protocol (agents/lib/control/protocol.py): built by
``PurePursuit(limits)``, ``reset()`` on a new path, ``command(ControlInput) -> ControlCommand``
in the robot frame (m/s, rad/s).  It must answer finite numbers: chronav refuses anything else.
"""

from __future__ import annotations

import math

import numpy as np

from agents.lib.control.protocol import ControlCommand, ControlInput, RobotLimits

LOOKAHEAD_M = 0.6
GOAL_TOLERANCE_M = 0.15
SLOW_NEAR_PERSON_M = 1.0   # below this distance to anyone, the speed falls linearly to a fifth


class PurePursuit:
    """Pure pursuit 0.6 m ahead on the path, slower within 1 m of a person."""

    def __init__(self, limits: RobotLimits) -> None:
        self.limits = limits

    def reset(self) -> None:
        pass    # nothing carried between paths

    def command(self, control_input: ControlInput) -> ControlCommand:
        x, y, theta = control_input.pose
        path = control_input.path
        goal = path[-1]
        left = float(np.hypot(*(goal - (x, y))))
        if left < GOAL_TOLERANCE_M:
            return ControlCommand(vx=0.0, vy=0.0, omega=0.0, reached=True, distance_to_goal_m=left)
        ahead = np.hypot(path[:, 0] - x, path[:, 1] - y) >= LOOKAHEAD_M
        target = path[int(np.argmax(ahead))] if np.any(ahead) else goal
        heading = math.atan2(target[1] - y, target[0] - x)
        error = math.atan2(math.sin(heading - theta), math.cos(heading - theta))
        speed = self.limits.max_speed_mps * max(0.0, math.cos(error)) * min(1.0, left / 0.5)
        people = control_input.people
        if len(people):
            nearest = float(np.min(np.hypot(people[:, 0] - x, people[:, 1] - y) - people[:, 4]))
            speed *= min(1.0, max(0.2, nearest / SLOW_NEAR_PERSON_M))
        omega = max(-self.limits.max_angular_speed_radps, min(self.limits.max_angular_speed_radps, 2.0 * error))
        return ControlCommand(vx=speed, vy=0.0, omega=omega, reached=False, distance_to_goal_m=left)
