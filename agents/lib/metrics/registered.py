"""Mission metrics by name: what ``chronav evaluate`` measures on every done mission.

Why a registry: a researcher's measure (a comfort index, a legibility score) joins the study's
table beside chronav's, from their own package (group ``chronav.metrics``); chronav registers its
own catalogue there (metric_catalog.py, docs/metrics.md) as an outside package would.

Protocol: an entry point names a factory ``factory() -> MissionMetric``; ``measure(run)`` gets
one done mission (MissionRun: the scene file, the robot's trajectory rows t, x, y, theta in s, m,
m, rad, world frame, and the same rows' CSV file) and returns flat ``{column: value}`` floats (the
units belong in the column name or the metric's docstring).  A column another metric already
gave is refused for the later one; a metric that raises or returns non-numbers is reported and
its columns left empty for that mission.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from agents.lib import registry


@dataclass(frozen=True)
class MissionRun:
    """One done mission: where it ran and how the robot moved (rows t, x, y, theta)."""

    scene_file: Path
    trajectory: NDArray[np.float64]
    trajectory_csv: Path
    mission: str
    planner: str
    controller: str


@runtime_checkable
class MissionMetric(Protocol):
    """Measures a done mission: flat ``{column: float}``."""

    def measure(self, run: MissionRun) -> Mapping[str, float]: ...




def metric(name: str) -> MissionMetric:
    """The metric ``name``, built once per process; UnknownExtension or RefusedExtension."""
    return registry.built_once("metric", name, MissionMetric, "measure()")


def usable_metrics() -> tuple[dict[str, MissionMetric], list[registry.RefusedExtension]]:
    """Every installed metric that loads, and the refused ones (warned about at a study's start)."""
    good: dict[str, MissionMetric] = {}
    refused: list[registry.RefusedExtension] = []
    for name in registry.names("metric"):
        try:
            good[name] = metric(name)
        except registry.RefusedExtension as exc:
            refused.append(exc)
    return good, refused


def measure_all(run: MissionRun) -> tuple[dict[str, float], list[str]]:
    """Every usable metric on ``run``: the columns, and one problem line per metric that failed
    (raised, returned non-numbers, or a column another metric gave first)."""
    columns: dict[str, float] = {}
    problems: list[str] = []
    for name, found in usable_metrics()[0].items():
        try:
            values = dict(found.measure(run))
            clean = {str(k): float(v) for k, v in values.items()}
        except Exception as exc:  # noqa: BLE001 - a plug-in's failure is reported, the study goes on
            problems.append(f"metric {name!r} failed on mission {run.mission}: {type(exc).__name__}: {exc}")
            continue
        taken = sorted(set(clean) & set(columns))
        if taken:
            problems.append(f"metric {name!r}: column(s) {', '.join(taken)} already given by another metric; refused")
            clean = {k: v for k, v in clean.items() if k not in columns}
        columns.update(clean)
    return columns, problems
