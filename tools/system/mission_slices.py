"""Each mission of a finished run cut out of it: ``<run>/missions/<mission>.csv`` (the robot),
``<mission>.people.csv`` (everyone, over the same stretch) and ``<mission>.json`` (what the
mission was: its goal, when it started and ended).

Why files, written by every run: a run's ``trajectory.csv`` and ``people.csv`` cover the whole day,
so measuring the day as one mission mixes the 09:00 world with a path driven until 17:20.  With
the slices on disk, ``chronav metrics``, ``chronav report`` and ``chronav evaluate`` measure each
mission from the same three files, without re-running anything, and give the same numbers.  A
mission's slices sit together, so ``chronav metrics SCENE <run>/missions/m.csv`` finds the people
and the goal beside the trajectory (``slice_inputs``).

One code path for every kind of run: the launcher and the in-process runner both end in
``tools.launch._write_result``, which calls ``ensure_mission_slices``; the demo's report and the
study's table call it too, so a run written before the slices existed gets them when first read.
"""

from __future__ import annotations

import hashlib
import json
import math
import re
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

#: the folder of a run that holds its missions' slices
MISSIONS_DIR = "missions"
#: the people's slice of ``<mission>.csv`` is ``<mission>.people.csv`` beside it
PEOPLE_SUFFIX = ".people"
#: mission ids used as file names as they are (anything else: slice_stem)
_SAFE_STEM = re.compile(r"[A-Za-z0-9_-]{1,100}")
#: margin on each side of a mission's window (the clock's float sums)
WINDOW_EPS_S = 1e-6


@dataclass(frozen=True)
class MissionSlice:
    """Where a mission's slices are, and what measuring them needs besides the scene."""

    mission: str
    trajectory_csv: Path
    people_csv: Path | None            # None when the run recorded nobody's trajectory
    started_s: float
    finished_s: float
    goal_xy: tuple[float, float] | None
    goal_missing: str                  # why there is no target point ("" when there is one)


@dataclass(frozen=True)
class SliceInputs:
    """What ``chronav metrics`` takes from beside a trajectory CSV when the user did not say."""

    people_csv: Path | None
    at_s: float | None
    goal_xy: tuple[float, float] | None


def slice_stem(mission_id: str) -> str:
    """The file name (without extension) of a mission's slices: the id itself when it is made of
    letters, digits, ``_`` and ``-``; otherwise those characters and a hash of the id.

    Why: a mission id is any printable name (scenes/names.py), and ``a/../b`` or ``x.people`` must
    neither leave ``missions/`` nor take another mission's people slice."""
    if _SAFE_STEM.fullmatch(mission_id):
        return mission_id
    cleaned = re.sub(r"[^A-Za-z0-9_-]+", "_", mission_id)[:60].strip("_") or "mission"
    return f"{cleaned}-{hashlib.sha256(mission_id.encode('utf-8')).hexdigest()[:10]}"


def slice_paths(run_dir: Path, mission_id: str) -> tuple[Path, Path, Path]:
    """(robot CSV, people CSV, mission JSON) of one mission of a run."""
    base, stem = Path(run_dir) / MISSIONS_DIR, slice_stem(mission_id)
    return base / f"{stem}.csv", base / f"{stem}{PEOPLE_SUFFIX}.csv", base / f"{stem}.json"


def mission_target(mission: Mapping[str, Any]) -> tuple[tuple[float, float] | None, str]:
    """A mission's target point (a pose mission's x, y) or None and why (room, person, object goals
    have no single point: completed and the distances to target are then not measured)."""
    goal = str(mission.get("goal", ""))
    kind, _, argument = goal.partition(":")
    if kind == "pose":
        try:
            x, y = (float(v) for v in argument.split(",")[:2])
            return (x, y), ""
        except ValueError:
            pass
    return None, f"a {kind or 'mission'} goal has no single target point"


def mission_window(trajectory: np.ndarray, started_s: float, finished_s: float) -> np.ndarray:
    """The rows of an (N, >=1) array whose time (column 0) lies in the mission's window."""
    mask = (trajectory[:, 0] >= started_s - WINDOW_EPS_S) & (trajectory[:, 0] <= finished_s + WINDOW_EPS_S)
    return trajectory[mask]


def ended_window(mission: Mapping[str, Any]) -> tuple[float, float] | None:
    """(started_s, finished_s) of a mission that started and ended, else None."""
    try:
        started, finished = float(mission["started_s"]), float(mission["finished_s"])
    except (KeyError, TypeError, ValueError):
        return None
    return (started, finished) if math.isfinite(started) and math.isfinite(finished) else None


