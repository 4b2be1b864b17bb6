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
                typer.echo(f"{file}: ok ({len(scene.rooms)} rooms, {len(scene.objects)} objects, "
                           f"{len(scene.people)} people, {len(scene.missions)} missions)")
                for note in loaded.notes:
                    typer.echo(f"{file}: note: {note}")
        if as_json:
            typer.echo(json.dumps({"files": results, "notes": notes, "ok": not failed}))
        raise typer.Exit(1 if failed else 0)

    app.add_typer(scene_app, name="scene")
