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

import numpy as np
from numpy.typing import NDArray

from agents.lib.socialmap.grid import CostArray
from agents.lib.socialmap.layers import CellMask
from agents.lib.socialmap.search import TimeCosts

CostProfile = Callable[[NDArray[np.float64]], NDArray[np.float64]]


def encode_spaces(base: CostArray, masks: Sequence[CellMask | None], *,
                  in_place: bool = False) -> tuple[CostArray, list[tuple[frozenset[int], float]]]:
    """``base`` (a copy unless ``in_place``) with its interaction-space cells set to
    ``-(label + 1)``; the labels as (indices of the covering masks, static cost). Blocked cells
    stay blocked."""
    grid = base if in_place else base.copy()
    labels: list[tuple[frozenset[int], float]] = []
    index: dict[tuple[frozenset[int], float], int] = {}
    for k, mask in enumerate(masks):
        if mask is None:
            continue
        view = grid[mask.rows, mask.cols]
        values = view[mask.mask]
        open_cells = np.isfinite(values)
        if not open_cells.any():
            continue
        distinct, inverse = np.unique(values[open_cells], return_inverse=True)
        codes = np.empty(distinct.size, dtype=grid.dtype)
        for i, value in enumerate(distinct):
            if value < 0:   # already in other spaces: add k to that label's set
                covering, static = labels[int(-value) - 1]
                key = (covering | {k}, static)
            else:
                key = (frozenset((k,)), float(value))
            if key not in index:
                index[key] = len(labels)
                labels.append(key)
            codes[i] = -(index[key] + 1)
        values[open_cells] = codes[inverse.reshape(-1)]
        view[mask.mask] = values
    return grid, labels


def time_costs(base: CostArray, masks: Sequence[CellMask | None], profiles: Sequence[CostProfile],
               t0_s: float, cruise_speed_mps: float, resolution_m: float, time_step_s: float,
               horizon_m: float, *, in_place: bool = False) -> TimeCosts:
    """The search's arrival-time grid and table: one table row per label, one column per
    ``time_step_s`` of travel at ``cruise_speed_mps`` up to ``horizon_m`` (longer trips use the
    last column). ``profiles[k](times)`` is space k's cost at those times (inf: forbidden)."""
    if cruise_speed_mps <= 0.0 or time_step_s <= 0.0:
        raise ValueError("cruise speed and time step must be > 0")
    grid, labels = encode_spaces(base, masks, in_place=in_place)
    bins = max(1, math.ceil(horizon_m / cruise_speed_mps / time_step_s) + 1)
    times = t0_s + (np.arange(bins) + 0.5) * time_step_s
    times[0] = t0_s
    per_space = {k: np.asarray(profiles[k](times), dtype=np.float64)
                 for k in sorted({k for covering, _ in labels for k in covering})}
    table = np.ones((max(1, len(labels)), bins))
    for row, (covering, static) in enumerate(labels):
        table[row] = np.maximum(static, np.max([per_space[k] for k in covering], axis=0))
    return TimeCosts(grid=grid, table=table, cells_per_bin=cruise_speed_mps * time_step_s / resolution_m)
