"""Object shapes: seed areas (Eqs. 10-12), posing, and the closed-form rasterisation vs shapely."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely

from agents.lib.socialmap.grid import GridSpec
from agents.lib.socialmap.layers import shape_mask
from agents.lib.socialmap.objects import local_contains, object_geometry
from scenes.geometry import posed_polygon
from agents.lib.socialmap.types import SocialMapInputError, SocialObject
from scenes.geometry import Circle, GeometryError, Rectangle, Trapezoid, shape_from_spec


def test_areas_follow_the_seed_equations() -> None:
    trapezoid, rectangle, circle = Trapezoid(2.8, 1.2, 3.2), Rectangle(2.8, 2.4), Circle(1.5)
    assert trapezoid.area == pytest.approx(2.8 * (1.2 + 3.2) / 2)        # Eq. 10
    assert rectangle.area == pytest.approx(2.8 * 2.4)                    # Eq. 11
    assert circle.area == pytest.approx(math.pi * 1.5**2)                # Eq. 12
    for shape in (trapezoid, rectangle, circle):
        assert posed_polygon(shape, 3.0, -1.0, 0.8).area == pytest.approx(shape.area, rel=0.003)


def test_tv_space_opens_in_front_of_the_screen() -> None:
    tv = SocialObject("tv", "tv", 5.0, 0.0, math.pi / 2, Rectangle(0.2, 1.2), Trapezoid(3.0, 1.0, 3.0))
    geometry = object_geometry(tv)
    minx, miny, maxx, maxy = geometry.interaction.bounds
    assert (miny, maxy) == pytest.approx((0.0, 3.0))                     # facing +y
    assert (minx, maxx) == pytest.approx((3.5, 6.5))                     # far edge 3 m wide
    assert geometry.interaction.contains(shapely.Point(5.0, 2.5))
    assert not geometry.interaction.contains(shapely.Point(5.0, -0.5))   # nothing behind the TV


@pytest.mark.parametrize("shape", [Rectangle(1.6, 0.9, offset=0.3), Circle(0.7), Trapezoid(2.8, 1.2, 3.2)])
@pytest.mark.parametrize("inflate", [0.0, 0.3])
def test_closed_form_cells_match_shapely(shape, inflate: float) -> None:  # type: ignore[no-untyped-def]
    spec = GridSpec.from_bounds((0.0, 0.0, 8.0, 8.0), 0.05)
    obj = SocialObject("o", "x", 4.1, 3.9, 0.6, shape, shape)
    polygon = posed_polygon(shape, obj.x, obj.y, obj.theta)
    mask = shape_mask(spec, obj, shape, polygon, inflate)
    assert mask is not None
    rows, cols = np.nonzero(mask.mask)
    ours = set(zip((rows + mask.rows.start).tolist(), (cols + mask.cols.start).tolist(), strict=True))
    grown = polygon.buffer(inflate, quad_segs=64) if inflate else polygon
    xs, ys = np.meshgrid(spec.xs(), spec.ys())
    inside = shapely.intersects_xy(grown, xs, ys)
    theirs = set(zip(*(a.tolist() for a in np.nonzero(inside)), strict=True))
    # Only cells whose centre is within a polygonisation error of the boundary may differ.
    assert len(ours ^ theirs) <= 0.01 * len(theirs)
    assert abs(len(ours) * 0.05**2 - grown.area) < 0.03 * grown.area


def test_local_contains_boundary_is_inside() -> None:
    u = np.array([0.8, 0.0, 0.81])
    v = np.array([0.0, 0.45, 0.0])
    np.testing.assert_array_equal(local_contains(Rectangle(1.6, 0.9), u, v), [True, True, False])


def test_shape_from_spec_errors_name_the_key() -> None:
    assert shape_from_spec({"shape": "circle", "radius": 1.5}) == Circle(1.5)
    with pytest.raises(GeometryError, match="tv interaction: trapezoid needs key 'far_width'"):
        shape_from_spec({"shape": "trapezoid", "height": 1, "near_width": 1}, "tv interaction")
    with pytest.raises(GeometryError, match="unknown key"):
        shape_from_spec({"shape": "circle", "radius": 1.5, "radiuss": 2})
    with pytest.raises(GeometryError, match="'shape' must be one of"):
        shape_from_spec({"shape": "hexagon"})
    with pytest.raises(SocialMapInputError, match="object 'bed' footprint: rectangle: width must be > 0"):
        SocialObject("bed", "bed", 0, 0, 0, {"shape": "rectangle", "length": 2, "width": 0}, Circle(1))
