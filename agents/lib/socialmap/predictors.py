"""People predictors by name: where each tracked person will be, a few seconds ahead.

Why a registry: the walker prediction the social map draws (motion.py) is one method among the
field's; ``chronav predict evaluate --predictor NAME`` scores any installed one on the same
pedestrian files (group ``chronav.predictors``; chronav registers its own there, as an outside
package does).

Protocol (frames and units as the map's): ``predict(people, times_s, walls)`` gets the tracked
people (types.Person: x, y in m, theta in rad, vx, vy in m/s, world frame), the times ahead
``times_s`` (T,) in seconds (> 0, increasing) and the walls (a shapely geometry or None), and
returns (K, T, 2) positions in metres, one row per person in the order given.  An entry point
names a factory ``factory() -> PeoplePredictor``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray
from shapely.geometry.base import BaseGeometry

from agents.lib import registry
from agents.lib.socialmap.motion import MotionParams, Prediction, predict_many
from agents.lib.socialmap.types import Person

FloatArray = NDArray[np.float64]
DEFAULT_PREDICTOR = "chronav"


@runtime_checkable
class PeoplePredictor(Protocol):
    """Where people will be at ``times_s`` ahead: (K, T, 2) metres, world frame."""

    def predict(self, people: Sequence[Person], times_s: FloatArray, walls: BaseGeometry | None) -> FloatArray: ...


class ChronavPredictor:
    """chronav's walker model: along the velocity, turned by walls and doors toward the agenda's destination."""

    def __init__(self, motion: MotionParams | None = None) -> None:
        self.motion = motion or MotionParams()

    def predict(self, people: Sequence[Person], times_s: FloatArray, walls: BaseGeometry | None) -> FloatArray:
        times = np.asarray(times_s, dtype=np.float64)
        step = float(times[0]) if len(times) else self.motion.step_s
        motion = self.motion.model_copy(update={"horizon_s": float(times[-1]) if len(times) else 0.0,
                                                "step_s": step})
        found = predict_many(people, motion, walls)
        return np.stack([interpolated(p, f, times) for p, f in zip(people, found, strict=True)]) if people \
            else np.zeros((0, len(times), 2))


class ConstantVelocityPredictor:
    """Constant velocity: each person keeps their tracked velocity (the field's baseline)."""

    def predict(self, people: Sequence[Person], times_s: FloatArray, walls: BaseGeometry | None) -> FloatArray:
        times = np.asarray(times_s, dtype=np.float64)
        xy = np.array([(p.x, p.y) for p in people], dtype=np.float64).reshape(-1, 1, 2)
        v = np.array([(p.vx, p.vy) for p in people], dtype=np.float64).reshape(-1, 1, 2)
        return xy + v * times[None, :, None]


def interpolated(person: Person, found: Prediction | None, times: FloatArray) -> FloatArray:
    """A prediction at ``times`` (s ahead): where it says nothing (a standing person) or stops short
    (a wall, an arrival) the person stays at their last predicted place."""
    here = np.array([[person.x, person.y]])
    if found is None or len(found.times) == 0:
        return np.repeat(here, len(times), axis=0)
    known_t = np.concatenate([[0.0], found.times])
    known = np.concatenate([here, found.points])
    return np.stack([np.interp(times, known_t, known[:, 0]), np.interp(times, known_t, known[:, 1])], axis=1)




def predictor(name: str) -> PeoplePredictor:
    """The predictor ``name``, built once per process; UnknownExtension or RefusedExtension."""
    return registry.built_once("predictor", name, PeoplePredictor, "predict()")


def checked_prediction(name: str, predicted: object, people: int, steps: int) -> FloatArray:
    """``predicted`` as a finite (people, steps, 2) array, else ValueError naming the predictor."""
    array = np.asarray(predicted, dtype=np.float64)
    if array.shape != (people, steps, 2):
        raise ValueError(f"predictor {name!r} returned shape {array.shape}, expected ({people}, {steps}, 2)")
    if not np.all(np.isfinite(array)):
        raise ValueError(f"predictor {name!r} returned NaN or infinite positions")
    return array
