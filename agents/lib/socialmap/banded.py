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
from collections.abc import Sequence

import numba
import numpy as np
from numpy.typing import NDArray

from agents.lib.socialmap.grid import COST_DTYPE, cell_centres
from agents.lib.socialmap.personal_space import PersonalSpace, half_axis_factors

_MARGIN = 1e-6      # in the exponent: exp's error is ~1e-16 relative, the margin 1e-6


@numba.njit(cache=True, nogil=True)
def _row_span(dy, x0, cos_t, sin_t, factors, root, xs):   # pragma: no cover - compiled
    """Columns [j0, j1) of the row ``dy`` (from the person) outside which the exponent exceeds
    ``root`` squared: the Gaussian's scaled half-axes bound |u| by root / k (k of that half) and
    |v| likewise, a rectangle in the person's frame, padded by two cells against rounding; where
    the row crosses it is an interval of x.  The cells outside it need no arithmetic at all."""
    n = xs.shape[0]
    res = xs[1] - xs[0] if n >= 2 else 0.0
    if not res > 0.0:                       # one column, or not a grid's increasing centres: all of it
        return 0, n
    pad = 2.0 * res
    u_lo, u_hi = -root / (factors[0] - factors[1]) - pad, root / (factors[0] + factors[1]) + pad
    v_lo, v_hi = -root / (factors[2] - factors[3]) - pad, root / (factors[2] + factors[3]) + pad
    lo, hi = -math.inf, math.inf
    along = dy * sin_t                      # u = dx cos + dy sin
    if abs(cos_t) > 1e-9:
        a, b = (u_lo - along) / cos_t, (u_hi - along) / cos_t
        lo, hi = max(lo, min(a, b)), min(hi, max(a, b))
    elif along < u_lo or along > u_hi:
        return 0, 0
    across = dy * cos_t                     # v = dy cos - dx sin
    if abs(sin_t) > 1e-9:
        a, b = (across - v_hi) / sin_t, (across - v_lo) / sin_t
        lo, hi = max(lo, min(a, b)), min(hi, max(a, b))
    elif across < v_lo or across > v_hi:
        return 0, 0
    if lo > hi:
        return 0, 0
    first = (x0 + lo - xs[0]) / res
    last = (x0 + hi - xs[0]) / res
    j0 = 0 if first <= 0.0 else (n if first >= n else int(math.floor(first)))
    j1 = n if last >= n - 1 else (0 if last < 0.0 else int(math.ceil(last)) + 1)
    return j0, max(j0, j1)


@numba.njit(cache=True, nogil=True)
def _band(density, low, mid, high):   # pragma: no cover - compiled
    """How many of the three levels ``density`` reaches (0-3): the band both kernels colour a cell by."""
    band = 0
    if density >= low:
        band += 1
    if density >= mid:
        band += 1
    if density >= high:
        band += 1
    return band


@numba.njit(cache=True, nogil=True)
def _banded(xs, ys, x0, y0, cos_t, sin_t, factors, weight, levels, table, out):   # pragma: no cover - compiled
    a_u, b_u, a_v, b_v = factors[0], factors[1], factors[2], factors[3]
    # A cell whose exponent is beyond the lowest level's by a margin far above exp's rounding is in
    # no band, whatever the last bits: most of a window's cells, skipped without the exponential.
    beyond = math.log(weight / levels[0]) + _MARGIN if weight > 0.0 else -1.0
    low, mid, high = levels[0], levels[1], levels[2]
    out[:, :] = table[0]
    if beyond < 0.0:
        return
    root = math.sqrt(beyond)
    c_low, c_mid, c_high = math.log(weight / low), math.log(weight / mid), math.log(weight / high)
    for i in range(ys.shape[0]):
        dy = ys[i] - y0
        dy_sin = dy * sin_t
        dy_cos = dy * cos_t
        j0, j1 = _row_span(dy, x0, cos_t, sin_t, factors, root, xs)
        for j in range(j0, j1):
            dx = xs[j] - x0
            u = dx * cos_t + dy_sin
            v = dy_cos - dx * sin_t
            su = u * a_u + abs(u) * b_u
            sv = v * a_v + abs(v) * b_v
            q = su * su + sv * sv
            if q > beyond:
                continue
            # weight exp(-q) >= level  <=>  q <= log(weight / level): decided on q unless q is within
            # the margin of one of those (where exp's last bits could matter: computed as before)
            if abs(q - c_low) <= _MARGIN or abs(q - c_mid) <= _MARGIN or abs(q - c_high) <= _MARGIN:
                band = _band(weight * math.exp(-q), low, mid, high)
            else:
                band = (q < c_low) + (q < c_mid) + (q < c_high)
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


