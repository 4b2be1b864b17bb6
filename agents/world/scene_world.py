"""A scene with its agenda resolved and its scripted events checked: what every run starts from.

Why a layer above ``scenes/``: a scene file is only data (schema and geometry, ``scenes/``); its
agenda needs the agenda library to be placed on the sim date, and its scripted agenda changes can
only be checked by applying them.  Agents, the launcher and every offline command load a scene
through :func:`load_world`, so a scene that one of them accepts, all of them accept, and a bad
scripted change fails at ``chronav scene check`` instead of minutes into a run.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from agents.lib.agenda import (AgendaChangeError, AgendaDay, AgendaError, AgendaSourceError, AgendaValidationError,
                               apply_change, expand_day, load_scene_agenda, parse_change)
from agents.world.vocabulary import activity_id_of
from scenes.clock import parse_clock
from scenes.loader import LoadedScene, load_scene
from scenes.model import Scene, WaitGoal
from scenes.yamlio import SourceError


@dataclass(frozen=True)
class ScriptedChange:
    """One of the scene's ``agenda_changes``: applied once when the sim clock reaches ``at_s``.

    ``key`` ("scene#<index>") marks it applied in the DSR's agenda log (restart-safe); ``text`` is
    the change in the wire form of ``chronav agenda`` (agents/lib/agenda/changes.py)."""

    index: int
    at_s: float
    text: str

    @property
    def key(self) -> str:
        return f"scene#{self.index}"


@dataclass(frozen=True)
class SceneWorld:
    """A loaded scene, the day's agenda as planned, and the scripted changes in the order they apply."""

    loaded: LoadedScene
    agenda: AgendaDay
    scripted: tuple[ScriptedChange, ...]

    @property
    def scene(self) -> Scene:
        return self.loaded.scene

    @property
    def path(self) -> Path:
        return self.loaded.path

    @property
    def object_names(self) -> frozenset[str]:
        return frozenset(o.name for o in self.scene.objects)

    @property
    def room_names(self) -> frozenset[str]:
        return frozenset(r.name for r in self.scene.rooms)

    def apply(self, day: AgendaDay, change: ScriptedChange) -> AgendaDay:
        """``change`` applied to ``day`` exactly as the agenda agent applies it."""
        return apply_change(day, parse_change(change.text), known_objects=self.object_names,
                            known_rooms=self.room_names)


def scripted_changes(scene: Scene) -> tuple[ScriptedChange, ...]:
    """The scene's ``agenda_changes`` in the order they take effect: by time, then as written."""
    out = []
    for index, change in enumerate(scene.agenda_changes):
        payload = {k: v for k, v in change.model_dump().items() if k != "at" and v is not None}
        out.append(ScriptedChange(index, parse_clock(change.at), json.dumps(payload)))
    return tuple(sorted(out, key=lambda c: (c.at_s, c.index)))


def _agenda_error(exc: Exception, loaded: LoadedScene) -> SourceError:
    """Agenda errors name "file:line" in their findings; keep that position for the scene check."""
    scene_file = str(loaded.path)
    if isinstance(exc, AgendaSourceError):
        problem = exc.problems[0]
        return SourceError(problem.file, problem.line or 1, 1, problem.key, problem.message)
    if isinstance(exc, AgendaValidationError) and exc.report.errors:
        finding = exc.report.errors[0]
        file, _, line = finding.source.rpartition(":")
        if file and line.isdigit():
            return SourceError(file, int(line), 1, "agenda", finding.message)
        return SourceError(scene_file, 1, 1, "agenda", finding.message)
    return SourceError(scene_file, 1, 1, "agenda", str(exc))


def resolve_world(loaded: LoadedScene) -> SceneWorld:
    """The agenda of a loaded scene placed on its date, and its scripted changes checked by applying
    them in order (SourceError at the offending ``agenda_changes`` entry)."""
    scene = loaded.scene
    if scene.agenda_file is not None and not loaded.resolve(scene.agenda_file).exists():
        raise loaded.error(("agenda_file",), f"agenda file {scene.agenda_file!r} not found")
    try:
        day = expand_day(load_scene_agenda(loaded.path), scene.clock.date, scene.clock.timezone,
                         {o.name for o in scene.objects}, known_rooms={r.name for r in scene.rooms})
    except AgendaError as exc:
        raise _agenda_error(exc, loaded) from None
    world = SceneWorld(loaded, day, scripted_changes(scene))
    check = day
    for change in world.scripted:
        try:
            check = world.apply(check, change)
        except AgendaChangeError as exc:
            raise loaded.error(("agenda_changes", change.index), str(exc)) from None
    _check_wait_missions(loaded, {a.id for a in day.activities} | {a.id for a in check.activities})
    return world


def _check_wait_missions(loaded: LoadedScene, activity_ids: set[str]) -> None:
    """A ``wait`` mission names an activity of the day (or one a scripted change adds)."""
    for index, mission in enumerate(loaded.scene.missions):
        if isinstance(mission.goal, WaitGoal):
            wanted = activity_id_of(mission.goal.wait)
            if wanted not in activity_ids:
                known = ", ".join(sorted(activity_ids)) or "none"
                raise loaded.error(("missions", index, "goal", "wait"),
                                   f"mission {mission.id!r} waits for unknown activity {wanted!r}; activities: {known}")


def load_world(name_or_path: str | Path | LoadedScene) -> SceneWorld:
    """Read, validate and resolve a scene; SourceError (``file:line:col: key: message``) otherwise."""
    loaded = name_or_path if isinstance(name_or_path, LoadedScene) else load_scene(name_or_path)
    return resolve_world(loaded)
