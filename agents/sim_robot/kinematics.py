"""Robot kinematics for the simulator: differential drive and omnidirectional bases.

Why here and not in social_navigation: this is the *world's* physics (what the wheels do with a
command), kept apart from the controller that decides the command, so a controller bug can never
be hidden by a simulator that "helps".
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from scenes.angles import wrap_angle


@dataclass(frozen=True)
class Velocity:
    """Body-frame command: vx forward, vy left (omnidirectional only), omega counter-clockwise."""

    vx: float = 0.0
    vy: float = 0.0
    omega: float = 0.0


@dataclass(frozen=True)
class Limits:
    max_speed: float
    max_angular_speed: float
    max_acceleration: float


def _clamp(value: float, bound: float) -> float:
    return max(-bound, min(bound, value))


def limit_command(cmd: Velocity, previous: Velocity, dt: float, limits: Limits, omni: bool) -> Velocity:
    """What the motor controllers actually deliver: saturation plus acceleration limits."""
    vx, vy = _saturate(cmd.vx, cmd.vy if omni else 0.0, limits.max_speed)
    step = limits.max_acceleration * dt
    vx = previous.vx + _clamp(vx - previous.vx, step)
    vy = previous.vy + _clamp(vy - previous.vy, step)
    vx, vy = _saturate(vx, vy, limits.max_speed)  # a too-fast previous velocity must not persist
    omega = _clamp(cmd.omega, limits.max_angular_speed)
    return Velocity(vx, vy, omega)


def _saturate(vx: float, vy: float, max_speed: float) -> tuple[float, float]:
    speed = math.hypot(vx, vy)
    if speed > max_speed:
        return vx * max_speed / speed, vy * max_speed / speed
    return vx, vy


def integrate(x: float, y: float, theta: float, vel: Velocity, dt: float) -> tuple[float, float, float]:
    """Exact integration of a constant body twist over dt (arc, not Euler: no drift on turns)."""
    cos_t, sin_t = math.cos(theta), math.sin(theta)
    if abs(vel.omega) < 1e-9:
        dx_body, dy_body = vel.vx * dt, vel.vy * dt
    else:
        s, c = math.sin(vel.omega * dt), math.cos(vel.omega * dt)
        dx_body = (vel.vx * s - vel.vy * (1 - c)) / vel.omega
        dy_body = (vel.vx * (1 - c) + vel.vy * s) / vel.omega
    new_theta = wrap_angle(theta + vel.omega * dt)
    return (x + cos_t * dx_body - sin_t * dy_body, y + sin_t * dx_body + cos_t * dy_body, new_theta)
