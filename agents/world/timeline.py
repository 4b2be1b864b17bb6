"""The world at a sim time: a scene plus its scripted events applied up to ``t``.

Why one function for it: the simulator, the agenda agent and the human observer each carry out
part of the scene's script (doors, agenda changes, people's walks) live; `chronav path`, `plan`
and `metrics --at t` must see the same world without running them.  Both sides call these
functions, so a door closed at 09:00 is closed for the offline planner at 09:30 too.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from agents.lib.agenda import AgendaChangeError, AgendaDay
from agents.lib.agenda.chronemics import UPCOMING_WINDOW_S
from agents.world.motion import PersonState, people_at
from agents.world.scene_world import SceneWorld
from scenes.clock import parse_clock
from scenes.model import Scene


def doors_at(scene: Scene, t_s: float) -> dict[str, bool]:
    """Every door's state at ``t_s``: open unless its latest scripted change due by then closed it."""
    state = {door.name: True for door in scene.doors}
    due = sorted(((parse_clock(c.at), i, c) for i, c in enumerate(scene.door_changes)), key=lambda d: d[:2])
    for at_s, _, change in due:
        if at_s <= t_s:
            state[change.door] = change.open
    return state


def agenda_at(world: SceneWorld, t_s: float, upcoming_window_s: float = UPCOMING_WINDOW_S) -> AgendaDay:
    """The day's agenda with the scripted changes due by ``t_s`` applied (a refused one is skipped,
    as the agenda agent skips it) and every activity's state brought up to ``t_s``."""
    day = world.agenda
    for change in world.scripted:
        if change.at_s > t_s:
            break
        try:
            day = world.apply(day, change)
        except AgendaChangeError:
            continue
    return day.at(t_s, upcoming_window_s)


@dataclass(frozen=True)
class WorldAt:
    """The scripted world at ``t_s``: doors, agenda and where everyone truly is."""

    world: SceneWorld
    t_s: float
    doors_open: Mapping[str, bool]
    agenda: AgendaDay
    people: tuple[PersonState, ...]


def world_at(world: SceneWorld, t_s: float) -> WorldAt:
    return WorldAt(world, t_s, doors_at(world.scene, t_s), agenda_at(world, t_s),
                   tuple(people_at(world.scene, t_s)))
