"""The demo's result tables: each mission as executed by the social planner vs a non-social baseline.

Why the baseline is planned, not driven: the seeds compare their social paths with a classical
planner's path between the same start and goal at the same time; we plan that baseline on the
same map with social costs off and drive it at the robot's cruise speed, so d_t, tau, CHC, d_min
and Psi are measured the same way for both (agents/social_navigation/metrics.py).
"""

from __future__ import annotations

import textwrap
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.table import Table

from agents.world.vocabulary import MissionState
from tools.plain import WHOLE_LINE


def build_report(scene: str | Path, run_dir: Path, missions: dict[str, dict[str, Any]]) -> dict[str, Any]:
    """Per mission: social and baseline metrics (model_dump of MetricsReport), measured from the
    run's per-mission slices (tools/system/mission_slices.py: cut now if the run has none yet)."""
    from agents.lib.metrics.metrics import TrajectoryFormatError, read_people_csv, read_trajectory_csv
    from agents.lib.planning.plan import plan
    from agents.lib.planning.search import PlanningError
    from agents.world.offline import OfflineError, SceneMaps, path_as_trajectory
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
    report["not_measured"] = {mid: _why_not_measured(m, mid in slices) for mid, m in missions.items()
                              if m.get("state") != MissionState.DONE or mid not in slices}
    for mission_id, piece in slices.items():
        if mission_id not in missions or missions[mission_id].get("state") != MissionState.DONE:
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


def _why_not_measured(mission: dict[str, Any], sliced: bool) -> str:
    state = str(mission.get("state", "not started"))
    reason = str(mission.get("reason") or "")
    if state == MissionState.DONE and not sliced:
        return "done, but the robot left fewer than 2 samples in its window"
    return f"{state}: {reason}" if reason else state


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
    from agents.lib.metrics.metrics import MetricsReport

    return MetricsReport(**metrics).to_table()


#: the baseline column's footnote (why its tau is not a time anyone drove, why it has no dynamic metrics)
BASELINE_NOTE = ("baseline: the non-social planner's path (walls and bodies only) between the same start and "
                 "goal, planned at the mission's start, not driven: it is measured as if driven at the robot's "
                 "cruise speed{speed}, so its tau is its length over that speed, and it has no metrics among "
                 "moving people (nobody moved around it).")


class _Notes:
    """Footnotes numbered in order of first use: a reason repeated in many cells is printed once."""

    def __init__(self) -> None:
        self.texts: dict[str, int] = {}

    def mark(self, text: str) -> str:
        return f"[{self.texts.setdefault(text, len(self.texts) + 1)}]"

    def cell(self, value: str) -> str:
        """A table cell: a missing value's ``- (why)`` becomes ``- [n]`` with the why in note n."""
        if value.startswith("- (") and value.endswith(")"):
            return f"- {self.mark(value[3:-1])}"
        return value


def mission_tables(report: dict[str, Any], notes: _Notes) -> list[tuple[str, list[tuple[str, str, str]]]]:
    """(title, [(metric, social, baseline)]) per mission of a report, missing values as footnote marks."""
    if not report["missions"]:
        return []
    speed = report.get("cruise_speed_mps")
    baseline_mark = notes.mark(BASELINE_NOTE.format(speed=f" ({speed:.2f} m/s)" if speed else ""))
    out = []
    for mission_id, entry in report["missions"].items():
        social = dict(_rows(entry["social"]))
        if "baseline" in entry:
            baseline = dict(_rows(entry["baseline"]))
            absent = f"- {baseline_mark}"
        else:
            baseline, absent = {}, f"- {notes.mark('no baseline path: ' + str(entry.get('baseline_error')))}"
        rows = [(label, notes.cell(value), notes.cell(baseline[label]) if label in baseline else absent)
                for label, value in social.items()]
        out.append((f"{report['scene']} / {mission_id}: social planner vs non-social baseline {baseline_mark} "
                    "(definitions: docs/metrics.md)", rows))
    return out


def render_report(report: dict[str, Any], console: Console) -> None:
    """The per-mission tables (social against baseline), then each footnote once and the missions
    not measured.  On a terminal rich tables; piped (a log, ``| less``) a plain layout whose names
    stay whole at the console's width (80 columns when stdout is not a terminal)."""
    if "error" in report:
        console.print(f"no metrics: {report['error']}", style="yellow", markup=False, highlight=False)
        return
    notes = _Notes()
    line = WHOLE_LINE    # paths and messages stay whole
    for title, rows in mission_tables(report, notes):
        if console.is_terminal:
            table = Table(title=title)
            table.add_column("metric (unit)")
            table.add_column("social", justify="right", no_wrap=True)
            table.add_column("baseline", justify="right", no_wrap=True)
            for row in rows:
                table.add_row(*row)
            console.print(table)
        else:
            for text in plain_table(title, ("metric (unit)", "social", "baseline"), rows, console.width):
                console.print(text, **line)
            console.print("", **line)
    for mission_id, why in report.get("not_measured", {}).items():
        console.print(f"{mission_id}: not measured ({why})", **line)
    width = console.width
    for text, number in notes.texts.items():
        for k, piece in enumerate(textwrap.wrap(f"[{number}] {text}", width - 4 if width > 40 else width)):
            console.print(piece if k == 0 else f"    {piece}", **line)


def plain_table(title: str, header: tuple[str, str, str], rows: list[tuple[str, str, str]], width: int) -> list[str]:
    """A table as plain lines of at most ``width`` characters: values right-aligned, labels wrapped
    between words (never inside one) when the line would be too long."""
    value_widths = [max(len(r[i]) for r in [header, *rows]) for i in (1, 2)]
    label_width = max(len(r[0]) for r in [header, *rows])
    label_width = max(20, min(label_width, width - sum(value_widths) - 4))
    lines = textwrap.wrap(title, width) + [""]
    for label, *values in [header, *rows]:
        wrapped = textwrap.wrap(label, label_width, break_long_words=False, break_on_hyphens=False) or [""]
        cells = "  ".join(f"{v:>{w}}" for v, w in zip(values, value_widths, strict=True))
        lines += [f"{piece:<{label_width}}" for piece in wrapped[:-1]]
        lines.append(f"{wrapped[-1]:<{label_width}}  {cells}".rstrip())
        if label == header[0]:
            lines.append("-" * min(width, label_width + sum(value_widths) + 4))
    return [text.rstrip() for text in lines]
