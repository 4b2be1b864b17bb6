"""The table of a study: one row per (scene, planner, seed, mission) with every metric of the mission.

Why the metrics come from ``metrics_offline`` on a per-mission trajectory file: the promise of
``chronav evaluate`` is that its numbers are what ``chronav metrics SCENE TRAJ.csv`` prints for the
same stretch of the run.  So each mission is measured on the run's slices of it (the robot's
``<run>/missions/<mission>.csv`` and the people's ``<mission>.people.csv`` beside it, written by
every run: tools/system/mission_slices.py) by the command's own library function, and *every*
number it returns becomes a column (nested names joined with a dot by the metrics library's ``flatten``:
``d_min_person_m.senior_1``).
A metric added to ``chronav metrics`` later (the dynamic ones of issue 15) becomes a column, a box
plot and a line of the report's tables without a change here.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

from agents.world.vocabulary import MissionState

#: columns that describe a row; every other column is a metric
META_COLUMNS: tuple[str, ...] = (
    "scene", "planner", "controller", "seed", "mission", "state", "reason", "refused", "mission_time_s", "started_s", "finished_s", "at_s",
    "trajectory_csv", "run_dir", "rrd", "host", "run_wall_s",
)
TABLE_STEM = "table"


def measure_mission(scene: str | Path, trajectory_csv: Path) -> tuple[float, dict[str, float]]:
    """(time the world is taken at, flat metrics) exactly as ``chronav metrics SCENE CSV --json``
    prints them for a mission's slice: the people's slice, the mission's start and its target are
    the ones ``chronav metrics`` finds beside the CSV (tools/system/mission_slices.py), so the
    ``dynamic.*`` metrics among the moving people are columns too."""
    from agents.lib.metrics.metrics import flatten
    from agents.world.offline import metrics_offline
    from tools.system.mission_slices import slice_inputs

    beside = slice_inputs(trajectory_csv)
    report = metrics_offline(scene, trajectory_csv, beside.at_s, beside.people_csv, goal_xy=beside.goal_xy)
    return float(report["at_s"]), flatten(report["metrics"])


AT_S_COLUMN = "at_s"
REFUSED_PREFIX = "plug-in refused"   # the navigation agent's failure reason for a refused plug-in


class ChronavMetrics:
    """chronav's catalogue: the seeds' path metrics, HuNavSim's and the dynamic ones (docs/metrics.md)."""

    def measure(self, run: Any) -> dict[str, float]:
        at_s, metrics = measure_mission(run.scene_file, run.trajectory_csv)
        return {AT_S_COLUMN: at_s, **metrics}


def mission_rows(*, scene: str | Path, planner: str, seed: int, run_dir: Path, rrd: str | None,
                 missions: Mapping[str, Mapping[str, Any]], host: str, run_wall_s: float,
                 controller: str = "elastic_band") -> list[dict[str, Any]]:
    """One row per mission of a finished run: its state, times and (when done) every installed
    metric's columns (agents/lib/metrics/registered.py; chronav's own catalogue is one of them),
    measured on the run's per-mission slices."""
    from agents.lib.metrics.metrics import read_trajectory_csv
    from agents.lib.metrics.registered import MissionRun, measure_all
    from tools.system.mission_slices import ensure_mission_slices

    slices = ensure_mission_slices(Path(run_dir), missions)
    rows = []
    for mission_id, mission in sorted(missions.items(), key=lambda kv: float(kv[1].get("time_s", 0.0))):
        row: dict[str, Any] = {
            "scene": Path(scene).stem, "planner": planner, "controller": controller, "seed": int(seed),
            "mission": mission_id,
            "state": str(mission.get("state")), "reason": str(mission.get("reason") or ""),
            # a plug-in (planner or controller) refused during the mission: counted by the study
            "refused": float(REFUSED_PREFIX in str(mission.get("reason") or "")),
            "mission_time_s": _num(mission.get("time_s")),
            "started_s": _num(mission.get("started_s")), "finished_s": _num(mission.get("finished_s")),
            "at_s": math.nan, "trajectory_csv": None, "run_dir": str(run_dir), "rrd": rrd, "host": host,
            "run_wall_s": float(run_wall_s),
        }
        piece = slices.get(mission_id)
        if piece is not None and row["state"] == MissionState.DONE:
            row["trajectory_csv"] = str(piece.trajectory_csv)
            run = MissionRun(scene_file=Path(scene), trajectory=read_trajectory_csv(piece.trajectory_csv),
                             trajectory_csv=piece.trajectory_csv, mission=mission_id, planner=planner,
                             controller=controller)
            metrics, problems = measure_all(run)
            row["at_s"] = metrics.pop(AT_S_COLUMN, math.nan)
            row.update(metrics)
            for problem in problems:
                print(f"warning: {problem}", file=sys.stderr)
        rows.append(row)
    return rows


def _num(value: Any) -> float:
    try:
        return float(value)
    except (TypeError, ValueError):
        return math.nan


def metric_columns(rows: Iterable[Mapping[str, Any]]) -> list[str]:
    """Every metric column present in any row, in first-seen order."""
    seen: dict[str, None] = {}
    for row in rows:
        for key in row:
            if key not in META_COLUMNS:
                seen.setdefault(key, None)
    return list(seen)


def headline_metric(metric: str) -> bool:
    """A metric of the whole mission (``d_t``, ``dynamic.min_distance_to_people_m``), not one of a
    person, object, band or group (``d_min_person_m.ann``, ``dynamic.intrusions_per_person.ann.personal``):
    the study's summary shows these; the per-mission tables show every column."""
    head, _, rest = metric.partition(".")
    return not rest or (head == "dynamic" and "." not in rest)


def to_arrow(rows: Sequence[Mapping[str, Any]]) -> Any:
    """The rows as a pyarrow Table: meta columns first, metrics after, missing metrics null."""
    import pyarrow as pa

    columns = [*META_COLUMNS, *metric_columns(rows)]
    data: dict[str, list[Any]] = {name: [] for name in columns}
    for row in rows:
        for name in columns:
            value = row.get(name)
            data[name].append(None if isinstance(value, float) and math.isnan(value) else value)
    types = {name: pa.string() for name in ("scene", "planner", "controller", "mission", "state", "reason",
                                            "trajectory_csv", "run_dir", "rrd", "host")}
    types["seed"] = pa.int64()
    arrays = [pa.array(data[name], type=types.get(name, pa.float64())) for name in columns]
    return pa.Table.from_arrays(arrays, names=columns)


def write_table(rows: Sequence[Mapping[str, Any]], out_dir: Path) -> tuple[Path, Path]:
    """``table.parquet`` and ``table.csv`` under ``out_dir`` (same columns, same rows)."""
    import pyarrow.csv as pacsv
    import pyarrow.parquet as pq

    table = to_arrow(rows)
    parquet, csv = out_dir / f"{TABLE_STEM}.parquet", out_dir / f"{TABLE_STEM}.csv"
    pq.write_table(table, parquet)
    pacsv.write_csv(table, csv)
    return parquet, csv


def read_table(path: Path) -> list[dict[str, Any]]:
    """A study's rows back from its Parquet file (nulls as NaN for metrics)."""
    import pyarrow.parquet as pq

    rows = pq.read_table(path).to_pylist()
    for row in rows:
        for key, value in row.items():
            if value is None and key not in META_COLUMNS:
                row[key] = math.nan
    return rows
