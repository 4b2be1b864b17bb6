"""`chronav path` (one social plan, no processes) and `chronav metrics` (a trajectory vs a scene).

Why offline commands: a care-home engineer tuning a scene wants to see, in a second, which route
the robot would take at 11:15 and how it scores, without launching six processes.  Both commands
build the social map exactly as the navigation agent does (agents/world/offline.py), and plan
with the same planners (``--planner``, agents/lib/planning/planners.py).
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
    from agents.lib.planning.planners import DEFAULT_PLANNER, planner
    from agents.lib.registry import RefusedExtension, UnknownExtension

    if baseline and departure_time:
        raise typer.BadParameter("give one of --baseline and --departure-time (or --planner NAME)",
                                 param_hint="--baseline")
    alias = "baseline" if baseline else "departure" if departure_time else None
    try:
        chosen = name if name is not None else alias or DEFAULT_PLANNER
        planner(chosen)
    except (UnknownExtension, RefusedExtension) as exc:
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
                                             help="a registered planner (`chronav plugins` lists them; social by "
                                                  "default; docs/evaluate.md); --baseline and --departure-time "
                                                  "are the same as baseline and departure"),
                 method: str = typer.Option("astar", help="astar or dijkstra"),
                 controller: str = typer.Option(None, "--controller",
                                                help="also drive this local controller along the path, offline "
                                                     "(people stand where the map has them; `chronav plugins` "
                                                     "lists the controllers)"),
                 as_json: bool = typer.Option(False, "--json", help="one JSON object on stdout")) -> None:
    """Plan one path on SCENE's social map at a given time and score it (and drive a controller along it)."""
    from agents.world.offline import OfflineError, plan_offline

    t_s = _clock(at, "--at")
    assert t_s is not None
    if method not in ("astar", "dijkstra"):
        raise typer.BadParameter("use astar or dijkstra", param_hint="--method")
    chosen = _planner(planner, baseline, departure_time)
    if controller is not None:
        from tools.system.launch_cli import check_controller

        check_controller(controller, "--controller")
    try:
        result = plan_offline(scene, t_s, _xy(start, "--from"), _xy(goal, "--to"), planner=chosen,
                              method=method, controller=controller)
    except OfflineError as exc:
        _fail(str(exc), 1 if exc.no_path else 2)
        return
    driven = result.get("controller")
    if as_json:
        typer.echo(json.dumps(result))
    else:
        _print_path(result, chosen, t_s)
        if driven is not None:
            typer.echo(f"controller {driven['name']}: " + (f"refused: {driven['refused']}" if driven["refused"] else
                       f"{'reached the goal' if driven['reached'] else 'did not reach the goal'} in "
                       f"{driven['time_s']:.1f} s over {driven['length_m']:.2f} m"))
    if driven is not None and (driven["refused"] or not driven["reached"]):
        raise typer.Exit(1)


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
    from agents.lib.metrics.metric_catalog import column_label

    for key, value in result["metrics"]["psi_percent"].items():
        table.add_row(column_label(f"psi_zone_percent.{key}"), f"{value:.1f}")
    for key, value in result["metrics"].get("psi_unadapted_zone_percent", {}).items():
        table.add_row(column_label(f"psi_unadapted_zone_percent.{key}"), f"{value:.1f}")
    for name, value in result["metrics"]["psi_interaction_percent"].items():
        r = result["objects"][name]["R"]
        table.add_row(f"{column_label(f'psi_object_percent.{name}')}, R={r:.2f}", f"{value:.1f}")
    table.add_row("waypoints", str(len(result["points"])))
    Console().print(table)


