"""A person's Gaussian straight into cost bands on a grid window (compiled).

Why: a predicted position's cost patch needs only which band each cell falls in (the weighted
density against the social, personal and intimate levels), yet numpy built it through a dozen
window-sized temporaries (the rotated coordinates, the scaled half-axes, the exponential, the
comparisons, the table lookup).  With 40 walkers, 12 predicted positions each, at every 5 Hz
replan, that was the social map's largest cost (docs/performance.md).  This kernel does the same
arithmetic in the same order, one cell at a time, and writes the band's cost.

The numbers are those of ``personal_space.asymmetric_gaussian`` times the weight, then banded as
``motion.prediction_patches`` did: every cell's density is computed with the same operations
(no fused multiply-add, the same exponential up to the last bit of libm's).
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

from agents.lib.socialmap.grid import COST_DTYPE
from agents.lib.socialmap.personal_space import PersonalSpace, half_axis_factors

_MARGIN = 1e-6      # in the exponent: exp's error is ~1e-16 relative, the margin 1e-6


@numba.njit(cache=True, nogil=True)
def _banded(xs, ys, x0, y0, cos_t, sin_t, factors, weight, levels, table, out):   # pragma: no cover - compiled
    a_u, b_u, a_v, b_v = factors[0], factors[1], factors[2], factors[3]
    # A cell whose exponent is beyond the lowest level's by a margin far above exp's rounding is in
    # no band, whatever the last bits: most of a window's cells, skipped without the exponential.
    beyond = math.log(weight / levels[0]) + _MARGIN if weight > 0.0 else -1.0
    low, mid, high = levels[0], levels[1], levels[2]
    for i in range(ys.shape[0]):
        dy = ys[i] - y0
        dy_sin = dy * sin_t
        dy_cos = dy * cos_t
        for j in range(xs.shape[0]):
            dx = xs[j] - x0
            u = dx * cos_t + dy_sin
            v = dy_cos - dx * sin_t
            su = u * a_u + abs(u) * b_u
            sv = v * a_v + abs(v) * b_v
            q = su * su + sv * sv
            if q > beyond:
                out[i, j] = table[0]
                continue
            density = weight * math.exp(-q)
            band = 0
            if density >= low:
                band += 1
            if density >= mid:
                band += 1
            if density >= high:
                band += 1
            out[i, j] = table[band]


def banded_gaussian(space: PersonalSpace, x0: float, y0: float, theta: float, xs: NDArray[np.float64],
                    ys: NDArray[np.float64], weight: float, levels: NDArray[np.float64],
                    table: NDArray[np.float32]) -> NDArray[np.float32]:
    """Costs on the window of cell centres ``xs`` (columns) by ``ys`` (rows): ``table[k]`` where k is
    how many of ``levels`` the person's weighted density ``weight * g`` reaches at the cell."""
    out = np.empty((len(ys), len(xs)), dtype=COST_DTYPE)
    _banded(np.ascontiguousarray(xs, dtype=np.float64), np.ascontiguousarray(ys, dtype=np.float64), float(x0),
            float(y0), math.cos(theta), math.sin(theta), np.asarray(half_axis_factors(space), dtype=np.float64),
            float(weight), np.asarray(levels, dtype=np.float64), np.asarray(table, dtype=COST_DTYPE), out)
    return out


def warm_up() -> None:
    """Compile (or load from numba's disk cache) the kernel now, not on the first map."""
    banded_gaussian(PersonalSpace(1.0, 0.5, 0.7, 0.7), 0.0, 0.0, 0.0, np.zeros(2), np.zeros(2), 0.5,
                    np.array([0.1, 0.4, 0.8]), np.array([0.0, 1.0, 2.0, np.inf], dtype=COST_DTYPE))