def write_trajectory_csv(rows: np.ndarray, path: Path) -> int:
    """``t,x,y,theta`` rows as a CSV (Python floats' repr: read back bit for bit); how many."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", encoding="utf-8") as handle:
        handle.write("t,x,y,theta\n")
        for t, x, y, theta in rows.tolist():
            handle.write(f"{t!r},{x!r},{y!r},{theta!r}\n")
    return len(rows)


def _write_people_slices(people_csv: Path, windows: Mapping[str, tuple[float, float]],
                         targets: Mapping[str, Path]) -> None:
    """Copy each line of the run's people.csv into the slice of every mission whose window holds
    its time (the lines as written: nothing re-formatted).  One pass over the file."""
    handles = {}
    try:
        with people_csv.open(encoding="utf-8") as source:
            header = source.readline()
            for mission_id, path in targets.items():
                handles[mission_id] = path.open("w", encoding="utf-8")
                handles[mission_id].write(header)
            for line in source:
                try:
                    t = float(line.split(",", 1)[0])
                except ValueError:
                    continue   # blank or damaged line: the reader of the whole file reports it
                for mission_id, (started, finished) in windows.items():
                    if started - WINDOW_EPS_S <= t <= finished + WINDOW_EPS_S:
                        handles[mission_id].write(line)
    finally:
        for handle in handles.values():
            handle.close()


def write_mission_slices(run_dir: Path, missions: Mapping[str, Mapping[str, Any]]) -> dict[str, MissionSlice]:
    """Cut every mission that started and ended out of the run's ``trajectory.csv`` and
    ``people.csv``; the slices written (missions with fewer than 2 robot samples get none)."""
    from agents.lib.metrics.metrics import MetricsInputError, read_trajectory_csv

    run_dir = Path(run_dir)
    try:
        trajectory = read_trajectory_csv(run_dir / "trajectory.csv")
    except (MetricsInputError, OSError):
        return {}    # stopped before the robot drove, or a damaged file: no mission has samples
    windows = {mid: w for mid, m in missions.items() if (w := ended_window(m)) is not None}
    written: dict[str, MissionSlice] = {}
    for mission_id, (started, finished) in windows.items():
        robot_csv, people_csv, info_json = slice_paths(run_dir, mission_id)
        if write_trajectory_csv(mission_window(trajectory, started, finished), robot_csv) < 2:
            robot_csv.unlink()
            continue
        mission = missions[mission_id]
        goal_xy, why = mission_target(mission)
        info = {"mission": mission_id, "goal": mission.get("goal"), "goal_xy": goal_xy, "goal_missing": why,
                "state": mission.get("state"), "time_s": mission.get("time_s"), "started_s": started,
                "finished_s": finished, "trajectory": robot_csv.name, "people": people_csv.name}
        info_json.write_text(json.dumps(info, indent=2), encoding="utf-8")
        written[mission_id] = MissionSlice(mission_id, robot_csv, people_csv, started, finished, goal_xy, why)
    people = run_dir / "people.csv"
    if written and people.exists():
        _write_people_slices(people, {m: windows[m] for m in written},
                             {m: s.people_csv for m, s in written.items() if s.people_csv is not None})
    else:
        written = {m: _without_people(s) for m, s in written.items()}
    return written


def _without_people(found: MissionSlice) -> MissionSlice:
    if found.people_csv is not None and found.people_csv.exists():
        found.people_csv.unlink()    # a stale slice of an earlier write
    return MissionSlice(found.mission, found.trajectory_csv, None, found.started_s, found.finished_s,
                        found.goal_xy, found.goal_missing)


def read_mission_slices(run_dir: Path) -> dict[str, MissionSlice]:
    """The slices a run holds, by mission (from each ``<mission>.json``), in start order."""
    found = []
    for info_json in sorted((Path(run_dir) / MISSIONS_DIR).glob("*.json")):
        try:
            info = json.loads(info_json.read_text(encoding="utf-8"))
            mission_id = str(info["mission"])
            started, finished = float(info["started_s"]), float(info["finished_s"])
        except (OSError, ValueError, KeyError, TypeError):
            continue
        robot_csv, people_csv, _ = slice_paths(run_dir, mission_id)
        if not robot_csv.exists():
            continue
        goal = info.get("goal_xy")
        goal_xy = (float(goal[0]), float(goal[1])) if isinstance(goal, list) and len(goal) == 2 else None
        found.append(MissionSlice(mission_id, robot_csv, people_csv if people_csv.exists() else None, started,
                                  finished, goal_xy, str(info.get("goal_missing") or "")))
    return {s.mission: s for s in sorted(found, key=lambda s: s.started_s)}


def ensure_mission_slices(run_dir: Path, missions: Mapping[str, Mapping[str, Any]]) -> dict[str, MissionSlice]:
    """The run's slices, cut now if any ended mission has none yet (a run from before the slices)."""
    held = read_mission_slices(run_dir)
    if all(mid in held for mid, m in missions.items() if ended_window(m) is not None):
        return held
    return write_mission_slices(run_dir, missions)


def slice_inputs(trajectory_csv: Path) -> SliceInputs:
    """For a mission's slice: its people's slice, its start (the time its world is taken at) and
    its target, from the files beside it; for any other CSV, ``people.csv`` beside it (a run's
    whole day) and nothing else."""
    trajectory_csv = Path(trajectory_csv)
    people = trajectory_csv.with_name(f"{trajectory_csv.stem}{PEOPLE_SUFFIX}.csv")
    info_json = trajectory_csv.with_suffix(".json")
    if info_json.exists() and trajectory_csv.parent.name == MISSIONS_DIR:
        try:
            info = json.loads(info_json.read_text(encoding="utf-8"))
            goal = info.get("goal_xy")
            return SliceInputs(people if people.exists() else None, float(info["started_s"]),
                               (float(goal[0]), float(goal[1])) if isinstance(goal, list) and len(goal) == 2 else None)
        except (OSError, ValueError, KeyError, TypeError):
            pass
    if people.exists():
        return SliceInputs(people, None, None)
    whole_day = trajectory_csv.with_name("people.csv")
    return SliceInputs(whole_day if whole_day.exists() else None, None, None)
