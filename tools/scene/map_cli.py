"""``chronav scene from-map MAP.yaml --out SCENE`` and ``chronav map export SCENE --at HH:MM --out DIR``.

Why: a care home that deploys a robot has a SLAM map of its building (ROS map_server format) and
often runs Nav2.  ``scene from-map`` gives a starting scene on that map (candidate rooms, doors, a
robot pose, commented examples); ``map export`` gives chronav's time-dependent social map back as
Nav2 costmap-filter masks, one set per time slice, built through the offline world
(``agents/world/offline.SceneMaps``) so it is the map the navigation uses at that time.
Mapping of costs to mask values: ``agents/lib/socialmap/nav2.py`` and docs/maps.md.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import typer

MAX_SLICES = 500


def _fail(message: str, code: int = 2) -> None:
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(code)


def _clock(text: str, option: str) -> float:
    from scenes.clock import parse_clock

    try:
        return parse_clock(text)
    except ValueError as exc:
        raise typer.BadParameter(str(exc), param_hint=option) from None


def slice_times(at_s: float, until_s: float | None, every_min: float | None) -> list[float]:
    """--at, then every --every minutes up to --until (inclusive)."""
    if until_s is None and every_min is None:
        return [at_s]
    if until_s is None or every_min is None:
        raise typer.BadParameter("--until and --every go together", param_hint="--until/--every")
    if not (math.isfinite(every_min) and every_min > 0):
        raise typer.BadParameter("must be a positive number of minutes", param_hint="--every")
    if until_s < at_s:
        raise typer.BadParameter("must not be before --at", param_hint="--until")
    count = math.floor((until_s - at_s) / (every_min * 60.0) + 1e-9) + 1
    if count > MAX_SLICES:
        raise typer.BadParameter(f"{count} slices; at most {MAX_SLICES} (use a longer --every)", param_hint="--every")
    return [at_s + i * every_min * 60.0 for i in range(count)]


def _tag(t_s: float) -> str:
    """The slice's file tag: ``HHMM``, ``HHMMSS`` when not on a whole minute (file names stay as
    they were before clock times always carried their seconds)."""
    from scenes.clock import format_clock

    text = format_clock(t_s)
    return (text[:-3] if text.endswith(":00") else text).replace(":", "")


def filters_params(tag: str, scale: Any) -> dict[str, Any]:
    """ROS 2 parameters for Nav2's costmap_filter_info_server and the two mask map_servers."""
    from agents.lib.socialmap.nav2 import KEEPOUT_FILTER_TYPE, SPEED_FILTER_PERCENT_TYPE

    return {
        "keepout_filter_info_server": {"ros__parameters": {
            "type": KEEPOUT_FILTER_TYPE, "filter_info_topic": "/keepout_filter_info",
            "mask_topic": "/keepout_filter_mask", "base": scale.base, "multiplier": scale.multiplier}},
        "keepout_filter_mask_server": {"ros__parameters": {
            "topic_name": "/keepout_filter_mask", "yaml_filename": f"keepout_{tag}.yaml"}},
        "speed_filter_info_server": {"ros__parameters": {
            "type": SPEED_FILTER_PERCENT_TYPE, "filter_info_topic": "/speed_filter_info",
            "mask_topic": "/speed_filter_mask", "base": 0.0, "multiplier": 1.0}},
        "speed_filter_mask_server": {"ros__parameters": {
            "topic_name": "/speed_filter_mask", "yaml_filename": f"speed_{tag}.yaml"}},
    }


