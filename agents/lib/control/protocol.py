"""The local controller interface: one cycle in, one velocity command out.

Why a protocol and plain data: chronav's elastic band, navground's behaviours and a researcher's
own controller must be interchangeable behind ``--controller NAME`` without the navigation agent
knowing which it drives, and each must be testable offline with numpy arrays alone.

Frames and units (the same as the rest of chronav):
* world frame = the scene's map frame, x and y in metres, angles in radians, counter-clockwise;
* the command is in the robot frame (x forward, y left), m/s and rad/s.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal, Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
Drive = Literal["differential", "omni"]


def _empty(columns: int) -> FloatArray:
    return np.zeros((0, columns), dtype=np.float64)


@dataclass(frozen=True)
class RobotLimits:
    """The robot's body and limits, from the scene."""

    radius_m: float
    max_speed_mps: float
    max_angular_speed_radps: float
    max_accel_mps2: float = 0.8
    drive: Drive = "differential"


@dataclass(frozen=True)
class ControlInput:
    """Everything a local controller may look at in one control cycle.

    pose:        robot (x, y, theta) in the world frame (m, m, rad).
    velocity:    robot's current command (vx, vy, omega) in the robot frame (m/s, m/s, rad/s).
    path:        (N, 2) the global path still ahead, world frame, metres; path[-1] is the goal.
    goal_theta:  heading to end at (rad, world frame), or None for any heading.
    people:      (K, 5) tracked people: x, y, vx, vy (world frame, m and m/s), radius (m).
    obstacles:   (M, 4) static line segments x1, y1, x2, y2 (world frame, m): walls and object
                 footprints' edges.
    scan:        (L, 2) laser returns in the world frame (m), possibly empty.
    dt_s:        control period (s).
    now_s:       scene clock (s since midnight of the scene's date).
    """

    pose: tuple[float, float, float]
    velocity: tuple[float, float, float]
    path: FloatArray
    goal_theta: float | None
    limits: RobotLimits
    dt_s: float
    now_s: float = 0.0
    people: FloatArray = field(default_factory=lambda: _empty(5))
    obstacles: FloatArray = field(default_factory=lambda: _empty(4))
    scan: FloatArray = field(default_factory=lambda: _empty(2))


@dataclass(frozen=True)
class ControlCommand:
    """One cycle's answer.

    vx, vy, omega: robot frame (m/s, m/s, rad/s); a differential robot's vy is 0.
    reached:       the goal (and goal_theta, when given) is reached: the mission step is done.
    distance_to_goal_m: what is left along the path (m), for progress and logs.
    """

    vx: float
    vy: float
    omega: float
    reached: bool
    distance_to_goal_m: float


@runtime_checkable
class LocalController(Protocol):
    """A stateful local controller; one instance drives one robot through one mission step.

    ``reset`` is called when a new path is adopted or after an emergency stop; ``command`` once
    per control cycle.  It must return finite numbers: the navigation agent refuses anything else,
    stops the robot and fails the mission naming the controller.
    """

    def reset(self) -> None: ...

    def command(self, control_input: ControlInput) -> ControlCommand: ...
