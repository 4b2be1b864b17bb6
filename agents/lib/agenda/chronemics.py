"""R(t): the cost of an object's interaction space as a function of its agenda (seed section 4.2,
Fig. 8; affordance seed Fig. 6).

R = R_min with nothing scheduled or the next start more than ``ramp_before_s`` ahead; it rises
linearly to R_max at the start, stays R_max while the activity runs, and falls back linearly over
``ramp_after_s`` after the end ("decreases in the same way that it increased"). Overlapping
activities on one object take the maximum; cancelled ones are ignored. With the object's
``forbidden_while_active`` flag the space is an obstacle (infinite cost) while an activity runs.

Why linear ramps: Fig. 8 shows a monotone rise from 1.5 at 45 min before the start to 3.5 at the
start; the text gives only the end points, and a linear ramp is the simplest curve through them.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray
from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from agents.lib.agenda.model import ActivityWindow

_Scalar = TypeVar("_Scalar", bound=np.generic)

BAND_NAMES: tuple[str, ...] = ("yellow", "dark_yellow", "orange", "dark_orange")
BAND_COLOURS_RGB: tuple[tuple[int, int, int], ...] = ((255, 235, 59), (251, 192, 45), (255, 152, 0), (230, 81, 0))


class ChronemicsParams(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)

    r_min: float = Field(1.5, gt=0, description="cost with nothing scheduled (seed 5.2.2)")
    r_max: float = Field(3.5, gt=0, description="cost while an activity runs (seed 5.2.2)")
    ramp_before_s: float = Field(45 * 60.0, ge=0, description="rise from r_min to r_max before the start")
    ramp_after_s: float = Field(45 * 60.0, ge=0, description="fall back to r_min after the end")
    band_edges: tuple[float, ...] = Field((1.5, 2.0, 2.5, 3.0, 3.5),
                                          description="colour bands [e0,e1) [e1,e2) [e2,e3) [e3,e4]")

    @model_validator(mode="after")
    def _order(self) -> ChronemicsParams:
        if self.r_max < self.r_min:
            raise ValueError("r_max must be >= r_min")
        return self

    @field_validator("band_edges")
    @classmethod
    def _increasing(cls, value: tuple[float, ...]) -> tuple[float, ...]:
        if len(value) < 2 or any(b <= a for a, b in zip(value, value[1:], strict=False)):
            raise ValueError("band_edges must be at least two strictly increasing numbers")
        return value


# An activity is "upcoming" while its object's R(t) is already rising towards the start.
UPCOMING_WINDOW_S = ChronemicsParams().ramp_before_s


def _live(windows: Iterable[ActivityWindow]) -> list[ActivityWindow]:
    return [w for w in windows if not w.cancelled]


def r_profile(times_s: ArrayLike, windows: Sequence[ActivityWindow], params: ChronemicsParams) -> NDArray[np.float64]:
    """R(t) at many times at once (the planner samples it along arrival times)."""
    return r_profiles(times_s, [windows], params)[0]


def r_profiles(times_s: ArrayLike, windows: Sequence[Sequence[ActivityWindow]],
               params: ChronemicsParams) -> NDArray[np.float64]:
    """R(t) of several objects (``windows[k]``: object k's activities) at many times: row k is
    object k's. Why all at once and in few array passes: the planner samples every interaction
    space over its arrival-time horizon on each (re)plan (15 objects x 1,200 times at 1000^2), and
    one object at a time, a dozen passes each, took 0.6 ms of a 2.7 ms replan."""
    t = np.asarray(times_s, dtype=np.float64)
    found = _Windows.of(windows, t.ndim)
    result = np.full((len(windows), *t.shape), params.r_min)
    if not found.owners:
        return result
    # How many ramps t lies outside each window: (start - t) / ramp_before before it, (t - end) /
    # ramp_after after it, <= 0 inside. R falls with it, so an object's dearest window is the one
    # where it is smallest; R = r_max - (r_max - r_min) * clip(outside, 0, 1).
    outside = _ramps_outside(found.starts, t, params.ramp_before_s, -1.0)
    np.maximum(outside, _ramps_outside(found.ends, t, params.ramp_after_s, 1.0), out=outside)
    outside = found.per_owner(outside, np.minimum)
    np.clip(outside, 0.0, 1.0, out=outside)
    outside *= params.r_max - params.r_min
    result[found.owners] = np.subtract(params.r_max, outside, out=outside)
    return result


def _ramps_outside(edges: NDArray[np.float64], t: NDArray[np.float64], ramp_s: float,
                   side: float) -> NDArray[np.float64]:
    """``side * (t - edge) / ramp_s`` for each window's edge (a column) and time: how many ramps t
    lies beyond the edge on ``side`` (-1: before a start, +1: after an end); with no ramp, +inf
    beyond the edge and -inf elsewhere."""
    if ramp_s > 0.0:
        scale = side / ramp_s
        return t * scale - edges * scale
    return np.where(side * (t - edges) > 0.0, np.inf, -np.inf)


@dataclass(frozen=True, slots=True)
class _Windows:
    """The live windows of several objects as columns that broadcast against the times."""

    starts: NDArray[np.float64]
    ends: NDArray[np.float64]
    owners: list[int]      # the objects with a live window, in order
    first: list[int]       # where each owner's windows start in starts/ends
    single: bool           # one window per owner

    @staticmethod
    def of(windows: Sequence[Sequence[ActivityWindow]], ndim: int) -> _Windows:
        live = [_live(own) for own in windows]
        flat = [w for own in live for w in own]
        shape = (len(flat),) + (1,) * ndim
        owners, first, at = [], [], 0
        for k, own in enumerate(live):
            if own:
                owners.append(k)
                first.append(at)
                at += len(own)
        return _Windows(starts=np.array([w.start_s for w in flat], dtype=np.float64).reshape(shape),
                        ends=np.array([w.end_s for w in flat], dtype=np.float64).reshape(shape),
                        owners=owners, first=first, single=len(flat) == len(owners))

    def per_owner(self, values: NDArray[_Scalar], reduce: np.ufunc) -> NDArray[_Scalar]:
        """``values`` (one row per window) reduced to one row per owner."""
        return values if self.single else reduce.reduceat(values, self.first, axis=0)


def r_of_t(t_s: float, windows: Sequence[ActivityWindow], params: ChronemicsParams) -> float:
    """R(t) of one object at one time."""
    return float(r_profile(np.array([t_s]), windows, params)[0])


def active_mask(times_s: ArrayLike, windows: Sequence[ActivityWindow]) -> NDArray[np.bool_]:
    """True where some non-cancelled activity runs: ``ActivityWindow.running_at`` at many times."""
    return active_masks(times_s, [windows])[0]


def active_masks(times_s: ArrayLike, windows: Sequence[Sequence[ActivityWindow]]) -> NDArray[np.bool_]:
    """``active_mask`` of several objects at once (row k: ``windows[k]``)."""
    t = np.asarray(times_s, dtype=np.float64)
    found = _Windows.of(windows, t.ndim)
    result = np.zeros((len(windows), *t.shape), dtype=bool)
    if found.owners:
        result[found.owners] = found.per_owner((t >= found.starts) & (t < found.ends), np.logical_or)
    return result


def is_active(t_s: float, windows: Sequence[ActivityWindow]) -> bool:
    return any(window.running_at(t_s) for window in windows)


def interaction_cost_profile(times_s: ArrayLike, windows: Sequence[ActivityWindow], params: ChronemicsParams,
                             forbidden_while_active: bool) -> NDArray[np.float64]:
    """The grid cost of an interaction space over time: R(t), or inf while active if forbidden."""
    return interaction_cost_profiles(times_s, [windows], params, [forbidden_while_active])[0]


def interaction_cost_profiles(times_s: ArrayLike, windows: Sequence[Sequence[ActivityWindow]],
                              params: ChronemicsParams, forbidden_while_active: Sequence[bool]) -> NDArray[np.float64]:
    """``interaction_cost_profile`` of several objects at once (row k: ``windows[k]`` and
    ``forbidden_while_active[k]``)."""
    if len(forbidden_while_active) != len(windows):
        raise ValueError("one forbidden_while_active flag per object's windows")
    cost = r_profiles(times_s, windows, params)
    forbidden = [k for k, flag in enumerate(forbidden_while_active) if flag]
    if forbidden:
        active = active_masks(times_s, [windows[k] for k in forbidden])
        cost[forbidden] = np.where(active, math.inf, cost[forbidden])
    return cost


def r_band(r: float, params: ChronemicsParams) -> int:
    """Index of the seed's colour band of ``r`` (0 = yellow ... 3 = dark orange); values outside
    the edges clamp to the first or last band; inf (forbidden) is the last band."""
    edges = params.band_edges
    index = int(np.searchsorted(np.asarray(edges[1:-1]), r, side="right"))
    return min(max(index, 0), len(edges) - 2)
