"""`chronav scene check FILE...`: validate scene files the way the launcher will read them."""

from __future__ import annotations

import json
from pathlib import Path

import typer


def register(app: typer.Typer) -> None:
    scene_app = typer.Typer(help="Scene files (YAML worlds).", no_args_is_help=True)

    @scene_app.command("check")
    def check(files: list[Path] = typer.Argument(..., help="scene YAML files"),
              as_json: bool = typer.Option(False, "--json", help="one JSON object on stdout")) -> None:
        """Validate scenes: schema, names, geometry, reachability and agenda. Exit 1 if any file has an error;
        notes (overlapping activities) are printed but allowed."""
        from agents.world.scene_world import load_world, resolve_world
        from scenes.yamlio import SourceError
        from tools.plain import plural

        results: dict[str, str] = {}
        notes: dict[str, list[str]] = {}
        failed = False
        for file in files:
            try:
                loaded = load_world(file)
                for day in range(2, loaded.scene.clock.days + 1):   # a scene that spans days: each day's agenda
                    resolve_world(loaded.loaded, day)
            except SourceError as exc:
                typer.echo(str(exc), err=True)
                results[str(file)] = str(exc)
                failed = True
                continue
            scene = loaded.scene
            results[str(file)] = "ok"
            notes[str(file)] = list(loaded.notes)
            if not as_json:
                typer.echo(f"{file}: ok ({plural(len(scene.rooms), 'room')}, {plural(len(scene.objects), 'object')}, "
                           f"{plural(len(scene.people), 'person', 'people')}, {plural(len(scene.missions), 'mission')})")
                for note in loaded.notes:
                    typer.echo(f"{file}: note: {note}")
        if as_json:
            typer.echo(json.dumps({"files": results, "notes": notes, "ok": not failed}))
        raise typer.Exit(1 if failed else 0)

    @scene_app.command("day")
    def day(file: Path = typer.Argument(..., help="scene YAML file that spans days"),
            number: int = typer.Argument(..., min=1, help="the day, 1-based"),
            out: Path = typer.Option(..., "--out", help="where to write that day's scene (YAML)")) -> None:
        """Write day N of a scene as a single-day scene (that date's agenda, missions and scripted changes),
        for `chronav path/plan/metrics/evaluate` on that day (docs/long_runs.md)."""
        from agents.world.scene_world import load_world
        from scenes.loader import load_scene
        from scenes.yamlio import SourceError
        from tools.week import write_day_scene
        from tools.week_index import RotationError

        try:
            loaded = load_scene(file)
            write_day_scene(out, loaded, number)
            world = load_world(out)
        except (SourceError, RotationError) as exc:
            typer.echo(f"error: {exc}", err=True)
            raise typer.Exit(1) from None
        typer.echo(f"{out}: day {number} of {file}, {world.scene.clock.date.isoformat()} "
                   f"({len(world.agenda.activities)} activities, {len(world.scene.missions)} missions)")

    from tools.scene.show_cli import show   # light: its heavy imports are inside the command

    scene_app.command("show")(show)
    app.add_typer(scene_app, name="scene")
