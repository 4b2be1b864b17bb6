"""``chronav grammar check FILE...`` and ``chronav plan SCENE --mission M``.

Why here: checking a hand-written grammar and asking "what would the robot do for this mission
in this scene?" are the two things a person editing rules needs, without starting any agent.
Heavy imports stay inside the commands so that ``chronav --help`` stays fast.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any, Optional

import typer

grammar_app = typer.Typer(help="Grammar (AGGL) files: check them.", no_args_is_help=True)


def _fail(message: str, code: int = 2) -> None:
    typer.echo(message, err=True)
    raise typer.Exit(code)


@grammar_app.command("check")
def check(files: list[Path] = typer.Argument(..., help="grammar (.aggl) or target (.aggt) files"),
          as_json: bool = typer.Option(False, "--json", help="print one JSON object")) -> None:
    """Parse each file; print file:line:col: message for the first error of each broken file."""
    from grammar.errors import GrammarError
    from grammar.parser import load_grammar, load_target

    results: list[dict[str, Any]] = []
    for path in files:
        try:
            if path.suffix == ".aggt":
                target = load_target(path)
                results.append({"file": str(path), "ok": True, "kind": "target",
                                "nodes": len(target.pattern.nodes), "links": len(target.pattern.links)})
            else:
                grammar = load_grammar(path)
                results.append({"file": str(path), "ok": True, "kind": "grammar", "name": grammar.name,
                                "dialect": grammar.dialect, "rules": len(grammar.rules),
                                "types": len(grammar.types.parents), "includes": len(grammar.includes)})
        except GrammarError as err:
            typer.echo(str(err), err=True)
            results.append({"file": str(path), "ok": False, "error": str(err), "line": err.line,
                            "column": err.column, "message": err.message})
    failed = [r for r in results if not r["ok"]]
    if as_json:
        typer.echo(json.dumps({"ok": not failed, "files": results}))
    else:
        for r in results:
            if not r["ok"]:
                continue
            if r["kind"] == "target":
                typer.echo(f"{r['file']}: OK (target, {r['nodes']} nodes, {r['links']} links)")
            else:
                typer.echo(f"{r['file']}: OK ({r['dialect']} grammar {r['name']!r}, {r['rules']} rules, "
                           f"{r['types']} types)")
        if not failed:
            typer.echo(f"{len(results)} file(s) OK")
    if failed:
        raise typer.Exit(1)


def _parse_time(text: str | None) -> float | None:
    """``HH:MM`` (or ``HH:MM:SS``) or plain seconds since midnight."""
    from scenes.clock import parse_clock

    if text is None:
        return None
    try:
        return parse_clock(text) if ":" in text else float(text)
    except ValueError:
        _fail(f"--at {text!r}: expected HH:MM, HH:MM:SS or seconds since midnight")
    return None


def _load_world(scene: Path, at_s: float | None) -> Any:
    """A ``.json`` file is a networkx node-link graph; anything else is a scene: its symbolic
    graph (rooms, doors, robot, people, objects, the day's activities with their state at
    ``at_s``, by default the scene clock's start)."""
    if scene.suffix == ".json":
        from networkx.readwrite import json_graph

        try:
            data = json.loads(scene.read_text(encoding="utf-8"))
        except (OSError, ValueError) as exc:
            _fail(f"{scene}: cannot read symbolic graph: {exc}")
        edges_key = "links" if "links" in data else "edges"
        try:
            return json_graph.node_link_graph(data, directed=True, multigraph=True, edges=edges_key)
        except (KeyError, TypeError, ValueError) as exc:
            _fail(f"{scene}: not a node-link graph: {exc}")
    from agents.world.dsr_readers import symbolic_view
    from agents.world.offline import graph_at
    from agents.world.scene_world import load_world
    from scenes.yamlio import SourceError

    try:
        world = load_world(scene)
    except SourceError as exc:
        _fail(str(exc))
    return symbolic_view(graph_at(world, world.scene.clock.start_s if at_s is None else at_s))


def plan_command(scene: Path = typer.Argument(..., help="scene file, or a .json node-link symbolic graph"),
                 mission: str = typer.Option(..., "--mission", "-m",
                                             help="room:NAME, object:NAME, person:NAME, group:P1+P2, wait:ACTIVITY, "
                                                  "pose:X,Y,THETA (pose and agenda ids on scenes)"),
                 grammar_file: Optional[Path] = typer.Option(None, "--grammar", "-g",
                                                             help="grammar file (default: shipped social_navigation.aggl)"),
                 robot: Optional[str] = typer.Option(None, "--robot", help="robot node name if there are several"),
                 at: Optional[str] = typer.Option(None, "--at",
                                                  help="time of day (HH:MM) for the activities' state"),
                 max_expansions: int = typer.Option(20_000, "--max-expansions", min=1),
                 as_json: bool = typer.Option(False, "--json", help="print one JSON object")) -> None:
    """Plan a mission on a scene and print each step with its variable bindings.

    On a scene: the executive's own planning on the world at --at (tools/mission_plan.py)."""
    if scene.suffix.lower() not in (".json", ".xml"):  # a scene file or name, not a symbolic world file
        from tools.mission_plan import plan_scene

        plan_scene(scene, mission, _parse_time(at), grammar_file, robot, max_expansions, as_json)
        return
    from grammar.errors import GrammarError, MissionError, PlanningError
    from grammar.missions import plan_mission
    from grammar.parser import default_grammar_path, load_grammar

    try:
        grammar = load_grammar(grammar_file or default_grammar_path())
        world = _load_world(scene, _parse_time(at))
        result = plan_mission(grammar, world, mission, robot=robot, max_expansions=max_expansions)
    except (GrammarError, MissionError, PlanningError) as err:
        _fail(str(err))
        return
    if as_json:
        payload: dict[str, Any] = {"mission": mission, "grammar": grammar.file, "found": result.found,
                                   "expanded": result.expanded, "generated": result.generated}
        if result.found:
            payload.update(cost=result.cost, target_bindings=dict(result.target_bindings),  # type: ignore[union-attr]
                           steps=[{"rule": s.rule, "bindings": dict(s.bindings), "cost": s.cost}
                                  for s in result.steps])  # type: ignore[union-attr]
        else:
            payload["reason"] = result.reason  # type: ignore[union-attr]
        typer.echo(json.dumps(payload))
    elif result.found:
        steps = result.steps  # type: ignore[union-attr]
        typer.echo(f"plan for {mission!r}: {len(steps)} step(s), cost {result.cost:g}, "  # type: ignore[union-attr]
                   f"{result.expanded} state(s) expanded")
        for i, step in enumerate(steps, 1):
            bindings = " ".join(f"{var}={name}" for var, name in step.bindings.items())
            typer.echo(f"  {i}. {step.rule}  {bindings}")
    if not result.found:
        typer.echo(f"no plan for {mission!r}: {result.reason}", err=True)  # type: ignore[union-attr]
        raise typer.Exit(1)


def register(app: typer.Typer) -> None:
    app.add_typer(grammar_app, name="grammar")
    app.command("plan")(plan_command)


if __name__ == "__main__":  # pragma: no cover - manual use
    standalone = typer.Typer()
    register(standalone)
    standalone(sys.argv[1:])
