"""The demo's result tables: each mission as executed by the social planner vs a non-social baseline.

Why the baseline is planned, not driven: the seeds compare their social paths with a classical
planner's path between the same start and goal at the same time; we plan that baseline on the
same map with social costs off and drive it at the robot's cruise speed, so d_t, tau, CHC, d_min
and Psi are measured the same way for both (agents/social_navigation/metrics.py).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from rich.console import Console
from rich.table import Table

from agents.world.vocabulary import MissionState


def build_report(scene: str | Path, run_dir: Path, missions: dict[str, dict[str, Any]]) -> dict[str, Any]:
    """Per mission: social and baseline metrics (model_dump of MetricsReport), measured from the
    run's per-mission slices (tools/system/mission_slices.py: cut now if the run has none yet)."""
    from agents.lib.socialmap.metrics import TrajectoryFormatError, read_people_csv, read_trajectory_csv
    from agents.world.offline import OfflineError, SceneMaps, path_as_trajectory
    from agents.lib.socialmap.search import PlanningError
    from agents.lib.socialmap.social_map import plan
    from tools.system.mission_slices import ensure_mission_slices

    traj_path = Path(run_dir) / "trajectory.csv"
    report: dict[str, Any] = {"scene": Path(scene).stem, "missions": {}}
    if not traj_path.exists():
        report["error"] = "no trajectory was recorded"
        return report
    try:
        read_trajectory_csv(traj_path)
    except TrajectoryFormatError as exc:   # e.g. stopped before the robot's first sample
        report["error"] = f"no usable trajectory was recorded ({exc})"
        return report
    try:
        maps = SceneMaps.load(scene)
    except OfflineError as exc:
        report["error"] = str(exc)
        return report
    report["scene"] = maps.world.scene.name
    slices = ensure_mission_slices(Path(run_dir), missions)
    for mission_id, piece in slices.items():
        if missions.get(mission_id, {}).get("state") != MissionState.DONE:
            continue
        social = read_trajectory_csv(piece.trajectory_csv)
        try:   # the people's trajectories, for HuNavSim's dynamic metrics of each mission
            tracks = read_people_csv(piece.people_csv) if piece.people_csv is not None else None
        except TrajectoryFormatError:
            tracks = None
        started = piece.started_s
        entry: dict[str, Any] = {"social": maps.measure(social, started, tracks, goal_xy=piece.goal_xy,
                                                        goal_missing=piece.goal_missing).model_dump()}
        smap = maps.at(started)
        try:
            base = plan(smap, tuple(social[0, 1:3]), tuple(social[-1, 1:3]), planner="baseline")
            baseline_traj = path_as_trajectory(base.points_m, started, maps.cruise_speed)
            entry["baseline"] = maps.measure(baseline_traj, started).model_dump()
        except PlanningError as exc:
            entry["baseline_error"] = str(exc)
        report["missions"][mission_id] = entry
    report["cruise_speed_mps"] = maps.cruise_speed
    return report


def log_report(recorder: Any, report: dict[str, Any], missions: dict[str, dict[str, Any]]) -> None:
    """The metrics as scalars in the recording, at each mission's end, social and baseline side by side."""
    if not recorder.enabled:
        return
    for mission_id, entry in report.get("missions", {}).items():
        recorder.set_time(float(missions[mission_id]["finished_s"]))
        for planner in ("social", "baseline"):
            metrics = entry.get(planner)
            if metrics is None:
                continue
            base = f"metrics/missions/{planner}"
            recorder.scalar(f"{base}/d_t_m", metrics["distance_travelled_m"])
            recorder.scalar(f"{base}/tau_s", metrics["duration_s"])
            recorder.scalar(f"{base}/chc_rad", metrics["cumulative_heading_change_rad"])
            for band, value in metrics["psi_zone_percent"].items():
                recorder.scalar(f"{base}/psi_{band}_pct", value)
            for name, value in metrics["psi_object_percent"].items():
                recorder.scalar(f"{base}/psi_space_{name}_pct", value)
            people = metrics["d_min_person_m"]
            if people:
                recorder.scalar(f"{base}/d_min_person_m", min(people.values()))


def _rows(metrics: dict[str, Any]) -> list[tuple[str, str]]:
    from agents.lib.socialmap.metrics import MetricsReport

    return MetricsReport(**metrics).to_table()


def render_report(report: dict[str, Any], console: Console) -> None:
    if "error" in report:
        console.print(f"[yellow]no metrics: {report['error']}[/yellow]")
        return
    for mission_id, entry in report["missions"].items():
        table = Table(title=f"{report['scene']} / {mission_id}: social planner vs non-social baseline "
                            "(definitions: docs/metrics.md)")
        table.add_column("metric (unit)")
        table.add_column("social", justify="right")
        table.add_column("non-social", justify="right")
        social = dict(_rows(entry["social"]))
        baseline = dict(_rows(entry["baseline"])) if "baseline" in entry else {}
        for label, value in social.items():   # the baseline is planned, not driven: nobody moved around it
            table.add_row(label, value, baseline.get(label, "- (planned path, not driven among people)"))
        console.print(table)