def banded_gaussians(space: PersonalSpace, theta: float,
                     centres: Sequence[tuple[float, float, float, NDArray[np.float64], NDArray[np.float64]]],
                     levels: NDArray[np.float64], table: NDArray[np.float32]) -> list[NDArray[np.float32]]:
    """``banded_gaussian`` of one space and heading at several centres: (x, y, weight, xs, ys) each
    (a walker's predicted positions).  The same arrays; the space's factors, the heading's cosine
    and sine and the tables converted once, not per position."""
    factors = np.asarray(half_axis_factors(space), dtype=np.float64)
    cos_t, sin_t = math.cos(theta), math.sin(theta)
    levels = np.asarray(levels, dtype=np.float64)
    table = np.asarray(table, dtype=COST_DTYPE)
    found = []
    for x0, y0, weight, xs, ys in centres:
        out = np.empty((len(ys), len(xs)), dtype=COST_DTYPE)
        _banded(np.ascontiguousarray(xs, dtype=np.float64), np.ascontiguousarray(ys, dtype=np.float64), float(x0),
                float(y0), cos_t, sin_t, factors, float(weight), levels, table, out)
        found.append(out)
    return found


@numba.njit(cache=True, nogil=True)
def _banded_sum(xs, ys, x0s, y0s, cos_ts, sin_ts, factors, levels, table, out):   # pragma: no cover - compiled
    n = x0s.shape[0]
    low, mid, high = levels[0], levels[1], levels[2]
    # Every member's exponent beyond log(n / low) (by the margin): each Gaussian is below low / n, so
    # their sum is below low whatever exp's last bits: the cell is in no band, no exponential taken.
    beyond = math.log(n / low) + _MARGIN
    out[:, :] = table[0]
    if beyond < 0.0:
        return
    root = math.sqrt(beyond)
    qs = np.empty(n)
    for i in range(ys.shape[0]):
        j0, j1 = xs.shape[0], 0             # the members' spans' hull on this row
        for k in range(n):
            a, b = _row_span(ys[i] - y0s[k], x0s[k], cos_ts[k], sin_ts[k], factors[k], root, xs)
            if a < b:
                j0, j1 = min(j0, a), max(j1, b)
        for j in range(j0, j1):
            near = False
            for k in range(n):
                dx = xs[j] - x0s[k]
                dy = ys[i] - y0s[k]
                u = dx * cos_ts[k] + dy * sin_ts[k]
                v = dy * cos_ts[k] - dx * sin_ts[k]
                su = u * factors[k, 0] + abs(u) * factors[k, 1]
                sv = v * factors[k, 2] + abs(v) * factors[k, 3]
                q = su * su + sv * sv
                qs[k] = q
                if q <= beyond:
                    near = True
            if not near:
                continue
            density = math.exp(-qs[0])
            for k in range(1, n):          # summed in the members' order, as group_density sums
                density = density + math.exp(-qs[k])
            out[i, j] = table[_band(density, low, mid, high)]


def banded_group(spaces: Sequence[PersonalSpace], poses: Sequence[tuple[float, float, float]],
                 xs: NDArray[np.float64], ys: NDArray[np.float64], levels: NDArray[np.float64],
                 table: NDArray[np.float32]) -> NDArray[np.float32]:
    """Costs on the window of cell centres ``xs`` (columns) by ``ys`` (rows): ``table[k]`` where k is
    how many of ``levels`` a group's density reaches at the cell, the density being the sum of its
    members' Gaussians (``groups.group_density``; member m has ``spaces[m]`` at ``poses[m]``, x, y,
    theta).  What ``zones.band_patches`` makes of ``zones.density_windows``, without the densities."""
    if len(poses) == 1:                # a lone person: their Gaussian alone (1.0 x g is g, bit for bit)
        (x0, y0, theta), = poses
        return banded_gaussian(spaces[0], x0, y0, theta, xs, ys, 1.0, levels, table)
    out = np.empty((len(ys), len(xs)), dtype=COST_DTYPE)
    if not poses:
        out.fill(table[0])
        return out
    pose = np.asarray(poses, dtype=np.float64).reshape(-1, 3)
    _banded_sum(np.ascontiguousarray(xs, dtype=np.float64), np.ascontiguousarray(ys, dtype=np.float64),
                np.ascontiguousarray(pose[:, 0]), np.ascontiguousarray(pose[:, 1]),
                np.array([math.cos(t) for t in pose[:, 2].tolist()]), np.array([math.sin(t) for t in pose[:, 2].tolist()]),
                np.array([half_axis_factors(space) for space in spaces], dtype=np.float64).reshape(-1, 4),
                np.asarray(levels, dtype=np.float64), np.asarray(table, dtype=COST_DTYPE), out)
    return out


def warm_up() -> None:
    """Compile (or load from numba's disk cache) the kernels now, not on the first map.

    With the argument types a map passes: the cell centres are read-only (``GridSpec.xs``), and
    numba compiles a read-only array as another signature, and a group of one never reaches the
    group kernel.  Warmed with writable arrays and one person, the first map with people compiled
    both kernels, in the middle of a mission (and kept the code)."""
    space, levels = PersonalSpace(1.0, 0.5, 0.7, 0.7), np.array([0.1, 0.4, 0.8])
    table = np.array([0.0, 1.0, 2.0, np.inf], dtype=COST_DTYPE)
    xs = ys = cell_centres(0.0, 0.5, 2)
    banded_gaussian(space, 0.0, 0.0, 0.0, xs, ys, 0.5, levels, table)
    # two members: a group of one is banded_gaussian's and never reaches the group kernel
    banded_group([space, space], [(0.0, 0.0, 0.0), (0.5, 0.0, 0.0)], xs, ys, levels, table)
