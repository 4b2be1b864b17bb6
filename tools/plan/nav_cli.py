"""`chronav path` (one social plan, no processes) and `chronav metrics` (a trajectory vs a scene).

Why offline commands: a care-home engineer tuning a scene wants to see, in a second, which route
the robot would take at 11:15 and how it scores, without launching six processes.  Both commands
build the social map exactly as the navigation agent does (agents/world/offline.py), and plan
with the same planners (``--planner``, agents/lib/socialmap/planners.py).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import typer


def _xy(text: str, option: str) -> tuple[float, float]:
    try:
        x, y = (float(v) for v in text.split(","))
    except ValueError:
        raise typer.BadParameter(f"expected X,Y in metres, got {text!r}", param_hint=option) from None
    if not (math.isfinite(x) and math.isfinite(y)):
        raise typer.BadParameter("coordinates must be finite", param_hint=option)
    return x, y


def _clock(text: str | None, option: str) -> float | None:
    from scenes.clock import parse_clock

    if text is None:
        return None
    try:
        return parse_clock(text)
    except ValueError as exc:
        _fail(f"{option}: {exc}")  # the same words as `chronav plan --at` (one clock parser)
    return None


def _planner(name: str | None, baseline: bool, departure_time: bool) -> str:
    """--planner NAME, or its older spellings --baseline / --departure-time (not both kinds at once)."""
    from agents.lib.socialmap.planners import DEFAULT_PLANNER, UnknownPlannerError, check_planner

    if baseline and departure_time:
        raise typer.BadParameter("give one of --baseline and --departure-time (or --planner NAME)",
                                 param_hint="--baseline")
    alias = "baseline" if baseline else "departure" if departure_time else None
    try:
        chosen = check_planner(name if name is not None else alias or DEFAULT_PLANNER)
    except UnknownPlannerError as exc:
        raise typer.BadParameter(str(exc), param_hint="--planner") from None
    if alias is not None and alias != chosen:
        flag = "--baseline" if baseline else "--departure-time"
        raise typer.BadParameter(f"--planner {chosen} contradicts {flag} (the {alias} planner)", param_hint=flag)
    return chosen


def _fail(message: str, code: int = 2) -> None:
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(code)


def path_command(scene: str = typer.Argument(..., help="scene file or name in scenes/"),
                 at: str = typer.Option(..., "--at", help="local time HH:MM of the plan"),
                 start: str = typer.Option(..., "--from", help="start X,Y (m)"),
                 goal: str = typer.Option(..., "--to", help="goal X,Y (m)"),
                 baseline: bool = typer.Option(False, "--baseline", help="non-social planner (walls and bodies only)"),
                 departure_time: bool = typer.Option(False, "--departure-time",
                                                     help="price interaction spaces at --at (the seeds), "
                                                          "not at the time the robot reaches them"),
                 planner: str = typer.Option(None, "--planner",
                                             help="social (default), departure, static, baseline or inflation "
                                                  "(docs/evaluate.md); --baseline and --departure-time are "
                                                  "the same as baseline and departure"),
                 method: str = typer.Option("astar", help="astar or dijkstra"),
                 as_json: bool = typer.Option(False, "--json", help="one JSON object on stdout")) -> None:
    """Plan one path on SCENE's social map at a given time and score it."""
    from agents.world.offline import OfflineError, plan_offline

    t_s = _clock(at, "--at")
    assert t_s is not None
    if method not in ("astar", "dijkstra"):
        raise typer.BadParameter("use astar or dijkstra", param_hint="--method")
    chosen = _planner(planner, baseline, departure_time)
    try:
        result = plan_offline(scene, t_s, _xy(start, "--from"), _xy(goal, "--to"), planner=chosen,
                              method=method)
    except OfflineError as exc:
        _fail(str(exc), 1 if exc.no_path else 2)
        return
    if as_json:
        typer.echo(json.dumps(result))
        return
    _print_path(result, chosen, t_s)


