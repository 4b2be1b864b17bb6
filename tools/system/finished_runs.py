"""Finished runs: the one a user names (``latest``, a run directory or a run id) and what it left.

Why apart from tools/system/runs.py: that module finds *live* runs to join (connect file, launcher
alive); a finished run is any directory with a ``result.json``, whatever ran it (a launch, an
in-process run, a ROS robot), and is only read: ``chronav report``, ``chronav metrics RUN``.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from tools.system.runs import RESULT_FILE, RunError, latest_finished_run, runs_dir


def find_finished_run(run: str, directory: Path | None = None) -> Path:
    """``latest`` (your newest finished run: runs.latest_finished_run, as `chronav export`), a run
    directory, or a run id under the runs directory."""
    directory = directory or runs_dir()
    if run == "latest":
        return latest_finished_run(directory)
    for candidate in (Path(run), directory / run):
        if candidate.is_dir():
            if not (candidate / RESULT_FILE).exists():
                raise RunError(f"run {candidate} has no {RESULT_FILE}: it is still going or never started; wait "
                               "for it to end (or give another run)")
            return candidate.absolute()
    raise RunError(f"{run!r}: no such run (looked at {Path(run)} and {directory / run}); give latest, a run "
                   "directory or a run id as `chronav launch` printed it")


def read_result(run_dir: Path) -> dict[str, Any]:
    """A finished run's ``result.json`` (its scene, missions, outcome)."""
    path = run_dir / RESULT_FILE
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise RunError(f"{path}: not readable as a run's result ({exc})") from None
    if not isinstance(data, dict) or not isinstance(data.get("missions"), dict):
        raise RunError(f"{path}: has no 'missions' object; is it a chronav run's result?")
    return data


def run_scene(run_dir: Path, result: dict[str, Any]) -> str:
    """The scene a run ran: the file it recorded, else its name (a scene of scenes/)."""
    path = result.get("scene_path")
    if isinstance(path, str) and Path(path).exists():
        return path
    scene = result.get("scene")
    if not isinstance(scene, str) or not scene:
        raise RunError(f"{run_dir / RESULT_FILE}: records no scene; give the scene: chronav metrics SCENE ...")
    return scene


def unknown_mission(mission: str, run_dir: Path, known: list[str]) -> RunError:
    """The error for a mission the run does not have, listing the ones it has."""
    listed = ", ".join(known) if known else "none (no mission of this run ended with the robot driving)"
    return RunError(f"--mission {mission!r}: run {run_dir.name} has no mission of that name it measured; its missions: {listed}")
