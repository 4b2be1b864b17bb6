"""`chronav plan SCENE --mission M [--at HH:MM]`: what the executive would do for a mission then.

Why through the agents' code end to end: the scene's world at ``--at`` is built as the agents
would hold it (``agents.world.offline.graph_at``: scripted doors, agenda changes, people on their
walks), and the mission is planned by the executive's own planner (``agents.missions``), so this
command prints exactly the steps, intentions and goal poses the live executive would issue.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import typer


def _fail(message: str, code: int = 2) -> None:
    typer.echo(message, err=True)
    raise typer.Exit(code)


def _what(preview: Any) -> str:
    """The end of a step line: where the intention drives, or until when it waits."""
    from scenes.clock import format_clock

    if preview.error is not None:
        return f"  -> cannot resolve now: {preview.error}"
    rooms = f" via {', '.join(preview.rooms)}" if preview.rooms else ""
    if preview.until_s is not None:
        return f"  -> wait until {format_clock(preview.until_s)} (end of {preview.step.subject})"
    goal = preview.goal
    if goal is None:
        return ""
    heading = "any heading" if goal.theta is None else f"heading {goal.theta:.2f} rad"
    verb = "pass" if preview.pass_through else "drive to"
    return f"  -> {verb} ({goal.x:.2f}, {goal.y:.2f}), {heading}{rooms}"


def plan_scene(scene: Path, mission: str, at_s: float | None, grammar_file: Path | None, robot: str | None,
               max_expansions: int, as_json: bool) -> None:
    """Plan ``mission`` on ``scene`` at ``at_s`` (default: the scene clock's start) and print it."""
    from agents.missions.kinds import MissionStringError
    from agents.missions.planning import MissionPlanner, NoMissionPlan
    from agents.missions.preview import preview_mission
    from agents.world.offline import graph_at
    from agents.world.scene_world import load_world
    from grammar.errors import GrammarError, PlanningError
    from scenes.clock import format_clock
    from scenes.yamlio import SourceError

    try:
        world = load_world(scene)
        planner = MissionPlanner(world.scene, grammar_file, robot=robot, max_expansions=max_expansions)
    except (SourceError, GrammarError) as exc:
        _fail(str(exc))
        return
    t_s = world.scene.clock.start_s if at_s is None else at_s
    from agents.world.offline import OfflineError, check_within_day

    try:
        check_within_day(world, t_s)
    except OfflineError as exc:
        _fail(str(exc))
        return
    from scenes.names import shown

    echoed = shown(mission, 80)   # the mission as typed, cut to a readable length (it may be 100,000 characters)
    payload: dict[str, Any] = {"scene": world.scene.name, "mission": echoed, "at_s": t_s, "at": format_clock(t_s),
                               "grammar": str(planner.grammar_file)}
    try:
        plan, steps = preview_mission(planner, graph_at(world, t_s), mission)
    except MissionStringError as exc:
        _fail(str(exc))
        return
    except PlanningError as exc:
        _fail(str(exc))
        return
    except NoMissionPlan as exc:
        payload.update(found=False, reason=str(exc))
        result = exc.result
        if result is not None:
            payload.update(expanded=result.expanded, generated=result.generated)
            diagnosis = getattr(result, "diagnosis", None)
            if diagnosis is not None:
                payload["diagnosis"] = diagnosis.to_dict()
        if as_json:
            typer.echo(json.dumps(payload))
        typer.echo(f"no plan for {echoed!r} at {format_clock(t_s)}: {exc}", err=True)
        diagnosis = getattr(result, "diagnosis", None)
        if diagnosis is not None:  # the grammar's why: blocking rule, condition and facts
            for line in diagnosis.lines()[1:]:
                typer.echo(f"  {line}", err=True)
        raise typer.Exit(1) from None
    result = plan.result
    payload.update(found=True, grammar_mission=plan.grammar_mission, expanded=result.expanded,
                   generated=result.generated, cost=result.cost, target_bindings=dict(result.target_bindings),
                   steps=[s.as_json() for s in steps], intentions=len({s.intention for s in steps}),
                   agm_plan=result.agm_lines())  # the grammar's plan in AGM's plan-file form
    if as_json:
        typer.echo(json.dumps(payload))
        return
    planned_as = "" if plan.grammar_mission == mission else f" (planned as {plan.grammar_mission})"
    typer.echo(f"plan for {echoed!r} at {format_clock(t_s)}{planned_as}: {len(steps)} step(s) in "
               f"{payload['intentions']} intention(s), cost {result.cost:g}, {result.expanded} state(s) expanded")
    if not steps:
        typer.echo("  (already satisfied: nothing to do)")
    for i, preview in enumerate(steps, 1):
        bindings = " ".join(f"{var}={name}" for var, name in preview.step.bindings.items())
        typer.echo(f"  {i}. {preview.step.rule}  {bindings}{_what(preview) if preview.last_of_intention else ''}")