def _print_path(result: dict[str, Any], chosen: str, t_s: float) -> None:
    """The plan as a table: cost, length, Psi per zone and per interaction space, waypoint count."""
    from rich.console import Console
    from rich.table import Table

    from scenes.clock import format_clock

    table = Table(title=f"{chosen} path on {result['scene']} at {format_clock(t_s)}")
    table.add_column("quantity")
    table.add_column("value", justify="right")
    table.add_row("cost (cost-weighted m)", f"{result['cost']:.2f}")
    table.add_row("length (m)", f"{result['length_m']:.2f}")
    from agents.lib.socialmap.metric_catalog import column_label

    for key, value in result["metrics"]["psi_percent"].items():
        table.add_row(column_label(f"psi_zone_percent.{key}"), f"{value:.1f}")
    for name, value in result["metrics"]["psi_interaction_percent"].items():
        r = result["objects"][name]["R"]
        table.add_row(f"{column_label(f'psi_object_percent.{name}')}, R={r:.2f}", f"{value:.1f}")
    table.add_row("waypoints", str(len(result["points"])))
    Console().print(table)


def metrics_command(scene: str = typer.Argument(..., help="scene file or name in scenes/"),
                    trajectory: Path = typer.Argument(..., help="CSV with header t,x,y,theta (s, m, m, rad)"),
                    at: str = typer.Option(None, "--at", help="HH:MM for people and agenda (default: t of the "
                                                              "first sample if >= 1 h, else the scene's start)"),
                    people: Path = typer.Option(None, "--people", help="people's trajectories (header "
                                                "t,name,role,x,y,theta,vx,vy,group; s, -, -, m, m, rad, m/s, "
                                                "m/s, group label or empty; default: people.csv beside the "
                                                "trajectory, as a run writes it)"),
                    definitions: str = typer.Option("published", "--definitions",
                                                    help="published (the papers' definitions, chronav's names) "
                                                         "or hunav (HuNavSim's evaluator, its quirks and its "
                                                         "metric names; docs/metrics.md)"),
                    goal: str = typer.Option(None, "--goal", help="target X,Y (m) for completed and the "
                                                                  "distances to target"),
                    robot_radius: float = typer.Option(None, "--robot-radius", min=0.0,
                                                       help="robot radius (m; default: the scene's, or "
                                                            "HuNavSim's 0.35 with --definitions hunav)"),
                    person_radius: float = typer.Option(None, "--person-radius", min=0.0,
                                                        help="person radius (m; default 0.25, or HuNavSim's "
                                                             "0.35 with --definitions hunav)"),
                    as_json: bool = typer.Option(False, "--json", help="one JSON object on stdout")) -> None:
    """Social-navigation metrics of a trajectory, each with its unit and source (docs/metrics.md): the
    seeds' d_t, tau, CHC, d_min and Psi, and with the people's trajectories the metrics among moving
    people (distances, intrusions, forces, social work, collisions, speeds, target)."""
    from agents.lib.socialmap.metrics import MetricsInputError
    from agents.world.offline import OfflineError, metrics_offline

    if definitions not in ("published", "hunav"):
        raise typer.BadParameter("use published or hunav", param_hint="--definitions")
    try:
        report = metrics_offline(scene, trajectory, _clock(at, "--at"), people, definitions=definitions,
                                 goal_xy=None if goal is None else _xy(goal, "--goal"),
                                 robot_radius_m=robot_radius, person_radius_m=person_radius)
    except (OfflineError, MetricsInputError) as exc:
        _fail(str(exc))
        return
    if as_json:
        typer.echo(json.dumps({k: v for k, v in report.items() if k != "table"}))
        return
    from rich.console import Console
    from rich.table import Table

    table = Table(title=f"metrics of {trajectory} on {report['scene']} ({definitions} definitions)")
    table.add_column("metric (unit)")
    table.add_column("value", justify="right")
    for label, value in report["table"]:
        table.add_row(label, value)
    Console().print(table)


def register(app: typer.Typer) -> None:
    app.command("path")(path_command)
    app.command("metrics")(metrics_command)
