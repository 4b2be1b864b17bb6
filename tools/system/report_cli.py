"""``chronav report RUN``: the demo's per-mission tables (social against baseline) for any finished run.

Why from the run's slices and nothing else: a launch, an in-process run or a ROS robot's run leaves
``<run>/missions/<mission>.csv`` and ``.people.csv`` (tools/system/mission_slices.py), so a run is
measured after the fact as the demo measures it live, with the same code (tools/system/report.py),
without running anything again.
"""

from __future__ import annotations

import json
from typing import Any

import typer


def report_command(run: str = typer.Argument("latest", help="a finished run: latest (the newest), its directory "
                                             "or its id"),
                   mission: str = typer.Option(None, "--mission", help="only this mission (default: every one)"),
                   as_json: bool = typer.Option(False, "--json", help="one JSON object on stdout")) -> None:
    """Social planner against the non-social baseline, per mission, for a finished run (never re-run)."""
    from rich.console import Console

    from tools.system.finished_runs import find_finished_run, read_result, run_scene, unknown_mission
    from tools.system.report import build_report, render_report
    from tools.system.runs import RunError

    try:
        run_dir = find_finished_run(run)
        result = read_result(run_dir)
        missions: dict[str, dict[str, Any]] = result["missions"]
        if mission is not None:
            if mission not in missions:
                raise unknown_mission(mission, run_dir, list(missions))
            missions = {mission: missions[mission]}
        report = build_report(run_scene(run_dir, result), run_dir, missions)
    except RunError as exc:
        typer.echo(f"error: {exc}", err=True)
        raise typer.Exit(2) from None
    report["run_dir"] = str(run_dir)
    if as_json:
        typer.echo(json.dumps(report))
    else:
        render_report(report, Console())
    if "error" in report:
        raise typer.Exit(1)


def register(app: typer.Typer) -> None:
    app.command("report")(report_command)
