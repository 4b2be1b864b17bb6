"""``chronav scene from-crowd FILE... --out SCENE.yaml``: a scene where recorded pedestrians walk.

Why a command: researchers test social navigation on recorded people (SocNavBench replays ETH/UCY);
this writes the scene chronav runs them in (scenes/from_crowd.py says how the plaza and the robot's
missions are chosen) and checks it as ``chronav scene check`` would before saying it is done.
"""

from __future__ import annotations

import json
import math
import shlex
import sys
from pathlib import Path

import typer


def _fail(message: str, code: int = 2) -> None:
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(code)


def from_crowd(files: list[Path] = typer.Argument(..., help="ETH/UCY text files ('frame id x y' a line, metres)",
                                                  show_default=False),
               out: Path = typer.Option(..., "--out", help="scene file to write"),
               dt: float = typer.Option(0.4, "--dt", help="seconds between two annotated frames (ETH/UCY: 0.4)"),
               missions: int = typer.Option(3, "--missions", help="robot crossings of the busiest places (0-50)"),
               seed: int = typer.Option(0, "--seed", min=0, max=2**31 - 1, help="seed of the missions and the crowd"),
               replay: str = typer.Option("exact", "--replay", help="exact (walk the record whatever the robot "
                                                                    "does) or reactive (avoid the robot)"),
               margin: float = typer.Option(2.0, "--margin", help="m of plaza around the recordings' extent"),
               name: str | None = typer.Option(None, "--name", help="scene name (default: the output file's stem)"),
               force: bool = typer.Option(False, "--force", help="overwrite --out"),
               as_json: bool = typer.Option(False, "--json", help="one JSON object on stdout")) -> None:
    """Write a scene around recorded pedestrians: an open plaza, the people replaying their records,
    robot missions crossing the busiest places at their busy times (docs/crowds.md)."""
    from scenes.crowd_recording import RecordingError, read_recording
    from scenes.from_crowd import MAX_MISSIONS, CrowdSceneError, scene_text
    from scenes.names import check_name
    from tools.scene.map_cli import _write_checked_scene

    if replay not in ("exact", "reactive"):
        raise typer.BadParameter("use exact or reactive", param_hint="--replay")
    if not (math.isfinite(dt) and 0 < dt <= 10.0):
        raise typer.BadParameter("must be a number of seconds above 0 and at most 10", param_hint="--dt")
    if not 0 <= missions <= MAX_MISSIONS:
        raise typer.BadParameter(f"must be 0-{MAX_MISSIONS}", param_hint="--missions")
    if not (math.isfinite(margin) and 0.5 <= margin <= 20.0):
        raise typer.BadParameter("must be 0.5-20 m", param_hint="--margin")
    try:
        check_name(name or out.stem)
    except ValueError as exc:
        raise typer.BadParameter(str(exc), param_hint="--name" if name is not None else "--out") from None
    if out.exists() and not force:
        _fail(f"{out} exists; pass --force to overwrite it")
    try:
        recordings = [read_recording(path, dt) for path in files]
        text = scene_text(recordings, out, name or out.stem, margin_m=margin, missions=missions, seed=seed,
                          replay=replay, command=shlex.join(["chronav", "scene", "from-crowd", *sys.argv[3:]])
                          if sys.argv[1:3] == ["scene", "from-crowd"] else "")
    except (RecordingError, CrowdSceneError) as exc:
        _fail(str(exc))
        return
    _write_checked_scene(text, out)
    from scenes.loader import load_scene

    planned = len(load_scene(out).scene.missions)     # fewer than asked when the busy times are too close
    people = sum(len(r.tracks) for r in recordings)
    result = {"out": str(out), "people": people, "missions": planned, "replay": replay,
              "duration_s": round(max(r.duration_s for r in recordings), 3), "rows": sum(r.rows for r in recordings)}
    if as_json:
        typer.echo(json.dumps(result))
        return
    typer.echo(f"{out}: {people} recorded people replayed {replay} over {result['duration_s']:g} s, "
               f"{planned} robot crossing(s){f' (of {missions} asked: the busy times are too close together)' if planned < missions else ''}; run it with `chronav launch {out} --in-process`")


def register(app: typer.Typer) -> None:
    scene_group = next((g.typer_instance for g in app.registered_groups if g.name == "scene"), None)
    if scene_group is None:
        raise RuntimeError("tools.scene.crowd_cli must be registered after tools.scene.scene_cli (COMMAND_MODULES)")
    scene_group.command("from-crowd")(from_crowd)
