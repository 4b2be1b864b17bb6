"""Elastic band (seed Eqs. 13-16): forces by hand, spacing invariants, relaxation, robot following."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from agents.lib.control.elastic_band import (
    BandInputError,
    ElasticBand,
    ElasticBandParams,
    ObstacleField,
    band_from_path,
    contraction_forces,
    distance_gradient,
    forces,
    is_connected,
    relax,
    repulsion_forces,
    resample,
    step,
)

PARAMS = ElasticBandParams()  # 0.5 m robot: spacing 0.25 m, gain unit 0.5 mm


def disc(cx: float, cy: float, r: float, n: int = 72) -> np.ndarray:
    """Laser points on a circle: what a range sensor returns around a post or a person."""
    a = np.linspace(0.0, 2 * math.pi, n, endpoint=False)
    return np.column_stack([cx + r * np.cos(a), cy + r * np.sin(a)])


def test_gain_units_follow_the_robot_length() -> None:
    assert PARAMS.k_c == 120.0 and PARAMS.k_r == 60.0
    assert PARAMS.gain_unit_m == pytest.approx(0.5e-3)
    assert ElasticBandParams(robot_length_m=1.0).gain_unit_m == pytest.approx(1e-3)  # the seed's mm
    assert PARAMS.spacing_m == pytest.approx(0.25)
    assert PARAMS.min_spacing_m == pytest.approx(0.125)


def test_contraction_eq13_by_hand() -> None:
    """(0,0), (1,1), (2,0): unit vectors (-1,-1)/sqrt2 and (1,-1)/sqrt2 sum to (0, -sqrt2)."""
    pts = np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 0.0]])
    f = contraction_forces(pts, PARAMS)
    np.testing.assert_allclose(f[1], [0.0, -math.sqrt(2) * 120 * 0.5e-3])
    np.testing.assert_array_equal(f[[0, 2]], 0.0)  # endpoints are fixed
    aligned = np.array([[0.0, 0.0], [0.3, 0.0], [2.0, 0.0]])
    np.testing.assert_allclose(contraction_forces(aligned, PARAMS), 0.0, atol=1e-15)


def test_repulsion_eq14_15_by_hand() -> None:
    """One obstacle point at the origin, band point at (0.5, 0): D = 0.5, grad D = (1, 0),
    f_r = k_r * g * (D0 - D) = 60 * 0.5e-3 * 0.5 = 0.015 m away from the obstacle."""
    field = ObstacleField(np.array([[0.0, 0.0]]), PARAMS.max_radius_m)
    pts = np.array([[0.5, -3.0], [0.5, 0.0], [0.5, 3.0]])
    np.testing.assert_allclose(distance_gradient(pts[1:2], field, 0.02), [[1.0, 0.0]], atol=1e-9)
    f = repulsion_forces(pts, field, PARAMS)
    np.testing.assert_allclose(f[1], [0.015, 0.0], atol=1e-9)
    np.testing.assert_array_equal(f[[0, 2]], 0.0)
    # Beyond D0 = 1 m nothing happens.
    far = np.array([[1.5, -3.0], [1.5, 0.0], [1.5, 3.0]])
    np.testing.assert_array_equal(repulsion_forces(far, field, PARAMS), 0.0)


def test_bubble_radii_and_fallback() -> None:
    band = band_from_path([[0.0, 0.0], [2.0, 0.0]], [[1.0, 0.6]], PARAMS)
    expected = np.hypot(band.points[:, 0] - 1.0, band.points[:, 1] - 0.6)
    np.testing.assert_allclose(band.radii, np.minimum(expected, PARAMS.max_radius_m))
    assert band.radii.min() == pytest.approx(0.6)
    empty = band_from_path([[0.0, 0.0], [2.0, 0.0]], np.zeros((0, 2)), PARAMS)
    np.testing.assert_array_equal(empty.radii, PARAMS.max_radius_m)
    far = band_from_path([[0.0, 0.0], [2.0, 0.0]], [[100.0, 0.0]], PARAMS)
    np.testing.assert_array_equal(far.radii, PARAMS.max_radius_m)  # beyond the sensor range


def test_band_from_path_spacing_is_about_half_the_robot_length() -> None:
    band = band_from_path([[0.0, 0.0], [10.0, 0.0], [10.0, 0.1], [10.0, 3.0]], (), PARAMS)
    gaps = np.hypot(*np.diff(band.points, axis=0).T)
    assert gaps.max() <= PARAMS.spacing_m + 1e-9
    assert gaps.min() >= PARAMS.min_spacing_m - 1e-9
    np.testing.assert_array_equal(band.points[0], [0.0, 0.0])
    np.testing.assert_array_equal(band.points[-1], [10.0, 3.0])


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.floats(-5, 5), st.floats(-5, 5)), min_size=2, max_size=12))
def test_resample_keeps_endpoints_and_gap_bounds(raw: list[tuple[float, float]]) -> None:
    pts = np.asarray(raw, dtype=np.float64)
    out = resample(pts, 0.25, 0.125)
    np.testing.assert_array_equal(out[0], pts[0])
    np.testing.assert_array_equal(out[-1], pts[-1])
    gaps = np.hypot(*np.diff(out, axis=0).T)
    assert gaps.max() <= 0.25 + 1e-9
    if len(out) > 2:
        assert gaps.min() >= 0.125 - 1e-9


def test_points_closer_than_quarter_robot_are_combined() -> None:
    pts = np.array([[0.0, 0.0], [0.2, 0.0], [0.25, 0.0], [0.3, 0.0], [0.45, 0.0]])
    out = resample(pts, 0.25, 0.125)
    np.testing.assert_allclose(out, [[0.0, 0.0], [0.2, 0.0], [0.45, 0.0]])


def test_straight_band_without_obstacles_is_already_in_equilibrium() -> None:
    band = band_from_path([[0.0, 0.0], [5.0, 0.0]], (), PARAMS)
    result = relax(band, (), PARAMS)
    assert result.converged and result.iterations == 1
    np.testing.assert_allclose(result.band.points, band.points, atol=1e-12)


def test_contraction_straightens_a_staircase_path() -> None:
    """A grid planner's 8-connected staircase (5 cm steps) is smoothed out in a few iterations."""
    stairs = np.array([[0.05 * (i + i % 2), 0.05 * (i - i % 2)] for i in range(41)])  # diagonal zigzag
    band = band_from_path(stairs, (), PARAMS)
    result = relax(band, (), PARAMS)
    assert result.converged
    chord = stairs[-1] - stairs[0]
    normal = np.array([-chord[1], chord[0]]) / np.hypot(*chord)
    deviation = np.abs((result.band.points - stairs[0]) @ normal)
    assert deviation.max() < 0.01
    assert result.band.length_m == pytest.approx(np.hypot(*chord), rel=1e-3)


