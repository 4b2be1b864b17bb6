"""Scene.room_at with rooms of different numbers of corners (found: the prepared shapes were built
as one ragged array, and `chronav path` on a scene from a map failed with a numpy error)."""

from __future__ import annotations

from scenes.loader import load_scene
from scenes.model import Room
from tests.support import REPO_ROOT


def test_rooms_with_different_corner_counts() -> None:
    tiny = load_scene(str(REPO_ROOT / "tests" / "data" / "eval_tiny.yaml")).scene
    scene = tiny.model_copy(update={"rooms": [
        Room(name="square", polygon=[(0, 0), (4, 0), (4, 4), (0, 4)]),
        Room(name="l_shape", polygon=[(4, 0), (10, 0), (10, 6), (7, 6), (7, 4), (4, 4)])]})
    assert scene.room_at(1.0, 1.0) == "square"
    assert scene.room_at(8.0, 5.0) == "l_shape"
    assert scene.room_at(5.0, 5.0) is None


def test_rooms_at_answers_what_a_point_by_point_shapely_test_answers() -> None:
    """Scene.rooms_at (the observer's one call a tick) against the definition: the first room whose
    polygon covers the point (outlines and shared walls included), or None."""
    import numpy as np
    import shapely

    scene = load_scene(str(REPO_ROOT / "scenes" / "center_day.yaml")).scene
    xmin, ymin, xmax, ymax = scene.bounds
    rng = np.random.default_rng(3)
    xs = [*rng.uniform(xmin - 1, xmax + 1, 2000).tolist(), *(p[0] for r in scene.rooms for p in r.polygon)]
    ys = [*rng.uniform(ymin - 1, ymax + 1, 2000).tolist(), *(p[1] for r in scene.rooms for p in r.polygon)]
    polygons = [shapely.Polygon(room.polygon) for room in scene.rooms]
    expected = [next((room.name for room, poly in zip(scene.rooms, polygons, strict=True)
                      if poly.covers(shapely.Point(x, y))), None) for x, y in zip(xs, ys, strict=True)]
    assert scene.rooms_at(xs, ys) == expected
    assert [scene.room_at(x, y) for x, y in zip(xs[:300], ys[:300], strict=True)] == expected[:300]
    assert len(set(expected)) == len(scene.rooms) + 1, "every room and outside are exercised"
    assert scene.rooms_at([], []) == []
