"""A mission metric: how straight the robot went, straight-line distance over distance driven.

Implements chronav's MissionMetric protocol (agents/lib/metrics/registered.py): ``measure(run)``
gets a done mission (``run.trajectory`` rows t, x, y, theta in s, m, m, rad) and returns flat
columns; ``chronav evaluate`` adds them to its table beside chronav's own.
"""

from __future__ import annotations

import numpy as np

from agents.lib.metrics.registered import MissionRun


class PathEfficiency:
    """Path efficiency: straight-line distance from start to end over the distance driven (1 = straight)."""

    def measure(self, run: MissionRun) -> dict[str, float]:
        xy = np.asarray(run.trajectory, dtype=float)[:, 1:3]
        driven = float(np.hypot(*np.diff(xy, axis=0).T).sum()) if len(xy) > 1 else 0.0
        straight = float(np.hypot(*(xy[-1] - xy[0]))) if len(xy) else 0.0
        return {"example_path_efficiency": straight / driven if driven > 0 else float("nan")}
