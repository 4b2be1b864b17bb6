"""The arrival-time grid of successive social maps, updated only where their layers changed.

Why: after a person moved, a replan (replan.py) expands a thousand cells, but composing the
arrival-time grid afresh (a copy of the static grid, every patch, every interaction space encoded:
arrival.time_costs) and then comparing every cell's lower bound took about half of the 3 ms
replan (tools/bench/bench_planner.py, 1000^2). A planning agent rebuilds its social map for each
replan, but most of it is what it was 0.2 s ago.

Between two maps on the same static grid (the same array, which is never written), what can
change is the patches (a person moved: their body, zone bands, prediction), the interaction
spaces' masks (an object moved) and the table (R(t) with time, the agenda). A patch identical to
one of the previous map's (same window, same bits) changes nothing; patches and masks are never
written once a map is built. So every cell outside the windows of the patches not matched so (in
either map) holds the same uncoded value in both grids, and only those windows are recomposed:
the static grid, then the maximum with every patch overlapping them. When the masks changed or
one of those windows overlaps a space, every space's window (in either map) is recomposed too and
all spaces are encoded again in place (encode_spaces reads and writes only cells of the spaces);
otherwise the spaces' codes and labels stay as they were. The maximum is exact whatever the order,
so the grid, its labels and its table are the ones a fresh arrival.time_costs builds, bit for bit
(tests/unit/test_social_incremental.py).

The windows are also what the replanner needs: a cell outside them keeps its lower bound, so its
pass over the bounds covers only them (``changes``), plus the spaces' windows when the table moved.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from agents.lib.socialmap.arrival import CostProfiles, cost_table, encode_spaces
from agents.lib.socialmap.grid import CostArray, CostPatch, compose_into
from agents.lib.socialmap.layers import CellMask
from agents.lib.socialmap.grid import TimeCosts

Window = tuple[int, int, int, int]   # rows r0:r1, cols c0:c1


def _window(rows: slice, cols: slice, shape: tuple[int, int]) -> Window | None:
    """The box of a patch or mask, or None for a strided one (then everything is recomposed)."""
    r0, r1, r_step = rows.indices(shape[0])
    c0, c1, c_step = cols.indices(shape[1])
    if r_step != 1 or c_step != 1:
        return None
    return r0, max(r0, r1), c0, max(c0, c1)


def _boxes(patches: Sequence[CostPatch], masks: Sequence[CellMask | None],
           shape: tuple[int, int]) -> tuple[list[tuple[Window, CostPatch]], list[Window]] | None:
    """Each patch with its window, and the masks' windows; None if one is strided."""
    boxed = []
    for patch in patches:
        window = _window(patch.rows, patch.cols, shape)
        if window is None:
            return None
        boxed.append((window, patch))
    windows = []
    for mask in masks:
        if mask is not None:
            window = _window(mask.rows, mask.cols, shape)
            if window is None:
                return None
            windows.append(window)
    return boxed, windows


def _same(a: NDArray[np.generic], b: NDArray[np.generic]) -> bool:
    """Bit for bit the same array (what decides whether a composed cell can differ)."""
    return a is b or (a.shape == b.shape and a.dtype == b.dtype and a.tobytes() == b.tobytes())


def _overlaps(boxes: Sequence[Window], windows: Sequence[Window]) -> NDArray[np.bool_]:
    """(len(boxes), len(windows)): whether each box and window share a cell."""
    if not boxes or not windows:
        return np.zeros((len(boxes), len(windows)), dtype=bool)
    p = np.array(boxes, dtype=np.int64)[:, np.newaxis, :]
    w = np.array(windows, dtype=np.int64)[np.newaxis, :, :]
    return (p[..., 0] < w[..., 1]) & (w[..., 0] < p[..., 1]) & (p[..., 2] < w[..., 3]) & (w[..., 2] < p[..., 3])


