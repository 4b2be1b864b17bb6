"""The scripted world at a sim time: a scene's doors and agenda with its scripted events applied up to ``t``.

Why one function for each: the simulator and the agenda agent carry out part of the scene's script
(doors, agenda changes) live; `chronav path`, `plan` and `metrics --at t` must see the same world
without running them.  Both sides call these functions, so a door closed at 09:00 is closed for
the offline planner at 09:30 too.  Where the people are at ``t`` is agents/world/people.py.
"""

from __future__ import annotations

from collections.abc import Sequence
from agents.lib.agenda import AgendaChangeError, AgendaDay
from agents.lib.agenda.chronemics import UPCOMING_WINDOW_S
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


def scheduled_events(world: SceneWorld) -> tuple[float, ...]:
    """The sim times at which the scene's script changes the world: scripted agenda changes and
    door events, sorted.  Why: an idle skip of the clock stops at each of them, so an event fires
    at its time and not at the end of the skip (agents/sim_robot/agent.py)."""
    times = {change.at_s for change in world.scripted}
    times |= {float(parse_clock(change.at)) for change in world.scene.door_changes}
    return tuple(sorted(times))


def next_scheduled_event(world: SceneWorld, t_s: float) -> float | None:
    """The first scripted event strictly after ``t_s`` (None: no more today)."""
    return next((at for at in scheduled_events(world) if at > t_s + 1e-9), None)


def unapplied_changes(world: SceneWorld, t_s: float, applied: Sequence[str]) -> tuple[str, ...]:
    """Keys of the scripted agenda changes due by ``t_s`` that the agenda agent has not yet applied
    (nor refused): while there is one, the simulator's idle clock holds still for it."""
    done = set(applied)
    return tuple(change.key for change in world.scripted if change.at_s <= t_s and change.key not in done)
