"""A scene's people as the crowd simulates them: each person with their role's and routine's
defaults, the building as walls, rooms, objects and door leaves, and the checks `chronav scene check`
makes of who walks where.

Why apart from people.py: the scene check (agents/world/scene_world.py) needs these before any
agenda exists, and people.py needs a resolved world.
"""

from __future__ import annotations

import numpy as np
import shapely

from agents.lib.crowd.model import (BODY_RADIUS_M, ROLE_SPEED_MPS, ROUTINE_DWELL_S, WALKER_SPEED_MPS, Building,
                                    Thing, Walker)
from agents.lib.crowd.routes import NoRoute, Router
from agents.world.building import door_segment
from agents.world.motion import person_at
from scenes.clock import parse_clock
from scenes.crowd_recording import Recording, RecordingError, Track, read_recording
from scenes.geometry import posed_polygon
from scenes.loader import LoadedScene
from scenes.model import PersonSpec, RecordingSpec, Scene, Trapezoid

_RECORDINGS: dict[tuple[str, float, float, int], Recording] = {}   # (path, dt, mtime, size): read once a process


def scene_recordings(loaded: LoadedScene) -> dict[str, tuple[RecordingSpec, Recording]]:
    """The scene's recordings by name, read (scenes/crowd_recording.py); a bad file is a SourceError
    at its ``recordings`` entry, with the file's own line in the message."""
    out = {}
    for i, spec in enumerate(loaded.scene.recordings):
        path = loaded.resolve(spec.file)
        try:
            stat = path.stat()
            key = (str(path.resolve()), float(spec.dt), stat.st_mtime, stat.st_size)
            if key not in _RECORDINGS:
                if len(_RECORDINGS) > 8:
                    _RECORDINGS.clear()
                _RECORDINGS[key] = read_recording(path, spec.dt)
            out[spec.name] = (spec, _RECORDINGS[key])
        except FileNotFoundError:
            raise loaded.error(("recordings", i, "file"), f"recording file {spec.file!r} not found "
                               f"(looked for {path})") from None
        except (RecordingError, OSError) as exc:
            raise loaded.error(("recordings", i, "file"), f"recording {spec.name!r}: {exc}") from None
    return out


def _replayed(scene: Scene, person: PersonSpec, recordings: dict[str, tuple[RecordingSpec, Recording]]) -> Walker:
    """A ``routine: replay`` person: their record on the scene's clock (the recording's ``start``,
    default the day's start, is its first frame)."""
    spec, recording = recordings[person.recording or next(iter(recordings))]
    track: Track = recording.tracks[int(person.track or 0)]
    offset = parse_clock(spec.start) if spec.start is not None else scene.clock.start_s
    x, y, _, _ = track.at(track.start_s)
    reactive = (person.replay or scene.crowd.replay) == "reactive"
    return Walker(person.name, person.role, "replay", (x, y, person.pose.theta),
                  record=lambda t: track.at(t - offset),
                  present=(offset + track.start_s, offset + track.end_s), reactive=reactive)


def walker_of(scene: Scene, person: PersonSpec,
              recordings: dict[str, tuple[RecordingSpec, Recording]] | None = None) -> Walker:
    """A scene person with the defaults of their role and routine applied (``recordings``: the
    scene's, read by ``scene_recordings``, for its ``routine: replay`` people)."""
    pose = (person.pose.x, person.pose.y, person.pose.theta)
    if person.routine == "replay":
        if not recordings:
            raise ValueError(f"{person.name!r} replays a recording, but none was read (scene_recordings)")
        return _replayed(scene, person, recordings)
    if person.routine == "stay":
        moves = tuple(_moves(person))
        script = (lambda t, p=person: _pose(person_at(p, t))) if person.waypoints else None
        return Walker(person.name, person.role, "stay", pose, script=script, moves=moves)
    speed = person.speed if person.speed is not None else \
        (WALKER_SPEED_MPS if person.walker else ROLE_SPEED_MPS.get(person.role, 0.8))
    home = person.home or scene.room_at(person.pose.x, person.pose.y)
    dwell = tuple(person.dwell) if person.dwell is not None else ROUTINE_DWELL_S[person.routine]
    return Walker(person.name, person.role, person.routine, pose, home=home, rooms=tuple(person.rooms),
                  speed_mps=float(speed), walker=person.walker, escort=person.escort,
                  dwell_s=(float(dwell[0]), float(dwell[1])), visits=person.visits,
                  hours=None if person.hours is None else (parse_clock(person.hours[0]), parse_clock(person.hours[1])))


def _pose(state: object) -> tuple[float, float, float]:
    return (state.x, state.y, state.theta)  # type: ignore[attr-defined]


def _moves(person: PersonSpec) -> list[tuple[float, float]]:
    """The time intervals in which a scripted person's pose changes (walking or turning)."""
    out = []
    stops = [(parse_clock(w.time), w.pose) for w in person.waypoints]
    for (t0, a), (t1, b) in zip(stops, stops[1:], strict=False):
        if (a.x, a.y, a.theta) != (b.x, b.y, b.theta):
            out.append((t0, t1))
    return out


def building_of(scene: Scene) -> Building:
    rooms = {room.name: shapely.Polygon(room.polygon) for room in scene.rooms}
    things = {obj.name: Thing(obj.name, obj.pose.x, obj.pose.y, obj.pose.theta,
                              posed_polygon(obj.footprint, obj.pose.x, obj.pose.y, obj.pose.theta),
                              screen=isinstance(obj.interaction, Trapezoid))
              for obj in scene.objects}
    leaves = {door.name: door_segment(scene, door.name) for door in scene.doors}
    doors = {door.name: (float(door.position[0]), float(door.position[1])) for door in scene.doors}
    return Building(rooms, [[(x, y) for x, y in wall] for wall in scene.walls], things, leaves, doors)


