"""Feedback control law that drives the robot along the elastic band (seed section 5.3, "Control").

Pure functions compute a command from (pose, band) so that the agent, the simulator of the gain
tuner and the tests share one law; `BandFollower` adds the only state a controller needs, the
previous command, to enforce acceleration limits between control cycles.

The law (carrot following):
* project the robot onto the band polyline and take the carrot point ``lookahead_m`` further along
  it (the goal when less band is left);
* differential drive: heading error ``alpha`` to the carrot; ``omega = heading_gain * alpha``;
  ``v = v_max * exp(-alpha^2 / (2 heading_sigma^2))``, zero when |alpha| > pi/2 (turn on the
  spot rather than drive away from the band);
* omnidirectional: the velocity points at the carrot (in the robot frame), and the robot turns
  towards the band direction (or the goal heading when given and the goal is near);
* near the goal the speed is capped by ``sqrt(2 a_max d)``, d being the band length left, so that
  the robot can stop on the goal within the acceleration limit;
* inside ``goal_tolerance_m`` of the goal the robot stops, then turns to the optional goal
  heading until within ``goal_heading_tolerance_rad``: ``reached`` is True once both hold.

Frames: the pose is (x, y, theta) in the world frame (m, m, rad); commands are in the robot frame
(x forward, y left): v, vx, vy in m/s, omega in rad/s, counter-clockwise positive.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from pydantic import BaseModel, ConfigDict, Field

from scenes.geometry import project_on_segments, wrap_angle

if TYPE_CHECKING:   # a band is given as its points or as the ElasticBand itself (`_band`)
    from agents.lib.control.elastic_band import ElasticBand

FloatArray = NDArray[np.float64]
Drive = Literal["differential", "omni"]


class ControlInputError(ValueError):
    """Bad pose, band or time step given to the controller; the message names the argument."""


class ControlParams(BaseModel):
    """Limits and gains of the band-following law."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    max_speed_mps: float = Field(0.6, gt=0.0)
    max_angular_speed_radps: float = Field(1.2, gt=0.0)
    max_accel_mps2: float = Field(0.8, gt=0.0)
    max_angular_accel_radps2: float = Field(3.0, gt=0.0)
    lookahead_m: float = Field(0.6, gt=0.0, description="carrot distance along the band")
    heading_gain: float = Field(2.0, gt=0.0, description="rad/s of omega per rad of heading error")
    heading_sigma_rad: float = Field(0.5, gt=0.0, description="speed falls as a Gaussian of heading error")
    goal_tolerance_m: float = Field(0.1, gt=0.0)
    goal_heading_tolerance_rad: float = Field(0.1, gt=0.0)


DEFAULT_CONTROL = ControlParams()


@dataclass(frozen=True)
class DiffCommand:
    """Differential-drive command: forward speed (m/s) and turn rate (rad/s)."""

    v: float
    omega: float


@dataclass(frozen=True)
class OmniCommand:
    """Omnidirectional command in the robot frame (m/s, m/s, rad/s)."""

    vx: float
    vy: float
    omega: float


Command = DiffCommand | OmniCommand


@dataclass(frozen=True)
class ControlOutput:
    command: Command
    reached: bool
    distance_to_goal_m: float


def carrot(pose: ArrayLike, band: ArrayLike | ElasticBand, lookahead_m: float) -> tuple[FloatArray, float]:
    """The point ``lookahead_m`` along the band past the robot's projection on it, and the band
    length left from that projection to the goal (m)."""
    xy = _pose(pose)[:2]
    pts = _band(band)
    seg = np.diff(pts, axis=0)
    seg_len = np.hypot(*seg.T)
    projection = project_on_segments(xy, pts[:-1], pts[1:])
    s = projection.fraction
    k = int(np.argmin(projection.distance))
    cumulative = np.concatenate([[0.0], np.cumsum(seg_len)])
    at = cumulative[k] + s[k] * seg_len[k]
    remaining = float(cumulative[-1] - at)
    target = at + lookahead_m
    if target >= cumulative[-1]:
        return pts[-1].copy(), remaining
    j = min(int(np.searchsorted(cumulative, target, side="right")) - 1, len(seg) - 1)
    frac = (target - cumulative[j]) / max(seg_len[j], 1e-18)
    return pts[j] + frac * seg[j], remaining