def export_masks(scene: str, times: list[float], out: Path) -> dict[str, Any]:
    """Write one keepout mask, one speed mask and one filter-info file per time; the index as a dict."""
    import yaml

    from agents.lib.socialmap.nav2 import MaskScale, keepout_values, social_costs, speed_values
    from agents.world.offline import SceneMaps
    from scenes.clock import format_clock
    from scenes.occupancy import write_map

    maps = SceneMaps.load(scene)
    out.mkdir(parents=True, exist_ok=True)
    scale = MaskScale.for_params(maps.nav.params)
    slices = []
    spec = None
    for t_s in times:
        smap = maps.at(t_s)
        spec = smap.spec
        costs = social_costs(smap)
        tag = _tag(t_s)
        note = (f"chronav social map of {maps.world.scene.name} at {format_clock(t_s)} "
                f"(chronav map export); docs/maps.md explains the values")
        write_map(out / f"keepout_{tag}.yaml", keepout_values(costs, scale), spec.resolution, (spec.x0, spec.y0),
                  mode="scale", header=f"{note}\nkeepout: chronav cost = {scale.base:g} + {scale.multiplier:.6g} "
                                      "x value; 100 = forbidden")
        write_map(out / f"speed_{tag}.yaml", speed_values(costs, scale), spec.resolution, (spec.x0, spec.y0),
                  mode="scale", header=f"{note}\nspeed limit in % of the top speed; 0 = no limit")
        (out / f"filters_{tag}.yaml").write_text(
            f"# Nav2 costmap filter info for chronav's masks at {format_clock(t_s)}\n"
            + yaml.safe_dump(filters_params(tag, scale), sort_keys=False), encoding="utf-8")
        slices.append({"time": format_clock(t_s), "t_s": t_s, "keepout": f"keepout_{tag}.yaml",
                       "speed": f"speed_{tag}.yaml", "filters": f"filters_{tag}.yaml",
                       "objects": {s.name: {"R": round(s.r, 4), "band": s.band, "active": s.active}
                                   for s in smap.object_spaces}})
    assert spec is not None
    index = {"scene": maps.world.scene.name, "resolution": spec.resolution, "origin": [spec.x0, spec.y0, 0.0],
             "width": spec.cols, "height": spec.rows,
             "keepout_scale": {"base": scale.base, "multiplier": scale.multiplier, "lethal": 100},
             "slices": slices}
    (out / "chronav_masks.yaml").write_text("# chronav map export: one keepout and one speed mask per time slice\n"
                                            + yaml.safe_dump(index, sort_keys=False), encoding="utf-8")
    return {"out": str(out), **index}


def export(scene: str = typer.Argument(..., help="scene file or name in scenes/"),
           at: str = typer.Option(..., "--at", help="first time slice HH:MM"),
           until: str | None = typer.Option(None, "--until", help="last time slice HH:MM (with --every)"),
           every: float | None = typer.Option(None, "--every", help="minutes between slices (with --until)"),
           out: Path = typer.Option(..., "--out", help="directory for the masks (created)"),
           as_json: bool = typer.Option(False, "--json", help="one JSON object on stdout")) -> None:
    """The social map as Nav2 keepout and speed masks (map_server images + filter-info yaml) per time."""
    from agents.world.offline import OfflineError

    times = slice_times(_clock(at, "--at"), None if until is None else _clock(until, "--until"), every)
    if out.exists() and not out.is_dir():
        _fail(f"--out {out} exists and is not a directory")
    try:
        result = export_masks(scene, times, out)
    except OfflineError as exc:
        _fail(str(exc))
        return
    except OSError as exc:
        _fail(f"cannot write to {out}: {exc.strerror or exc}")
        return
    if as_json:
        typer.echo(json.dumps(result))
        return
    typer.echo(f"{len(result['slices'])} time slice(s) of {result['scene']} in {out} "
               f"({result['width']} x {result['height']} cells at {result['resolution']:g} m): "
               + ", ".join(s["time"] for s in result["slices"]))