def check_people(loaded: LoadedScene) -> None:
    """People who walk by themselves can: the scene's walls are polylines (a building map's wall
    cells are not walls for them yet), someone fetches those marked ``escort``, and each reaches
    every room of their routine from where they start (SourceError at the person's key)."""
    scene = loaded.scene
    check_replayed(loaded)
    walking = [(i, p) for i, p in enumerate(scene.people) if p.routine not in ("stay", "replay")]
    if not walking:
        return
    if scene.map is not None:
        i, person = walking[0]
        raise loaded.error(("people", i, "routine"), f"{person.name!r} walks by themself (routine "
                           f"{person.routine!r}), but this scene's walls come from a building map, which walking "
                           "people cannot see yet; use routine 'stay' (with waypoints) or walls drawn as polylines")
    if any(p.escort for _, p in walking) and not any(p.routine == "staff" for _, p in walking):
        i, person = next((i, p) for i, p in walking if p.escort)
        raise loaded.error(("people", i, "escort"), f"{person.name!r} is to be fetched to activities, but nobody "
                           "has routine 'staff' to fetch them; add a staff member or remove escort")
    building = building_of(scene)
    router = Router.build(shapely.union_all(list(building.rooms.values())), building.walls,
                          [t.footprint for t in building.things.values()])
    for i, person in walking:
        start = (person.pose.x, person.pose.y)
        for room in (person.rooms or [r.name for r in scene.rooms]):
            goal = _free_point(building.rooms[room], router)
            try:
                if goal is None:
                    raise NoRoute(room)
                router.route(start, goal)
            except NoRoute:
                key = ("people", i, "rooms") if person.rooms else ("people", i, "pose")
                raise loaded.error(key, f"{person.name!r} cannot walk from ({start[0]:g}, {start[1]:g}) to room "
                                   f"{room!r}: walls or furniture close the way (is a door missing or narrower "
                                   "than 0.6 m?)") from None


def check_replayed(loaded: LoadedScene) -> None:
    """The ``routine: replay`` people name a recording the scene has and an id in it, and their
    whole record lies inside the scene's rooms, clear of the walls (a person whose record starts
    inside a wall is refused with the reason, never moved silently); SourceError at the key."""
    scene = loaded.scene
    replayed = [(i, p) for i, p in enumerate(scene.people) if p.routine == "replay"]
    names = [r.name for r in scene.recordings]
    if len(set(names)) != len(names):
        dup = next(n for n in names if names.count(n) > 1)
        raise loaded.error(("recordings", names.index(dup), "name"), f"two recordings are named {dup!r}")
    if not replayed:
        return
    recordings = scene_recordings(loaded)
    rooms = shapely.union_all([shapely.Polygon(r.polygon) for r in scene.rooms])
    walls = shapely.MultiLineString([list(w) for w in scene.walls if len(w) >= 2]) if scene.walls else None
    for i, person in replayed:
        if person.recording is None and len(recordings) != 1:
            raise loaded.error(("people", i), f"{person.name!r} replays a track, but the scene has "
                               f"{len(recordings)} recordings: say which with 'recording: NAME'")
        if person.recording is not None and person.recording not in recordings:
            raise loaded.error(("people", i, "recording"), f"no recording named {person.recording!r} "
                               f"(the scene's: {', '.join(recordings) or 'none'})")
        spec, recording = recordings[person.recording or next(iter(recordings))]
        if person.track not in recording.tracks:
            raise loaded.error(("people", i, "track"), f"{person.name!r}: person {person.track} is not in "
                               f"recording {spec.name!r} ({spec.file})")
        track = recording.tracks[int(person.track or 0)]
        inside = shapely.contains_xy(rooms, track.xy[:, 0], track.xy[:, 1])
        if not inside.all():
            k = int(np.flatnonzero(~inside)[0])
            raise loaded.error(("people", i, "track"), f"{person.name!r} walks outside the scene's rooms at "
                               f"({track.xy[k, 0]:.2f}, {track.xy[k, 1]:.2f}), {track.t[k]:.1f} s into recording "
                               f"{spec.name!r} (its line {track.first_line} onwards): widen the rooms or leave "
                               "this person out")
        if walls is not None:
            near = shapely.distance(walls, shapely.points(track.xy[:1])) < BODY_RADIUS_M
            if near.any():
                raise loaded.error(("people", i, "track"), f"{person.name!r} starts inside a wall (within "
                                   f"{BODY_RADIUS_M} m of it) at ({track.xy[0, 0]:.2f}, {track.xy[0, 1]:.2f}): "
                                   "move the wall or leave this person out")


def _free_point(room: shapely.Polygon, router: Router) -> tuple[float, float] | None:
    """A place a person fits in ``room``: the free point of a 0.25 m lattice nearest its middle."""
    middle = room.representative_point()
    xmin, ymin, xmax, ymax = room.bounds
    xs, ys = np.meshgrid(np.arange(xmin + 0.125, xmax, 0.25), np.arange(ymin + 0.125, ymax, 0.25))
    candidates = sorted(zip(xs.ravel(), ys.ravel(), strict=True), key=lambda p: (p[0] - middle.x) ** 2 + (p[1] - middle.y) ** 2)
    for x, y in candidates:
        if shapely.contains_xy(room, x, y) and router.free(float(x), float(y)):
            return float(x), float(y)
    return None