def differential_command(pose: ArrayLike, band: ArrayLike | ElasticBand, params: ControlParams = DEFAULT_CONTROL,
                         goal_theta: float | None = None) -> ControlOutput:
    """(v, omega) that follows the band, within the speed limits (acceleration: `BandFollower`)."""
    x, y, theta = _pose(pose)
    pts = _band(band)
    distance = float(np.hypot(*(pts[-1] - (x, y))))
    if distance <= params.goal_tolerance_m:
        omega, done = _final_turn(theta, goal_theta, params)
        return ControlOutput(DiffCommand(0.0, omega), done, distance)
    target, remaining = carrot((x, y, theta), pts, params.lookahead_m)
    alpha = wrap_angle(math.atan2(target[1] - y, target[0] - x) - theta)
    omega = clip(params.heading_gain * alpha, params.max_angular_speed_radps)
    v = 0.0
    if abs(alpha) <= math.pi / 2:
        v = params.max_speed_mps * math.exp(-alpha ** 2 / (2.0 * params.heading_sigma_rad ** 2))
        v = min(v, _stopping_speed(max(remaining, distance), params))
    return ControlOutput(DiffCommand(v, omega), False, distance)


def omni_command(pose: ArrayLike, band: ArrayLike | ElasticBand, params: ControlParams = DEFAULT_CONTROL,
                 goal_theta: float | None = None) -> ControlOutput:
    """(vx, vy, omega) in the robot frame that follows the band, within the speed limits."""
    x, y, theta = _pose(pose)
    pts = _band(band)
    distance = float(np.hypot(*(pts[-1] - (x, y))))
    if distance <= params.goal_tolerance_m:
        omega, done = _final_turn(theta, goal_theta, params)
        return ControlOutput(OmniCommand(0.0, 0.0, omega), done, distance)
    target, remaining = carrot((x, y, theta), pts, params.lookahead_m)
    direction = np.asarray(target) - (x, y)
    norm = float(np.hypot(*direction))
    speed = min(params.max_speed_mps, _stopping_speed(max(remaining, distance), params))
    world_v = direction / norm * speed if norm > 1e-9 else np.zeros(2)
    c, s = math.cos(theta), math.sin(theta)
    vx, vy = c * world_v[0] + s * world_v[1], -s * world_v[0] + c * world_v[1]
    wanted = math.atan2(direction[1], direction[0]) if norm > 1e-9 else theta
    if goal_theta is not None and remaining <= params.lookahead_m:
        wanted = goal_theta
    omega = clip(params.heading_gain * wrap_angle(wanted - theta), params.max_angular_speed_radps)
    return ControlOutput(OmniCommand(vx, vy, omega), False, distance)


def limit_acceleration(previous: Command, wanted: Command, dt_s: float,
                       params: ControlParams = DEFAULT_CONTROL) -> Command:
    """The command closest to ``wanted`` reachable from ``previous`` in ``dt_s`` under the linear
    (vector norm for omni) and angular acceleration limits."""
    if dt_s <= 0.0 or not math.isfinite(dt_s):
        raise ControlInputError(f"dt_s: must be a positive finite time step, got {dt_s}")
    max_dv = params.max_accel_mps2 * dt_s
    max_dw = params.max_angular_accel_radps2 * dt_s
    omega = previous.omega + clip(wanted.omega - previous.omega, max_dw)
    if isinstance(wanted, DiffCommand) and isinstance(previous, DiffCommand):
        return DiffCommand(previous.v + clip(wanted.v - previous.v, max_dv), omega)
    if isinstance(wanted, OmniCommand) and isinstance(previous, OmniCommand):
        dvx, dvy = wanted.vx - previous.vx, wanted.vy - previous.vy
        norm = math.hypot(dvx, dvy)
        scale = 1.0 if norm <= max_dv else max_dv / norm
        return OmniCommand(previous.vx + dvx * scale, previous.vy + dvy * scale, omega)
    raise ControlInputError(f"previous and wanted commands differ in kind: "
                            f"{type(previous).__name__} vs {type(wanted).__name__}")


