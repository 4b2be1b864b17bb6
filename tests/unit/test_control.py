"""Band-following control law: geometry by hand, limits, goal handling, closed loop on a band."""

from __future__ import annotations

import math

import numpy as np
import pytest

from agents.lib.control.control_law import (
    BandFollower,
    ControlInputError,
    ControlParams,
    DiffCommand,
    OmniCommand,
    carrot,
    differential_command,
    integrate,
    limit_acceleration,
    omni_command,
    wrap_angle,
)
from agents.lib.control.elastic_band import band_from_path, step

PARAMS = ControlParams()
STRAIGHT = np.array([[0.0, 0.0], [5.0, 0.0]])


def test_carrot_is_lookahead_along_the_band_from_the_projection() -> None:
    band = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0]])
    point, remaining = carrot((1.0, 0.3, 0.0), band, 0.6)
    np.testing.assert_allclose(point, [1.6, 0.0])
    assert remaining == pytest.approx(3.0)
    point, remaining = carrot((1.8, -0.2, 0.0), band, 0.6)
    np.testing.assert_allclose(point, [2.0, 0.4])  # wraps round the corner
    assert remaining == pytest.approx(2.2)
    point, _ = carrot((2.1, 1.9, 0.0), band, 0.6)
    np.testing.assert_allclose(point, [2.0, 2.0])  # never past the goal


def test_differential_drives_straight_at_full_speed_on_a_straight_band() -> None:
    out = differential_command((0.0, 0.0, 0.0), STRAIGHT, PARAMS)
    assert out.command == DiffCommand(PARAMS.max_speed_mps, 0.0)
    assert not out.reached and out.distance_to_goal_m == pytest.approx(5.0)


def test_differential_turns_towards_the_band_and_respects_limits() -> None:
    # Band straight ahead to the left: carrot at (0, 0.6): heading error +pi/2.
    band = np.array([[0.0, 0.0], [0.0, 5.0]])
    out = differential_command((0.0, 0.0, 0.0), band, PARAMS)
    assert out.command.omega == pytest.approx(PARAMS.max_angular_speed_radps)  # 2 * pi/2 clipped
    gaussian = math.exp(-(math.pi / 2) ** 2 / (2 * 0.5 ** 2))
    assert out.command.v == pytest.approx(PARAMS.max_speed_mps * gaussian)
    # Band behind: turn on the spot, never drive away from it.
    behind = differential_command((0.0, 0.0, 0.0), np.array([[0.0, 0.0], [-5.0, 0.1]]), PARAMS)
    assert behind.command.v == 0.0 and abs(behind.command.omega) == pytest.approx(1.2)
    # Small error: proportional.
    small = differential_command((0.0, 0.0, 0.1), STRAIGHT, PARAMS)
    assert small.command.omega == pytest.approx(-0.2)


def test_speed_is_capped_to_stop_on_the_goal() -> None:
    out = differential_command((4.8, 0.0, 0.0), STRAIGHT, PARAMS)
    assert out.command.v == pytest.approx(math.sqrt(2 * PARAMS.max_accel_mps2 * (0.2 - 0.05)))
    assert out.command.v < PARAMS.max_speed_mps


def test_goal_tolerance_and_final_heading() -> None:
    out = differential_command((4.95, 0.0, 0.0), STRAIGHT, PARAMS)
    assert out.reached and out.command == DiffCommand(0.0, 0.0)
    turning = differential_command((4.95, 0.0, 0.0), STRAIGHT, PARAMS, goal_theta=math.pi / 2)
    assert not turning.reached
    assert turning.command == DiffCommand(0.0, PARAMS.max_angular_speed_radps)
    done = differential_command((4.95, 0.0, 1.55), STRAIGHT, PARAMS, goal_theta=math.pi / 2)
    assert done.reached


def test_omni_strafes_in_the_robot_frame() -> None:
    """Robot facing +y, band along +x: the velocity is -y in the robot frame, and it turns to the
    band direction (-pi/2 error -> omega clipped to -1.2)."""
    out = omni_command((0.0, 0.0, math.pi / 2), STRAIGHT, PARAMS)
    assert isinstance(out.command, OmniCommand)
    assert out.command.vx == pytest.approx(0.0, abs=1e-12)
    assert out.command.vy == pytest.approx(-PARAMS.max_speed_mps)
    assert out.command.omega == pytest.approx(-PARAMS.max_angular_speed_radps)
    assert math.hypot(out.command.vx, out.command.vy) <= PARAMS.max_speed_mps + 1e-12


def test_omni_faces_the_goal_heading_near_the_end() -> None:
    out = omni_command((4.6, 0.0, 0.0), STRAIGHT, PARAMS, goal_theta=0.5)
    assert out.command.omega == pytest.approx(1.0)
    assert out.command.vx > 0.0 and out.command.vy == pytest.approx(0.0, abs=1e-12)


