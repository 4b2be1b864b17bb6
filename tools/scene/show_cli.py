"""`chronav scene show SCENE [--json]`: what a scene holds, with coordinates, without reading its YAML.

Why: `chronav path --from X,Y --to X,Y`, `chronav plan --mission` and `chronav agenda add` need the
names and coordinates of rooms, doors, objects and people and the day's agenda; a newcomer should
not have to read 200 lines of YAML (or polygons) to find a point inside the lounge.  Each room
comes with a point inside it and clear of its objects, ready for `--from`/`--to`.

Everything comes from the resolved scene (agents/world/scene_world.py): the agenda as the agenda
agent will publish it on the scene's day (its file or inline activities, recurrences expanded),
and the missions as the executive reads them.
"""

from __future__ import annotations

import json
from typing import Any

import typer


def _xy(x: float, y: float) -> list[float]:
    return [round(float(x), 2), round(float(y), 2)]


def _room_point(polygon: Any, obstacles: Any) -> list[float]:
    """A point inside the room, clear of its objects when it can be (for --from/--to)."""
    free = polygon.difference(obstacles.buffer(0.5)) if obstacles is not None else polygon
    where = (free if not free.is_empty else polygon).representative_point()
    return _xy(where.x, where.y)


def _room_of(rooms: list[tuple[str, Any]], x: float, y: float) -> str | None:
    from shapely.geometry import Point

    here = Point(x, y)
    return next((name for name, polygon in rooms if polygon.covers(here)), None)


def scene_summary(world: Any) -> dict[str, Any]:
    """The scene as one JSON-ready dict: clock, rooms, doors, objects, people, robot, agenda, missions."""
    from shapely.geometry import Polygon
    from shapely.ops import unary_union

    from agents.world.scene_world import SceneWorld
    from scenes.clock import format_clock

    assert isinstance(world, SceneWorld)
    scene = world.scene
    rooms = [(room.name, Polygon(room.polygon)) for room in scene.rooms]
    footprints = unary_union([_footprint(o) for o in scene.objects]) if scene.objects else None
    room_rows = []
    for name, polygon in rooms:
        xmin, ymin, xmax, ymax = polygon.bounds
        room_rows.append({"name": name, "point": _room_point(polygon, footprints), "area_m2": round(polygon.area, 1),
                          "x": [round(xmin, 2), round(xmax, 2)], "y": [round(ymin, 2), round(ymax, 2)]})
    return {
        "scene": scene.name, "description": scene.description, "file": str(world.path),
        "clock": {"date": scene.clock.date.isoformat(), "timezone": scene.clock.timezone,
                  "start": format_clock(scene.clock.start_s), "end": format_clock(scene.clock.end_s)},
        "rooms": room_rows,
        "doors": [{"name": d.name, "between": list(d.between), "at": _xy(*d.position), "width_m": d.width}
                  for d in scene.doors],
        "objects": [{"name": o.name, "kind": o.kind, "at": _xy(o.pose.x, o.pose.y), "theta": round(o.pose.theta, 2),
                     "room": _room_of(rooms, o.pose.x, o.pose.y), "interaction": o.interaction.shape}
                    for o in scene.objects],
        "people": [{"name": p.name, "role": p.role, "at": _xy(p.pose.x, p.pose.y),
                    "room": _room_of(rooms, p.pose.x, p.pose.y),
                    "routine": "waypoints" if p.waypoints else str(p.routine)} for p in scene.people],
        "robot": {"name": scene.robot.name, "at": _xy(scene.robot.pose.x, scene.robot.pose.y),
                  "room": _room_of(rooms, scene.robot.pose.x, scene.robot.pose.y), "radius_m": scene.robot.radius,
                  "kinematics": scene.robot.kinematics},
        "agenda": [{"id": a.id, "name": a.name, "object": a.object, "room": a.room,
                    "start": format_clock(a.start_s), "end": format_clock(a.end_s),
                    "state": str(a.state.value), "participants": list(a.participants)}
                   for a in world.agenda.activities],
        "missions": [{"id": m.id, "time": format_clock(_clock_s(m.time)), "goal": m.goal_text(),
                      "description": m.description} for m in scene.missions],
    }


