"""Arrival-time chronemics: the interaction spaces' costs as a function of distance travelled.

Beyond the seeds, which price every interaction space at the departure time: a robot 60 m from a
TV whose therapy starts in two minutes will arrive after the start, so the planner should price
the TV's space at R(arrival). The search (search.py) asks, for a cell reached after travelling
``s`` metres, the cost at t0 + s / cruise speed.

A cell of an interaction space costs max(its static cost, R of every space covering it). Such
cells are labelled by (set of covering spaces, static cost), a handful of distinct labels, and get
the negative code ``-(label + 1)`` in a copy of the static grid; ``table[label, time bin]`` holds
the label's cost per bin. Labels are assigned space by space over each space's own cells, through
``np.unique`` of the few values found there (never over the whole grid).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numba
import numpy as np
from numpy.typing import NDArray

from agents.lib.socialmap.grid import CostArray
from agents.lib.socialmap.layers import CellMask
from agents.lib.socialmap.grid import TimeCosts

# times (n,) -> every space's cost at those times, shape (spaces, n)
CostProfiles = Callable[[NDArray[np.float64]], NDArray[np.float64]]


_MAX_DISTINCT = 64   # distinct static costs inside one space handled by the compiled pass


@numba.njit(cache=True, nogil=True)
def _distinct_values(view, mask, out):
    """The distinct finite values of ``view`` where ``mask``, into ``out``; -1 if more than fit."""
    count = 0
    for r in range(view.shape[0]):
        for c in range(view.shape[1]):
            if not mask[r, c]:
                continue
            value = view[r, c]
            if value == np.inf:
                continue
            seen = False
            for i in range(count):
                if out[i] == value:
                    seen = True
                    break
            if not seen:
                if count == out.shape[0]:
                    return -1
                out[count] = value
                count += 1
    return count


@numba.njit(cache=True, nogil=True)
def _replace_values(view, mask, distinct, codes, count):
    """Set each finite ``view`` cell in ``mask`` holding ``distinct[i]`` to ``codes[i]``."""
    for r in range(view.shape[0]):
        for c in range(view.shape[1]):
            if not mask[r, c]:
                continue
            value = view[r, c]
            for i in range(count):
                if distinct[i] == value:
                    view[r, c] = codes[i]
                    break


def encode_spaces(base: CostArray, masks: Sequence[CellMask | None], *,
                  in_place: bool = False) -> tuple[CostArray, list[tuple[frozenset[int], float]]]:
    """``base`` (a copy unless ``in_place``) with its interaction-space cells set to
    ``-(label + 1)``; the labels as (indices of the covering masks, static cost). Blocked cells
    stay blocked. (Two compiled passes per space: numpy's boolean indexing and ``np.unique``
    cost about 1 ms per rebuild at 1000^2, a tenth of a plan.)"""
    grid = base if in_place else base.copy()
    labels: list[tuple[frozenset[int], float]] = []
    index: dict[tuple[frozenset[int], float], int] = {}
    distinct = np.empty(_MAX_DISTINCT, dtype=grid.dtype)
    codes = np.empty(_MAX_DISTINCT, dtype=grid.dtype)
    for k, mask in enumerate(masks):
        if mask is None:
            continue
        view = grid[mask.rows, mask.cols]
        count = _distinct_values(view, mask.mask, distinct)
        if count < 0:   # a space over many different costs: numpy does it
            found = np.unique(view[mask.mask & np.isfinite(view)])
            count = found.size
            distinct, codes = found.astype(grid.dtype), np.empty(found.size, dtype=grid.dtype)
        for i in range(count):
            value = float(distinct[i])
            if value < 0:   # already in other spaces: add k to that label's set
                covering, static = labels[int(-value) - 1]
                key = (covering | {k}, static)
            else:
                key = (frozenset((k,)), value)
            if key not in index:
                index[key] = len(labels)
                labels.append(key)
            codes[i] = -(index[key] + 1)
        _replace_values(view, mask.mask, distinct, codes, count)
        if distinct.shape[0] != _MAX_DISTINCT:
            distinct = np.empty(_MAX_DISTINCT, dtype=grid.dtype)
            codes = np.empty(_MAX_DISTINCT, dtype=grid.dtype)
    return grid, labels


def time_costs(base: CostArray, masks: Sequence[CellMask | None], profiles: CostProfiles,
               t0_s: float, cruise_speed_mps: float, resolution_m: float, time_step_s: float,
               horizon_m: float, *, in_place: bool = False) -> TimeCosts:
    """The search's arrival-time grid and table: one table row per label, one column per
    ``time_step_s`` of travel at ``cruise_speed_mps`` up to ``horizon_m`` (longer trips use the
    last column). ``profiles(times)[k]`` is space k's cost at those times (inf: forbidden)."""
    if cruise_speed_mps <= 0.0 or time_step_s <= 0.0:
        raise ValueError("cruise speed and time step must be > 0")
    grid, labels = encode_spaces(base, masks, in_place=in_place)
    return TimeCosts(grid=grid, table=cost_table(labels, profiles, t0_s, cruise_speed_mps, time_step_s, horizon_m),
                     cells_per_bin=cruise_speed_mps * time_step_s / resolution_m)


def cost_table(labels: Sequence[tuple[frozenset[int], float]], profiles: CostProfiles, t0_s: float,
               cruise_speed_mps: float, time_step_s: float, horizon_m: float) -> NDArray[np.float64]:
    """The table of ``time_costs`` for ``labels`` (from encode_spaces): row k is label k's cost
    per time bin, the dearest of its static cost and of the spaces covering it."""
    bins = max(1, math.ceil(horizon_m / cruise_speed_mps / time_step_s) + 1)
    times = t0_s + (np.arange(bins, dtype=np.float64) + 0.5) * time_step_s
    times[0] = t0_s
    if not labels:
        return np.ones((1, bins))
    per_space = np.asarray(profiles(times), dtype=np.float64)
    spaces = [sorted(covering) for covering, _ in labels]
    statics = np.array([static for _, static in labels], dtype=np.float64)
    table = np.maximum(statics[:, np.newaxis], per_space[[own[0] for own in spaces]])
    for row, own in enumerate(spaces):
        for k in own[1:]:   # a cell in several spaces costs the dearest
            np.maximum(table[row], per_space[k], out=table[row])
    return table


def warm_up() -> None:
    """Compile (or load from numba's disk cache) the encoding passes."""
    grid = np.ones((3, 3), dtype=np.float32)
    mask = CellMask(slice(0, 2), slice(0, 2), np.ones((2, 2), dtype=np.bool_))
    encode_spaces(grid, [mask, mask])