def test_contraction_shortens_a_zigzag_and_never_moves_endpoints() -> None:
    zigzag = np.array([[0, 0], [1, 1], [2, -1], [3, 1], [4, -1], [5, 0]], dtype=float)
    band = band_from_path(zigzag, (), PARAMS)
    result = relax(band, (), PARAMS, max_iterations=300)
    assert result.band.length_m < 0.6 * band.length_m
    assert np.abs(result.band.points[:, 1]).max() < 0.15
    np.testing.assert_array_equal(result.band.points[[0, -1]], zigzag[[0, -1]])


def test_large_contraction_gain_saturates_instead_of_oscillating() -> None:
    """k_c = 1000 would throw points past their neighbours' chord; the cap keeps relaxation
    monotone: the band length never grows from one iteration to the next."""
    params = ElasticBandParams(k_c=1000.0)
    band = band_from_path([[0, 0], [1, 1], [2, -1], [3, 0]], (), params)
    lengths = [band.length_m]
    for _ in range(60):
        band = step(band, (), None, params)
        lengths.append(band.length_m)
    assert np.all(np.diff(lengths) <= 1e-9)


def test_repulsion_bends_the_band_around_an_unforeseen_obstacle() -> None:
    """A post (radius 0.2 m) appears 0.3 m beside a straight band: at equilibrium the band goes
    round the other side with clearance, stays connected, and the endpoints do not move."""
    post = disc(5.0, 0.3, 0.2)
    band = band_from_path([[0.0, 0.0], [10.0, 0.0]], post, PARAMS)
    assert band.radii.min() < 0.15
    result = relax(band, post, PARAMS, max_iterations=400)
    assert result.band.radii.min() > 0.6  # pushed out towards D0 = 1 m
    near = np.abs(result.band.points[:, 0] - 5.0) < 0.5
    assert np.all(result.band.points[near, 1] < -0.4)  # away from the post, which is at y > 0
    np.testing.assert_array_equal(result.band.points[[0, -1]], [[0.0, 0.0], [10.0, 0.0]])
    assert is_connected(result.band, clearance_m=0.25)


