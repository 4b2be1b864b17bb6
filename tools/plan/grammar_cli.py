"""``chronav grammar check FILE...`` and ``chronav plan SCENE --mission M``.

Why here: checking a hand-written grammar and asking "what would the robot do for this mission
in this scene?" are the two things a person editing rules needs, without starting any agent.
Heavy imports stay inside the commands so that ``chronav --help`` stays fast.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

import typer

grammar_app = typer.Typer(help="Grammar (AGGL) files: check them.", no_args_is_help=True)


def _fail(message: str, code: int = 2) -> None:
    typer.echo(message, err=True)
    raise typer.Exit(code)


@grammar_app.command("check")
def check(files: list[Path] = typer.Argument(..., help="grammar (.aggl) or target (.aggt) files"),
          no_includes: bool = typer.Option(False, "--no-includes",
                                           help="check each file alone, without reading its includes"),
          strict: bool = typer.Option(False, "--strict",
                                      help="refuse what is otherwise only warned about (what AGM reads but is "
                                           "probably a mistake: a stray ')', a rule redefined by an include...)"),
          as_json: bool = typer.Option(False, "--json", help="print one JSON object")) -> None:
    """Parse each file; print file:line:col: message for the first error of each broken file,
    and a warning for each thing read as AGM reads it that is probably a mistake."""
    from grammar.errors import GrammarError
    from grammar.parser import load_grammar, load_target

    results: list[dict[str, Any]] = []
    for path in files:
        try:
            if path.suffix == ".aggt":
                target = load_target(path, strict=strict)
                results.append({"file": str(path), "ok": True, "kind": "target",
                                "nodes": len(target.pattern.nodes), "links": len(target.pattern.links),
                                "warnings": [str(w) for w in target.warnings]})
            else:
                grammar = load_grammar(path, includes=not no_includes, strict=strict)
                results.append({"file": str(path), "ok": True, "kind": "grammar", "name": grammar.name,
                                "dialect": grammar.dialect, "rules": len(grammar.rules),
                                "hierarchical": sum(r.hierarchical for r in grammar.rules),
                                "combos": len(grammar.combos), "types": len(grammar.types.parents),
                                "includes": len(grammar.includes),
                                "skipped_includes": list(grammar.skipped_includes),
                                "warnings": [str(w) for w in grammar.warnings]})
        except GrammarError as err:
            typer.echo(str(err), err=True)
            results.append({"file": str(path), "ok": False, "error": str(err), "line": err.line,
                            "column": err.column, "message": err.message})
    for r in results:
        for warning in r.get("warnings", ()):
            typer.echo(warning, err=True)
    failed = [r for r in results if not r["ok"]]
    if as_json:
        typer.echo(json.dumps({"ok": not failed, "files": results}))
    else:
        for r in results:
            if r["ok"]:
                typer.echo(f"{r['file']}: OK ({_summary(r)})")
        if not failed:
            typer.echo(f"{len(results)} file(s) OK")
    if failed:
        raise typer.Exit(1)


def _summary(r: dict[str, Any]) -> str:
    if r["kind"] == "target":
        return f"target, {r['nodes']} nodes, {r['links']} links"
    parts = [f"{r['dialect']} grammar {r['name']!r}", f"{r['rules']} rules"]
    if r["hierarchical"]:
        parts.append(f"{r['hierarchical']} hierarchical")
    if r["combos"]:
        parts.append(f"{r['combos']} combo rules (parsed, not planned: AGM removed them in 2017)")
    parts.append(f"{r['types']} types")
    if r["includes"]:
        parts.append(f"{r['includes']} included files")
    if r["skipped_includes"]:
        parts.append(f"{len(r['skipped_includes'])} includes not read")
    return ", ".join(parts)


def _parse_time(text: str | None) -> float | None:
    """``HH:MM`` (or ``HH:MM:SS``): the one clock syntax of every command (scenes/clock.py)."""
    from scenes.clock import parse_clock

    if text is None:
        return None
    try:
        return parse_clock(text)
    except ValueError as exc:
        _fail(f"--at: {exc}")
    return None


def _load_world(path: Path) -> Any:
    """A world file: ``.json`` networkx node-link graph or ``.xml`` AGM world (a scene goes through
    tools/plan/mission_plan.py: the executive's own planning on the agents' DSR at ``--at``)."""
    from grammar.agm_world import load_world

    return load_world(path)


def _step_json(step: Any) -> dict[str, Any]:
    out: dict[str, Any] = {"rule": step.rule, "bindings": dict(step.bindings), "cost": step.cost,
                           "hierarchical": step.hierarchical, "agm_bindings": dict(step.agm_bindings)}
    if step.hierarchical:
        out["expansion"] = ([_step_json(s) for s in step.expansion.steps] if step.expansion is not None else None)
        out["expansion_error"] = step.expansion_error
    return out


def _step_lines(steps: Any, indent: str = "  ", prefix: str = "") -> list[str]:
    lines: list[str] = []
    for i, step in enumerate(steps, 1):
        number = f"{prefix}{i}"
        bindings = " ".join(f"{var}={name}" for var, name in step.bindings.items())
        mark = "*" if step.hierarchical else ""
        lines.append(f"{indent}{number}. {mark}{step.rule}  {bindings}")
        if step.hierarchical and step.expansion is not None:
            lines.append(f"{indent}   expands into ({len(step.expansion.steps)} step(s), "
                         f"cost {step.expansion.cost:g}):")
            lines += _step_lines(step.expansion.steps, indent + "   ", f"{number}.")
        elif step.hierarchical:
            lines.append(f"{indent}   not expanded yet: {step.expansion_error}")
    return lines


def _report(result: Any, what: str, payload: dict[str, Any], as_json: bool, primitive: Any = None) -> None:
    """Print a plan (or why there is none) in chronav's form and AGM's plan-file form; with
    ``primitive`` (``--expand``), also the primitive plan AGM's executive runs (grammar/executive.py)."""
    payload.update(found=result.found, expanded=result.expanded, generated=result.generated)
    if primitive is not None:
        payload["primitive_plan"] = ({"steps": [_step_json(s) for s in primitive.steps], "cost": primitive.cost,
                                      "plans": primitive.plans, "agm_plan": primitive.agm_lines()}
                                     if primitive.found else None)
        if not primitive.found:
            payload["primitive_plan_error"] = primitive.reason
    if result.found:
        payload.update(cost=result.cost, target_bindings=dict(result.target_bindings),
                       steps=[_step_json(s) for s in result.steps], agm_plan=result.agm_lines())
    else:
        payload["reason"] = result.reason
        payload["diagnosis"] = result.diagnosis.to_dict() if result.diagnosis is not None else None
    if as_json:
        typer.echo(json.dumps(payload))
    elif result.found:
        typer.echo(f"plan for {what}: {len(result.steps)} step(s), cost {result.cost:g}, "
                   f"{result.expanded} state(s) expanded")
        for line in _step_lines(result.steps):
            typer.echo(line)
        typer.echo("AGM plan:")
        for line in result.agm_lines():
            typer.echo(f"  {line}")
        if primitive is not None and primitive.found:
            typer.echo(f"primitive plan (AGM's executive: {len(primitive.steps)} step(s), cost {primitive.cost:g}, "
                       f"{primitive.plans} plan(s)):")
            for line in primitive.agm_lines():
                typer.echo(f"  {line}")
    if primitive is not None and not primitive.found:
        typer.echo(f"no primitive plan: {primitive.reason}", err=True)
        raise typer.Exit(1)
    if not result.found:
        typer.echo(f"no plan for {what}: {result.reason}", err=True)
        if result.diagnosis is not None:
            for line in result.diagnosis.lines()[1:]:
                typer.echo(f"  {line}", err=True)
        raise typer.Exit(1)


