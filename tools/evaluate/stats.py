"""A study's numbers: mean +- std per planner (the seeds' tables) and a paired test per metric.

Why a paired Wilcoxon signed-rank test (scipy.stats.wilcoxon, two-sided): the planners are run on
the same (scene, mission, seed), so the natural unit is the difference per pair; with a handful of
seeds nothing justifies assuming those differences are normal (a paired t-test), and Wilcoxon
uses their signs and ranks only.  Pairs whose difference is zero are dropped (``zero_method=
"wilcox"``); when every pair ties there is nothing to test and the p-value is left empty.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from agents.world.vocabulary import MissionState
from tools.evaluate.table import metric_columns

REFERENCE = "social"
MissionKey = tuple[str, str]         # (scene, mission)


@dataclass(frozen=True)
class Summary:
    """One cell of a seeds' table: a metric of one planner on one mission, over the seeds."""

    scene: str
    mission: str
    planner: str
    metric: str
    n: int
    mean: float
    std: float        # sample standard deviation (ddof=1); NaN with fewer than 2 values


@dataclass(frozen=True)
class PairedTest:
    """Wilcoxon signed-rank test of ``planner`` vs ``other`` on one metric, paired by
    (scene, mission, seed)."""

    metric: str
    planner: str
    other: str
    pairs: int
    nonzero: int
    median_difference: float     # median of planner - other
    statistic: float
    p_value: float               # NaN when there is nothing to test


def done_rows(rows: Sequence[Mapping[str, Any]]) -> list[Mapping[str, Any]]:
    return [row for row in rows if row.get("state") == MissionState.DONE]


def summarise(rows: Sequence[Mapping[str, Any]]) -> list[Summary]:
    """Mean and std of every metric per (scene, mission, planner), over the seeds (done missions)."""
    groups: dict[tuple[str, str, str], list[Mapping[str, Any]]] = {}
    for row in done_rows(rows):
        groups.setdefault((row["scene"], row["mission"], row["planner"]), []).append(row)
    metrics = metric_columns(rows)
    out = []
    for (scene, mission, planner), members in groups.items():
        for metric in metrics:
            values = np.array([float(r.get(metric, math.nan)) for r in members], dtype=float)
            values = values[np.isfinite(values)]
            if not len(values):
                continue
            std = float(np.std(values, ddof=1)) if len(values) > 1 else math.nan
            out.append(Summary(scene, mission, planner, metric, len(values), float(np.mean(values)), std))
    return out


def paired_tests(rows: Sequence[Mapping[str, Any]], planner: str = REFERENCE) -> list[PairedTest]:
    """``planner`` against every other planner of the study, per metric, paired by (scene, mission, seed)."""
    from scipy.stats import wilcoxon

    by_pair: dict[tuple[str, str, str, int], Mapping[str, Any]] = {}
    planners: list[str] = []
    for row in done_rows(rows):
        by_pair[(row["planner"], row["scene"], row["mission"], int(row["seed"]))] = row
        if row["planner"] not in planners:
            planners.append(row["planner"])
    if planner not in planners:
        return []
    out = []
    for other in (p for p in planners if p != planner):
        for metric in metric_columns(rows):
            diffs = []
            for (name, scene, mission, seed), row in by_pair.items():
                partner = by_pair.get((other, scene, mission, seed))
                if name != planner or partner is None:
                    continue
                a, b = float(row.get(metric, math.nan)), float(partner.get(metric, math.nan))
                if math.isfinite(a) and math.isfinite(b):
                    diffs.append(a - b)
            if not diffs:
                continue
            d = np.array(diffs)
            nonzero = int(np.count_nonzero(d))
            statistic = p_value = math.nan
            if nonzero:
                with warnings.catch_warnings():    # "exact p-value not possible with zeros": it falls back itself
                    warnings.simplefilter("ignore", UserWarning)
                    result = wilcoxon(d, zero_method="wilcox", alternative="two-sided")
                statistic, p_value = float(result.statistic), float(result.pvalue)
            out.append(PairedTest(metric, planner, other, len(d), nonzero, float(np.median(d)), statistic, p_value))
    return out


def missions_of(rows: Sequence[Mapping[str, Any]]) -> list[MissionKey]:
    """(scene, mission) in the order of the table (by scene, then mission time)."""
    seen: dict[MissionKey, float] = {}
    for row in rows:
        key = (row["scene"], row["mission"])
        t = float(row.get("mission_time_s") or 0.0)
        seen[key] = min(seen.get(key, t), t)
    return sorted(seen, key=lambda k: (k[0], seen[k]))


def planners_of(rows: Sequence[Mapping[str, Any]], order: Sequence[str] = ()) -> list[str]:
    found = {row["planner"] for row in rows}
    return [p for p in order if p in found] + sorted(found - set(order))
