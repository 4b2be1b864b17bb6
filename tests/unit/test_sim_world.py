"""The simulated world's physics: kinematics, command limits and the laser."""

from __future__ import annotations

import math

import numpy as np
import pytest

from agents.sim_robot.kinematics import Limits, Velocity, integrate, limit_command
from agents.sim_robot.laser import PERSON_RADIUS_M, Laser, polyline_segments

LIMITS = Limits(max_speed=0.6, max_angular_speed=1.0, max_acceleration=0.5)


def test_straight_and_arc_integration_are_exact() -> None:
    assert integrate(0, 0, 0, Velocity(1.0, 0, 0), 2.0) == pytest.approx((2.0, 0.0, 0.0))
    # Quarter circle of radius 1: v = 1, omega = 1 for pi/2 seconds ends at (1, 1) facing +y.
    x, y, theta = integrate(0, 0, 0, Velocity(1.0, 0, 1.0), math.pi / 2)
    assert (x, y, theta) == pytest.approx((1.0, 1.0, math.pi / 2))
    # Omnidirectional strafe left while facing +y moves along -x.
    assert integrate(0, 0, math.pi / 2, Velocity(0, 1.0, 0), 1.0)[:2] == pytest.approx((-1.0, 0.0))


def test_limits_saturate_and_rate_limit() -> None:
    cmd = limit_command(Velocity(5.0, 0, 9.0), Velocity(), dt=0.1, limits=LIMITS, omni=False)
    assert cmd.vx == pytest.approx(0.05) and cmd.omega == pytest.approx(1.0)
    assert limit_command(Velocity(0, 0.5, 0), Velocity(), 10.0, LIMITS, omni=False).vy == 0.0
    omni = limit_command(Velocity(0.6, 0.6, 0), Velocity(0.6, 0.6, 0), 0.1, LIMITS, omni=True)
    assert math.hypot(omni.vx, omni.vy) == pytest.approx(0.6)


def test_laser_hits_walls_and_people() -> None:
    walls = polyline_segments([[[-5, -5], [5, -5], [5, 5], [-5, 5], [-5, -5]]])
    laser = Laser(walls, n_rays=3, max_range=20.0, fov=math.pi / 2)  # rays at -45, 0, +45 degrees
    ranges = laser.scan(0, 0, 0, np.empty((0, 2)))
    assert ranges == pytest.approx([5 * math.sqrt(2), 5.0, 5 * math.sqrt(2)])
    with_person = laser.scan(0, 0, 0, np.array([[2.0, 0.0]]))
    assert with_person[1] == pytest.approx(2.0 - PERSON_RADIUS_M)
    points = laser.points(0, 0, 0, with_person)
    assert points[1] == pytest.approx([2.0 - PERSON_RADIUS_M, 0.0])


def test_laser_reports_max_range_in_the_open() -> None:
    laser = Laser(np.empty((0, 4)), n_rays=5, max_range=4.0)
    assert np.all(laser.scan(0, 0, 1.0, np.empty((0, 2))) == 4.0)
    assert len(laser.points(0, 0, 0, laser.scan(0, 0, 0, np.empty((0, 2))))) == 0