def _mission_slice(scene: str, trajectory: str | None, mission: str | None) -> tuple[str, Path]:
    """(scene, trajectory CSV) of ``chronav metrics``: SCENE TRAJ.csv as given, or a mission's slice
    of a finished run (SCENE RUN --mission M, or RUN --mission M with the scene the run recorded)."""
    from tools.system.finished_runs import find_finished_run, read_result, run_scene, unknown_mission
    from tools.system.mission_slices import ensure_mission_slices
    from tools.system.runs import RunError

    if trajectory is not None and trajectory != "latest" and not Path(trajectory).is_dir() \
            and (Path(trajectory).exists() or trajectory.endswith(".csv")):
        if mission is not None:
            raise typer.BadParameter(f"{trajectory} is a trajectory file; --mission picks a mission of a run: "
                                     "chronav metrics SCENE RUN --mission M", param_hint="--mission")
        return scene, Path(trajectory)
    try:
        run_dir = find_finished_run(scene if trajectory is None else trajectory)
    except RunError as exc:
        if trajectory is not None:
            raise
        raise RunError(f"no trajectory given: use chronav metrics SCENE TRAJ.csv, or a finished run with "
                       f"chronav metrics RUN --mission M ({exc})") from None
    result = read_result(run_dir)
    slices = ensure_mission_slices(run_dir, result["missions"])
    if mission is None:
        listed = ", ".join(slices) or "none (no mission of this run ended with the robot driving)"
        raise RunError(f"run {run_dir.name}: pick a mission with --mission M; its missions: {listed}")
    if mission not in slices:
        raise unknown_mission(mission, run_dir, list(slices))
    return (run_scene(run_dir, result) if trajectory is None else scene), slices[mission].trajectory_csv


def metrics_command(scene: str = typer.Argument(..., help="scene file or name in scenes/; or a finished run "
                                                "(latest, its directory or id) with --mission, the scene it ran"),
                    trajectory: str = typer.Argument(None, help="CSV with header t,x,y,theta (s, m, m, rad); or a "
                                                     "finished run (latest, its directory or id) with --mission",
                                                     show_default=False),
                    mission: str = typer.Option(None, "--mission", help="with a run: the mission to measure, on "
                                                "the run's slices of it (<run>/missions/<mission>.csv and the "
                                                "people's <mission>.people.csv)"),
                    at: str = typer.Option(None, "--at", help="HH:MM for people and agenda (default: a mission "
                                                              "slice's start, else t of the first sample if >= 1 h, "
                                                              "else the scene's start)"),
                    people: Path = typer.Option(None, "--people", help="people's trajectories (header "
                                                "t,name,role,x,y,theta,vx,vy,group; s, -, -, m, m, rad, m/s, "
                                                "m/s, group label or empty; default: <mission>.people.csv "
                                                "beside a mission's slice <run>/missions/<mission>.csv, "
                                                "else people.csv beside the trajectory, as a run writes it)"),
                    definitions: str = typer.Option("published", "--definitions",
                                                    help="published (the papers' definitions, chronav's names) "
                                                         "or hunav (HuNavSim's evaluator, its quirks and its "
                                                         "metric names; docs/metrics.md)"),
                    goal: str = typer.Option(None, "--goal", help="target X,Y (m) for completed and the "
                                                                  "distances to target (default: a mission "
                                                                  "slice's pose goal)"),
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
    from agents.lib.metrics.metrics import MetricsInputError
    from agents.world.offline import OfflineError, metrics_offline

    if definitions not in ("published", "hunav"):
        raise typer.BadParameter("use published or hunav", param_hint="--definitions")
    from tools.system.mission_slices import slice_inputs
    from tools.system.runs import RunError

    try:
        scene, trajectory_csv = _mission_slice(scene, trajectory, mission)
    except RunError as exc:
        _fail(str(exc))
        return
    beside = slice_inputs(trajectory_csv)    # a mission's slice: its people, start and target beside it
    at_s = _clock(at, "--at")
    try:
        report = metrics_offline(scene, trajectory_csv, beside.at_s if at_s is None else at_s,
                                 people or beside.people_csv, definitions=definitions,
                                 goal_xy=beside.goal_xy if goal is None else _xy(goal, "--goal"),
                                 robot_radius_m=robot_radius, person_radius_m=person_radius)
    except (OfflineError, MetricsInputError) as exc:
        _fail(str(exc))
        return
    if as_json:
        typer.echo(json.dumps({k: v for k, v in report.items() if k != "table"}))
        return
    from rich.console import Console
    from rich.table import Table

    table = Table(title=f"metrics of {trajectory_csv} on {report['scene']} ({definitions} definitions)")
    table.add_column("metric (unit)")
    table.add_column("value", justify="right")
    for label, value in report["table"]:
        table.add_row(label, value)
    Console().print(table)


def register(app: typer.Typer) -> None:
    app.command("path")(path_command)
    app.command("metrics")(metrics_command)
