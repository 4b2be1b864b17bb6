"""A people predictor: each person keeps their heading but slows down (halving every 2 s).

Implements chronav's PeoplePredictor protocol (agents/lib/socialmap/predictors.py):
``predict(people, times_s, walls) -> (K, T, 2)`` positions in metres, world frame.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from shapely.geometry.base import BaseGeometry

from agents.lib.socialmap.types import Person

HALF_LIFE_S = 2.0


class SlowingWalkers:
    """Constant heading, speed halving every 2 s (people tend to stop): a damped constant velocity."""

    def predict(self, people: Sequence[Person], times_s: np.ndarray, walls: BaseGeometry | None) -> np.ndarray:
        times = np.asarray(times_s, dtype=float)
        rate = math.log(2.0) / HALF_LIFE_S
        travelled = (1.0 - np.exp(-rate * times)) / rate          # integral of exp(-rate t)
        xy = np.array([(p.x, p.y) for p in people], dtype=float).reshape(-1, 1, 2)
        v = np.array([(p.vx, p.vy) for p in people], dtype=float).reshape(-1, 1, 2)
        return xy + v * travelled[None, :, None]