class BandFollower:
    """Stateful controller: the pure law plus acceleration limiting against the last command."""

    def __init__(self, drive: Drive = "differential", params: ControlParams = DEFAULT_CONTROL) -> None:
        if drive not in ("differential", "omni"):
            raise ControlInputError(f"drive: expected 'differential' or 'omni', got {drive!r}")
        self.drive: Drive = drive
        self.params = params
        self._last: Command = self._stopped()

    @property
    def last_command(self) -> Command:
        return self._last

    def reset(self, command: Command | None = None) -> None:
        """Forget the previous command (e.g. after an emergency stop): assume ``command`` or rest."""
        self._last = command if command is not None else self._stopped()

    def command(self, pose: ArrayLike, band: ArrayLike | ElasticBand, dt_s: float,
                goal_theta: float | None = None) -> ControlOutput:
        law = differential_command if self.drive == "differential" else omni_command
        out = law(pose, band, self.params, goal_theta)
        limited = limit_acceleration(self._last, out.command, dt_s, self.params)
        self._last = limited
        return ControlOutput(limited, out.reached and _is_stopped(limited), out.distance_to_goal_m)

    def _stopped(self) -> Command:
        return DiffCommand(0.0, 0.0) if self.drive == "differential" else OmniCommand(0.0, 0.0, 0.0)


def integrate(pose: ArrayLike, command: Command, dt_s: float) -> tuple[float, float, float]:
    """Exact pose after holding a robot-frame command for ``dt_s`` (constant-twist motion)."""
    x, y, theta = _pose(pose)
    vx, vy = (command.v, 0.0) if isinstance(command, DiffCommand) else (command.vx, command.vy)
    w = command.omega
    dtheta = w * dt_s
    if abs(dtheta) < 1e-9:
        bx, by = vx * dt_s, vy * dt_s
    else:
        sin_d, cos_d = math.sin(dtheta), math.cos(dtheta)
        bx = (vx * sin_d - vy * (1.0 - cos_d)) / w
        by = (vx * (1.0 - cos_d) + vy * sin_d) / w
    c, s = math.cos(theta), math.sin(theta)
    return x + c * bx - s * by, y + s * bx + c * by, wrap_angle(theta + dtheta)


def _final_turn(theta: float, goal_theta: float | None, params: ControlParams) -> tuple[float, bool]:
    return final_turn(theta, goal_theta, params.goal_heading_tolerance_rad, params.heading_gain,
                      params.max_angular_speed_radps)


def final_turn(theta: float, goal_theta: float | None, heading_tolerance_rad: float, heading_gain: float,
               max_angular_speed_radps: float) -> tuple[float, bool]:
    """On the goal: (omega, done), turning towards ``goal_theta`` until within the tolerance
    (done at once without one). Shared by every controller that arrives the way chronav's law does."""
    if goal_theta is None:
        return 0.0, True
    error = wrap_angle(goal_theta - theta)
    if abs(error) <= heading_tolerance_rad:
        return 0.0, True
    return clip(heading_gain * error, max_angular_speed_radps), False


def _stopping_speed(distance_m: float, params: ControlParams) -> float:
    return stopping_speed(distance_m, params.goal_tolerance_m, params.max_accel_mps2)


def stopping_speed(distance_m: float, goal_tolerance_m: float, max_accel_mps2: float) -> float:
    """The speed from which braking at ``max_accel_mps2`` stops inside the goal tolerance."""
    return math.sqrt(2.0 * max_accel_mps2 * max(distance_m - goal_tolerance_m / 2, 0.0))


def _is_stopped(command: Command) -> bool:
    values = (command.v, command.omega) if isinstance(command, DiffCommand) else (
        command.vx, command.vy, command.omega)
    return all(abs(v) < 1e-9 for v in values)


def clip(value: float, limit: float) -> float:
    """``value`` within +-``limit``."""
    return max(-limit, min(limit, value))


def _pose(pose: ArrayLike) -> tuple[float, float, float]:
    arr = np.asarray(pose, dtype=np.float64).ravel()
    if arr.size != 3 or not np.all(np.isfinite(arr)):
        raise ControlInputError(f"pose: expected finite (x, y, theta), got {arr.tolist()}")
    return float(arr[0]), float(arr[1]), float(arr[2])


def _band(band: ArrayLike | ElasticBand) -> FloatArray:
    pts = np.asarray(getattr(band, "points", band), dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 2 or len(pts) < 1 or not np.all(np.isfinite(pts)):
        raise ControlInputError(f"band: expected finite points of shape (N >= 1, 2), got {pts.shape}")
    if len(pts) == 1:
        pts = np.vstack([pts, pts])
    return pts