class IncrementalTimeCosts:
    """Builds ``SocialMap.time_costs`` for one map after another, reusing its own grid buffer.

    The returned TimeCosts is this object's buffer: valid until the next call (a replanner searches
    it and forgets it). One per planning thread; replan.Replanner owns one."""

    def __init__(self) -> None:
        self._static: CostArray | None = None   # the static grid of the buffer (None: rebuild all)
        self._grid: CostArray = np.empty((0, 0), dtype=np.float32)
        self._patches: list[tuple[Window, CostPatch]] = []
        self._masks: list[CellMask | None] = []
        self._mask_windows: list[Window] = []
        self._labels: list[tuple[frozenset[int], float]] = []
        self._changes: list[Window] | None = None   # since the last ``synced`` (None: all)
        self.current: TimeCosts | None = None
        self.last_windows: list[Window] | None = None   # recomposed by the last call (None: all)
        self.last_encoded = False                       # the last call encoded the spaces again

    def time_costs(self, static: CostArray, patches: Sequence[CostPatch], masks: Sequence[CellMask | None],
                   profiles: CostProfiles, t0_s: float, cruise_speed_mps: float, resolution_m: float,
                   time_step_s: float, horizon_m: float) -> TimeCosts:
        """arrival.time_costs(compose(static, patches), masks, ...), recomposing only what changed
        since the previous call."""
        if cruise_speed_mps <= 0.0 or time_step_s <= 0.0:
            raise ValueError("cruise speed and time step must be > 0")
        shape = static.shape
        found = _boxes(patches, masks, shape)
        same_static = static is self._static and self._grid.shape == shape and self._grid.dtype == static.dtype
        self._static, self.current = None, None   # until the buffer is consistent again
        labels = self._labels
        if found is not None and same_static:
            boxed, mask_windows = found
            changed = self._changed(boxed)
            # The spaces' codes stay when the spaces and every cell under them stay.
            encode = not self._same_masks(masks) or bool(_overlaps(changed, self._mask_windows).any())
            # each window once (most spaces' windows are the same in both maps)
            windows = list(dict.fromkeys([*changed, *self._mask_windows, *mask_windows] if encode else changed))
            self._recompose(static, boxed, windows)
            if self._changes is not None:
                self._changes.extend(windows)
            self.last_windows = windows
        else:
            if self._grid.shape != shape or self._grid.dtype != static.dtype:
                self._grid = np.empty_like(static)
            np.copyto(self._grid, static)
            compose_into(self._grid, patches)
            self._changes = None
            self.last_windows = None
            encode = True
        if encode:
            _, labels = encode_spaces(self._grid, masks, in_place=True)
        self.last_encoded = encode
        table = cost_table(labels, profiles, t0_s, cruise_speed_mps, time_step_s, horizon_m)
        if found is not None:
            self._static = static
            self._patches, self._mask_windows = found
            self._masks = list(masks)
            self._labels = labels
        self.current = TimeCosts(grid=self._grid, table=table,
                                 cells_per_bin=cruise_speed_mps * time_step_s / resolution_m)
        return self.current

    def changes(self) -> NDArray[np.int64] | None:
        """The windows (n, 4: r0, r1, c0, c1) outside which ``current``'s grid holds the values
        (costs, or the same spaces' codes) of the grid of the last ``synced`` call's ``current``;
        None when unknown (since then a rebuild from scratch, or nothing synced yet). The table
        is not covered: see ``space_windows``."""
        if self._changes is None:
            return None
        return np.array(self._changes, dtype=np.int64).reshape(-1, 4)

    def space_windows(self) -> NDArray[np.int64]:
        """The windows of ``current``'s interaction spaces: every coded cell (whose cost a change
        of the table alone changes) lies in one."""
        return np.array(self._mask_windows, dtype=np.int64).reshape(-1, 4)

    def synced(self, in_sync: bool = True) -> None:
        """Start counting changes from ``current`` (``in_sync``: a user now mirrors it), or stop
        (the user mirrors another grid: ``changes`` is None until the next sync)."""
        self._changes = [] if in_sync else None

    def _same_masks(self, masks: Sequence[CellMask | None]) -> bool:
        if len(masks) != len(self._masks):
            return False
        for new, old in zip(masks, self._masks, strict=True):
            if new is None or old is None:
                if new is not old:
                    return False
            elif new.rows != old.rows or new.cols != old.cols or not _same(new.mask, old.mask):
                return False
        return True

    def _changed(self, boxed: list[tuple[Window, CostPatch]]) -> list[Window]:
        """Windows of the patches not matched by an identical patch of the other map (both ways)."""
        previous: dict[Window, list[CostPatch]] = {}
        for window, patch in self._patches:
            previous.setdefault(window, []).append(patch)
        changed = []
        for window, patch in boxed:
            candidates = previous.get(window, [])
            for i, old in enumerate(candidates):
                if _same(old.values, patch.values):
                    del candidates[i]
                    break
            else:
                changed.append(window)
        changed.extend(window for window, left in previous.items() for _ in left)
        return changed

    def _recompose(self, static: CostArray, boxed: list[tuple[Window, CostPatch]], windows: list[Window]) -> None:
        """Reset ``windows`` to the static grid, then take the maximum with every patch over its
        overlap with each window (a cell covered twice gets the same value twice)."""
        grid = self._grid
        for r0, r1, c0, c1 in windows:
            grid[r0:r1, c0:c1] = static[r0:r1, c0:c1]
        for i, j in zip(*np.nonzero(_overlaps([window for window, _ in boxed], windows)), strict=True):
            (pr0, pr1, pc0, pc1), patch = boxed[i]
            wr0, wr1, wc0, wc1 = windows[j]
            r0, r1, c0, c1 = max(pr0, wr0), min(pr1, wr1), max(pc0, wc0), min(pc1, wc1)
            view = grid[r0:r1, c0:c1]
            np.maximum(view, patch.values[r0 - pr0:r1 - pr0, c0 - pc0:c1 - pc0], out=view)
