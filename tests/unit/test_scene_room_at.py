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
