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

import numpy as np
from numpy.typing import ArrayLike, NDArray
from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from agents.lib.agenda.model import ActivityWindow

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
    t = np.asarray(times_s, dtype=np.float64)
    result = np.full(t.shape, params.r_min)
    span = params.r_max - params.r_min
    for window in _live(windows):
        value = np.where((t >= window.start_s) & (t <= window.end_s), params.r_max, params.r_min)
        if params.ramp_before_s > 0.0:
            before = (t < window.start_s) & (t > window.start_s - params.ramp_before_s)
            rising = params.r_min + span * (1.0 - (window.start_s - t) / params.ramp_before_s)
            value = np.where(before, rising, value)
        if params.ramp_after_s > 0.0:
            after = (t > window.end_s) & (t < window.end_s + params.ramp_after_s)
            falling = params.r_min + span * (1.0 - (t - window.end_s) / params.ramp_after_s)
            value = np.where(after, falling, value)
        result = np.maximum(result, value)
    return result


def r_of_t(t_s: float, windows: Sequence[ActivityWindow], params: ChronemicsParams) -> float:
    """R(t) of one object at one time."""
    return float(r_profile(np.array([t_s]), windows, params)[0])


def active_mask(times_s: ArrayLike, windows: Sequence[ActivityWindow]) -> NDArray[np.bool_]:
    """True where some non-cancelled activity runs: ``ActivityWindow.running_at`` at many times."""
    t = np.asarray(times_s, dtype=np.float64)
    result = np.zeros(t.shape, dtype=bool)
    for window in _live(windows):
        result |= (t >= window.start_s) & (t < window.end_s)
    return result


def is_active(t_s: float, windows: Sequence[ActivityWindow]) -> bool:
    return any(window.running_at(t_s) for window in windows)


def interaction_cost_profile(times_s: ArrayLike, windows: Sequence[ActivityWindow], params: ChronemicsParams,
                             forbidden_while_active: bool) -> NDArray[np.float64]:
    """The grid cost of an interaction space over time: R(t), or inf while active if forbidden."""
    cost = r_profile(times_s, windows, params)
    if forbidden_while_active:
        cost = np.where(active_mask(times_s, windows), math.inf, cost)
    return cost


def r_band(r: float, params: ChronemicsParams) -> int:
    """Index of the seed's colour band of ``r`` (0 = yellow ... 3 = dark orange); values outside
    the edges clamp to the first or last band; inf (forbidden) is the last band."""
    edges = params.band_edges
    index = int(np.searchsorted(np.asarray(edges[1:-1]), r, side="right"))
    return min(max(index, 0), len(edges) - 2)