def _clock_s(text: str) -> float:
    from scenes.clock import parse_clock

    return parse_clock(text)


def _footprint(obj: Any) -> Any:
    """The object's footprint polygon in the world frame (scenes/geometry.py, as the planner sees it)."""
    from scenes.geometry import posed_polygon

    return posed_polygon(obj.footprint, obj.pose.x, obj.pose.y, obj.pose.theta)


def summary_lines(data: dict[str, Any], width: int) -> list[str]:
    """The summary as sections of short lines, wrapped between words at ``width``."""
    from tools.plain import plural, wrapped

    def point(xy: list[float]) -> str:
        return f"{xy[0]:g},{xy[1]:g}"

    clock = data["clock"]
    lines = wrapped(f"{data['scene']}: {data['description']}".rstrip(": "), width, indent="  ")
    lines.append(f"day {clock['date']} {clock['start']}-{clock['end']} ({clock['timezone']}); points are "
                 "X,Y in metres, as `chronav path --from/--to` takes them")
    lines.append(f"rooms ({len(data['rooms'])}): a point inside each")
    lines += [f"  {r['name']}  {point(r['point'])}  (x {r['x'][0]:g}..{r['x'][1]:g}, y {r['y'][0]:g}..{r['y'][1]:g}, "
              f"{r['area_m2']:g} m2)" for r in data["rooms"]]
    if data["doors"]:
        lines.append(f"doors ({len(data['doors'])})")
        lines += [f"  {d['name']}  {point(d['at'])}  {d['between'][0]} <-> {d['between'][1]}, {d['width_m']:g} m"
                  for d in data["doors"]]
    if data["objects"]:
        lines.append(f"objects ({len(data['objects'])})")
        lines += [f"  {o['name']}  {point(o['at'])}  {o['kind']}" + (f" in {o['room']}" if o["room"] else "")
                  for o in data["objects"]]
    robot = data["robot"]
    lines.append(f"robot  {robot['name']}  {point(robot['at'])}" + (f" in {robot['room']}" if robot["room"] else "")
                 + f", radius {robot['radius_m']:g} m, {robot['kinematics']}")
    if data["people"]:
        lines.append(f"people ({len(data['people'])}) at the start of the day")
        lines += [f"  {p['name']}  {point(p['at'])}  {p['role']}" + (f" in {p['room']}" if p["room"] else "")
                  + f", {p['routine']}" for p in data["people"]]
    lines.append(f"agenda ({plural(len(data['agenda']), 'activity', 'activities')})")
    for a in data["agenda"]:
        where = a["object"] + (f" in {a['room']}" if a["room"] else "")
        lines += wrapped(f"{a['start']}-{a['end']}  {a['id']} ({a['name']}) on {where}", width, first="  ",
                         indent="      ")
        if a["participants"]:
            lines += wrapped("with " + ", ".join(a["participants"]), width, first="      ", indent="      ")
    lines.append(f"missions ({len(data['missions'])})")
    for m in data["missions"]:
        lines += wrapped(f"{m['time']}  {m['id']}: {m['goal']}" + (f" ({m['description']})" if m["description"] else ""),
                         width, first="  ", indent="      ")
    out: list[str] = []
    for line in lines:       # any line still too long wraps between words, under its own indent
        lead = line[:len(line) - len(line.lstrip())]
        out += [line] if len(line) <= width else wrapped(line.strip(), width, first=lead, indent=lead + "    ")
    return out


def show(scene: str = typer.Argument(..., help="scene file or name in scenes/"),
         as_json: bool = typer.Option(False, "--json", help="one JSON object on stdout")) -> None:
    """Rooms (with a point inside each), doors, objects and people with their coordinates, the robot,
    the day's agenda and the missions: the names and points `chronav path`, `plan` and `agenda` take."""
    from rich.console import Console

    from agents.world.scene_world import load_world
    from scenes.yamlio import SourceError
    from tools.plain import console_width, print_lines

    try:
        world = load_world(scene)
    except SourceError as exc:
        typer.echo(str(exc), err=True)
        raise typer.Exit(1) from None
    data = scene_summary(world)
    if as_json:
        typer.echo(json.dumps(data))
        return
    console = Console()
    print_lines(console, summary_lines(data, console_width(console)))