def plan_command(scene: Path | None = typer.Argument(None, help="scene file, or a world file (.json node-link "
                                                                   "graph, .xml AGM world)"),
                 mission: str | None = typer.Option(None, "--mission", "-m",
                                                       help="room:NAME, object:NAME, person:NAME, group:P1+P2, "
                                                            "wait:ACTIVITY, pose:X,Y,THETA (pose on scenes)"),
                 world_file: Path | None = typer.Option(None, "--world", "-w",
                                                           help="AGM world (.xml) or node-link graph (.json); "
                                                                "use with --target, as AGM's agglplan"),
                 target_file: Path | None = typer.Option(None, "--target", "-t",
                                                            help="target file (.aggt), with --world"),
                 grammar_file: Path | None = typer.Option(None, "--grammar", "-g",
                                                             help="grammar file (default: shipped social_navigation.aggl)"),
                 robot: str | None = typer.Option(None, "--robot", help="robot node name if there are several"),
                 at: str | None = typer.Option(None, "--at",
                                                  help="time of day (HH:MM) for the activities' state"),
                 max_expansions: int = typer.Option(20_000, "--max-expansions", min=1),
                 max_new_symbols: int | None = typer.Option(
                     None, "--max-new-symbols", min=0,
                     help="with --world/--target: search only worlds at most N symbols larger than the start "
                          "(default: AGM's 5, then 10, then unbounded until a plan is found)"),
                 expand: bool = typer.Option(
                     False, "--expand",
                     help="with --world/--target: also print the primitive plan AGM's executive runs (each "
                          "hierarchical step replaced by its expansion, re-planning after each step)"),
                 as_json: bool = typer.Option(False, "--json", help="print one JSON object")) -> None:
    """Plan a mission on a scene (SCENE --mission M), or a target on a world as AGM's agglplan
    (--world W --target T --grammar G); print each step with its bindings and the AGM plan file."""
    from grammar.errors import GrammarError, MissionError, PlanningError
    from grammar.parser import default_grammar_path, load_grammar, load_target

    agm_mode = world_file is not None or target_file is not None
    if agm_mode:
        if world_file is None or target_file is None:
            _fail("--world and --target go together: chronav plan --world W.xml --target T.aggt --grammar G.aggl")
        if scene is not None or mission is not None or at is not None or robot is not None:
            _fail("with --world/--target, give no SCENE, --mission, --robot or --at")
    elif expand:
        _fail("--expand goes with --world W.xml --target T.aggt (AGM's hierarchical plans)")
    elif scene is None or mission is None:
        _fail("give SCENE --mission M, or --world W.xml --target T.aggt [--grammar G.aggl]")
    elif scene.suffix.lower() not in (".json", ".xml"):  # a scene: the executive's own planning at --at
        from tools.plan.mission_plan import plan_scene

        plan_scene(scene, mission, _parse_time(at), grammar_file, robot, max_expansions, as_json)
        return
    primitive: Any = None
    try:
        grammar = load_grammar(grammar_file or default_grammar_path())
        for warning in grammar.warnings:  # read as AGM reads it, but probably a mistake: say so
            typer.echo(str(warning), err=True)
        if agm_mode:
            from grammar.planner import plan_growing

            assert world_file is not None and target_file is not None
            target = load_target(target_file)
            for warning in target.warnings:
                typer.echo(str(warning), err=True)
            world = _load_world(world_file)
            steps = (max_new_symbols,) if max_new_symbols is not None else None
            result, bound = (plan_growing(grammar, world, target, max_expansions=max_expansions, steps=steps)
                             if steps is not None else plan_growing(grammar, world, target, max_expansions=max_expansions))
            payload: dict[str, Any] = {"world": str(world_file), "target": str(target_file), "grammar": grammar.file,
                                       "max_new_symbols": bound}
            if expand and result.found:
                from grammar.executive import primitive_plan

                primitive = (primitive_plan(grammar, world, target, max_expansions=max_expansions, steps=steps)
                             if steps is not None else
                             primitive_plan(grammar, world, target, max_expansions=max_expansions))
            what = f"target {str(target_file)!r}"
        else:
            from grammar.missions import plan_mission

            assert scene is not None and mission is not None
            world = _load_world(scene)
            result = plan_mission(grammar, world, mission, robot=robot, max_expansions=max_expansions)
            payload = {"mission": mission, "grammar": grammar.file}
            what = repr(mission)
    except (GrammarError, MissionError, PlanningError) as err:
        _fail(str(err))
        return
    _report(result, what, payload, as_json, primitive if expand and result.found else None)


def register(app: typer.Typer) -> None:
    app.add_typer(grammar_app, name="grammar")
    app.command("plan")(plan_command)


if __name__ == "__main__":  # pragma: no cover - manual use
    standalone = typer.Typer()
    register(standalone)
    standalone(sys.argv[1:])