def test_acceleration_limits() -> None:
    ramp = limit_acceleration(DiffCommand(0.0, 0.0), DiffCommand(1.0, 2.0), 0.1, PARAMS)
    assert ramp == DiffCommand(pytest.approx(0.08), pytest.approx(0.3))
    brake = limit_acceleration(DiffCommand(0.5, 0.0), DiffCommand(0.0, 0.0), 0.1, PARAMS)
    assert brake.v == pytest.approx(0.42)
    omni = limit_acceleration(OmniCommand(0.0, 0.0, 0.0), OmniCommand(0.6, 0.8, 0.0), 0.1, PARAMS)
    assert (omni.vx, omni.vy) == (pytest.approx(0.048), pytest.approx(0.064))  # norm 0.08, same direction
    with pytest.raises(ControlInputError, match="dt_s"):
        limit_acceleration(DiffCommand(0.0, 0.0), DiffCommand(1.0, 0.0), 0.0, PARAMS)
    with pytest.raises(ControlInputError, match="differ in kind"):
        limit_acceleration(DiffCommand(0.0, 0.0), OmniCommand(1.0, 0.0, 0.0), 0.1, PARAMS)


def test_follower_ramps_up_linearly_and_reports_its_state() -> None:
    follower = BandFollower("differential", PARAMS)
    speeds = [follower.command((0.0, 0.0, 0.0), STRAIGHT, 0.1).command.v for _ in range(5)]
    np.testing.assert_allclose(speeds, [0.08, 0.16, 0.24, 0.32, 0.40])
    follower.reset()
    assert follower.last_command == DiffCommand(0.0, 0.0)
    with pytest.raises(ControlInputError, match="drive"):
        BandFollower("tracked")  # type: ignore[arg-type]


def test_integrate_exact_arcs() -> None:
    assert integrate((0.0, 0.0, 0.0), DiffCommand(1.0, 0.0), 2.0) == pytest.approx((2.0, 0.0, 0.0))
    x, y, th = integrate((0.0, 0.0, 0.0), DiffCommand(1.0, math.pi / 2), 1.0)
    assert (x, y, th) == pytest.approx((2 / math.pi, 2 / math.pi, math.pi / 2))
    # Omni strafing left while facing +y moves towards -x in the world.
    assert integrate((0.0, 0.0, math.pi / 2), OmniCommand(0.0, 1.0, 0.0), 1.0) == pytest.approx(
        (-1.0, 0.0, math.pi / 2))
    assert wrap_angle(3 * math.pi / 2) == pytest.approx(-math.pi / 2)


@pytest.mark.parametrize("drive", ["differential", "omni"])
def test_closed_loop_follows_an_l_shaped_band_to_the_goal(drive: str) -> None:
    band = band_from_path([[0.0, 0.0], [3.0, 0.0], [3.0, 3.0]], ())
    follower = BandFollower(drive, PARAMS)  # type: ignore[arg-type]
    pose = (0.0, 0.0, 0.0)
    dt = 0.1
    previous = follower.last_command
    for _ in range(400):
        band = step(band, (), pose)
        out = follower.command(pose, band, dt, goal_theta=math.pi / 2)
        cmd = out.command
        if isinstance(cmd, DiffCommand):
            assert abs(cmd.v) <= PARAMS.max_speed_mps + 1e-9
            assert abs(cmd.v - previous.v) <= PARAMS.max_accel_mps2 * dt + 1e-9
        else:
            assert math.hypot(cmd.vx, cmd.vy) <= PARAMS.max_speed_mps + 1e-9
        assert abs(cmd.omega) <= PARAMS.max_angular_speed_radps + 1e-9
        assert abs(cmd.omega - previous.omega) <= PARAMS.max_angular_accel_radps2 * dt + 1e-9
        previous = cmd
        if out.reached:
            break
        pose = integrate(pose, cmd, dt)
    assert out.reached
    assert math.hypot(pose[0] - 3.0, pose[1] - 3.0) <= PARAMS.goal_tolerance_m
    assert abs(wrap_angle(pose[2] - math.pi / 2)) <= PARAMS.goal_heading_tolerance_rad


@pytest.mark.parametrize(("call", "fragment"), [
    (lambda: differential_command((0.0, 0.0), STRAIGHT), "pose"),
    (lambda: differential_command((0.0, np.nan, 0.0), STRAIGHT), "pose"),
    (lambda: omni_command((0.0, 0.0, 0.0), np.zeros((0, 2))), "band"),
    (lambda: omni_command((0.0, 0.0, 0.0), [[0.0, np.inf]]), "band"),
])
def test_bad_input_names_the_argument(call, fragment: str) -> None:
    with pytest.raises(ControlInputError, match=fragment):
        call()