def from_map(map_file: Path = typer.Argument(..., help="map_server .yaml (naming a .pgm/.png image)"),
             out: Path = typer.Option(..., "--out", help="scene file to write"),
             name: str | None = typer.Option(None, "--name", help="scene name (default: the output file's stem)"),
             door_width: float = typer.Option(1.4, "--door-width", help="passages narrower than this (m) "
                                              "separate rooms and become candidate doors"),
             min_room_area: float = typer.Option(2.0, "--min-room-area", help="smaller free areas (m2) are "
                                                 "left out"),
             unknown: str = typer.Option("wall", "--unknown", help="the map's unknown cells: wall or free"),
             force: bool = typer.Option(False, "--force", help="overwrite --out"),
             as_json: bool = typer.Option(False, "--json", help="one JSON object on stdout")) -> None:
    """Write a starting scene on a building map: candidate rooms and doors, the robot at a free pose."""
    from scenes.from_map import LayoutError, layout_from_map, scene_text
    from scenes.occupancy import load_occupancy
    from scenes.yamlio import SourceError

    _check_from_map_options(out, name, door_width, min_room_area, unknown, force)
    try:
        occupancy = load_occupancy(map_file)
        layout = layout_from_map(occupancy, unknown_is_wall=unknown == "wall", door_width_m=door_width,
                                 min_room_area_m2=min_room_area)
    except SourceError as exc:
        _fail(str(exc))
        return
    except LayoutError as exc:
        _fail(f"{map_file}: {exc}", 1)
        return
    text = scene_text(layout, map_file, out, name or out.stem, unknown == "wall", door_width)
    _write_checked_scene(text, out)
    result = {"out": str(out), "map": str(map_file), "rooms": [r.name for r in layout.rooms],
              "doors": [{"name": d.name, "between": list(d.between)} for d in layout.doors],
              "robot": list(layout.robot)}
    if as_json:
        typer.echo(json.dumps(result))
        return
    typer.echo(f"{out}: {len(layout.rooms)} candidate rooms, {len(layout.doors)} doors, robot at "
               f"({layout.robot[0]:g}, {layout.robot[1]:g}); review them, then `chronav scene check {out}`")


def _check_from_map_options(out: Path, name: str | None, door_width: float, min_room_area: float, unknown: str,
                            force: bool) -> None:
    """Refuse options ``scene from-map`` cannot honour, and an existing --out without --force."""
    if unknown not in ("wall", "free"):
        raise typer.BadParameter("use wall or free", param_hint="--unknown")
    for option, value in (("--door-width", door_width), ("--min-room-area", min_room_area)):
        if not (math.isfinite(value) and value > 0):
            raise typer.BadParameter("must be a positive number", param_hint=option)
    from scenes.names import check_name

    try:   # the scene's name as `scene check` will read it (it is written by the YAML emitter too)
        check_name(name or out.stem)
    except ValueError as exc:
        raise typer.BadParameter(str(exc), param_hint="--name" if name is not None else "--out") from None
    if out.exists() and not force:
        _fail(f"{out} exists; pass --force to overwrite it")


def _write_checked_scene(text: str, out: Path) -> None:
    """Write the scene, then load it as `chronav scene check` does: what is written must pass it."""
    from agents.world.scene_world import load_world
    from scenes.yamlio import SourceError

    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(text, encoding="utf-8")
    except OSError as exc:
        _fail(f"cannot write {out}: {exc.strerror or exc}")
    try:
        load_world(out)   # what `chronav scene check` runs: the output must pass it as written
    except SourceError as exc:
        _fail(f"the scene written to {out} does not pass the scene check ({exc}); please report this map", 1)


def register(app: typer.Typer) -> None:
    map_app = typer.Typer(help="Building maps and Nav2 costmap-filter masks.", no_args_is_help=True)
    map_app.command("export")(export)
    app.add_typer(map_app, name="map")

    scene_group = next((g.typer_instance for g in app.registered_groups if g.name == "scene"), None)
    if scene_group is None:
        raise RuntimeError("tools.scene.map_cli must be registered after tools.scene.scene_cli (COMMAND_MODULES)")
    scene_group.command("from-map")(from_map)