def test_forces_expose_both_terms_for_drawing() -> None:
    post = disc(1.0, 0.5, 0.1)
    band = band_from_path([[0.0, 0.0], [1.0, 0.3], [2.0, 0.0]], post, PARAMS)
    f = forces(band, post, PARAMS)
    assert f.contraction.shape == f.repulsion.shape == band.points.shape
    assert np.all(f.contraction[1:-1, 1] <= 1e-12)  # pulls the bump down
    assert f.repulsion[1:-1, 1].min() < 0.0  # the post above pushes down too


def test_step_follows_the_robot_and_drops_the_passed_part() -> None:
    band = band_from_path([[0.0, 0.0], [4.0, 0.0]], (), PARAMS)
    moved = step(band, (), (1.3, 0.05, 0.0), PARAMS)
    np.testing.assert_allclose(moved.points[0], [1.3, 0.05])
    assert np.all(moved.points[1:, 0] > 1.3)
    np.testing.assert_array_equal(moved.points[-1], [4.0, 0.0])
    at_goal = step(band, (), (4.2, 0.0, 0.0), PARAMS)
    np.testing.assert_allclose(at_goal.points, [[4.2, 0.0], [4.0, 0.0]])


def test_obstacle_field_can_be_reused_and_matches_raw_points() -> None:
    post = disc(2.0, 0.4, 0.2)
    field = ObstacleField(post, PARAMS.max_radius_m)
    band = band_from_path([[0.0, 0.0], [4.0, 0.0]], post, PARAMS)
    np.testing.assert_allclose(step(band, field, None, PARAMS).points, step(band, post, None, PARAMS).points)


def test_is_connected_detects_a_blocked_band() -> None:
    wall = np.column_stack([np.full(41, 2.0), np.linspace(-1.0, 1.0, 41)])
    band = band_from_path([[0.0, 0.0], [4.0, 0.0]], wall, PARAMS)
    assert not is_connected(band, clearance_m=0.25)
    assert is_connected(band_from_path([[0.0, 0.0], [4.0, 0.0]], (), PARAMS), clearance_m=0.25)


@pytest.mark.parametrize(("call", "fragment"), [
    (lambda: band_from_path([[0.0, 0.0]], ()), "at least 2 waypoints"),
    (lambda: band_from_path([[0.0, 0.0, 1.0], [1.0, 0.0, 1.0]], ()), "path_xy: expected shape (N, 2)"),
    (lambda: band_from_path([[0.0, 0.0], [np.nan, 1.0]], ()), "path_xy: row 1 is not finite"),
    (lambda: band_from_path([[0.0, 0.0], [1.0, 1.0]], [[1.0, 2.0, 3.0]]), "obstacles_xy"),
    (lambda: band_from_path([[0.0, 0.0], [1.0, 1.0]], [["a", "b"]]), "obstacles_xy: not numeric"),
    (lambda: step(band_from_path([[0, 0], [1, 0]], ()), (), (np.inf, 0.0, 0.0)), "robot_pose"),
    (lambda: ElasticBand(np.zeros((1, 2)), np.zeros(1)), "band points"),
])
def test_bad_input_raises_a_typed_error_naming_the_argument(call, fragment: str) -> None:
    with pytest.raises(BandInputError) as info:
        call()
    assert fragment in str(info.value)


def test_params_reject_inconsistent_values() -> None:
    with pytest.raises(ValueError, match="influence_distance_m"):
        ElasticBandParams(influence_distance_m=5.0, max_radius_m=4.0)
    with pytest.raises(ValueError):
        ElasticBandParams(k_c=-1.0)
    with pytest.raises(ValueError):
        ElasticBandParams(unknown=1.0)


def test_step_does_not_short_circuit_a_u_turn() -> None:
    """The band goes 3 m out and comes back 0.4 m beside the robot: a robot that has just started
    must keep the whole loop, not jump onto the returning branch."""
    band = band_from_path([[0.0, 0.0], [3.0, 0.0], [3.0, 0.4], [0.0, 0.4]], (), PARAMS)
    moved = step(band, (), (0.1, 0.3, 0.0), PARAMS)
    assert moved.length_m > 6.0
    np.testing.assert_array_equal(moved.points[-1], [0.0, 0.4])
