"""The compiled banding of a predicted position (agents/lib/socialmap/banded.py) gives the costs the
numpy code gave: the weighted asymmetric Gaussian against the zone levels, cell for cell."""

from __future__ import annotations

import math

import numpy as np

from agents.lib.socialmap.banded import banded_gaussian
from agents.lib.socialmap.grid import COST_DTYPE
from agents.lib.socialmap.personal_space import PersonalSpace, asymmetric_gaussian


def _numpy_bands(space: PersonalSpace, x0: float, y0: float, theta: float, xs: np.ndarray, ys: np.ndarray,
                 w: float, levels: np.ndarray, table: np.ndarray) -> np.ndarray:
    density = w * asymmetric_gaussian(space, x0, y0, theta, xs[np.newaxis, :], ys[:, np.newaxis])
    index = (density >= levels[0]).astype(np.int8) + (density >= levels[1]) + (density >= levels[2])
    return table[index]


def test_banded_gaussian_equals_the_numpy_banding_cell_for_cell() -> None:
    rng = np.random.default_rng(7)
    table = np.array([0.0, 3.0, 10.0, math.inf], dtype=COST_DTYPE)
    levels = np.array([0.1, 0.4, 0.8])
    bands_seen: set[float] = set()
    for _ in range(300):
        space = PersonalSpace(*rng.uniform(0.2, 3.0, 4))
        x0, y0, theta = rng.uniform(-3, 3), rng.uniform(-3, 3), rng.uniform(-4, 4)
        xs = -4 + (np.arange(rng.integers(1, 120)) + 0.5) * 0.05
        ys = -4 + (np.arange(rng.integers(1, 120)) + 0.5) * 0.05
        w = float(rng.choice([rng.uniform(0.05, 1.0), 1.0, 0.1]))
        ours = banded_gaussian(space, x0, y0, theta, xs, ys, w, levels, table)
        theirs = _numpy_bands(space, x0, y0, theta, xs, ys, w, levels, table)
        assert ours.dtype == theirs.dtype and ours.shape == theirs.shape
        np.testing.assert_array_equal(ours, theirs)
        bands_seen |= set(np.unique(ours).tolist())
    assert bands_seen == {0.0, 3.0, 10.0, math.inf}, "every band is exercised"
