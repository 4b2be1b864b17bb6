"""Fault schedules for `chronav chaos`: what to break, when, and how schedule files are read.

Why faults are anchored to missions: the day's missions end the run, so a fault timed on the
wall clock may land after the last one; "``at_s`` seconds after mission M started" always hits
work under way, and the same schedule means the same thing on a slow or a fast machine.
"""

from __future__ import annotations

import json
import random
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from tools.launch import agent_names


def processes() -> tuple[str, ...]:
    """What a fault may kill or stop: every agent of a run (the registry's), and the router."""
    return (*agent_names(), "router")


Action = Literal["kill", "stop", "agenda"]
ACTIONS: tuple[Action, ...] = ("kill", "stop", "agenda")

# Bounds of a chaos run (docs/limits.md): each fault waits for the system to converge before the
# next, so a run of more faults than this would not end in a working day; a schedule file is small.
MAX_FAULTS = 1_000
MAX_SCHEDULE_BYTES = 1024 * 1024


class ChaosError(Exception):
    """The chaos run could not be set up (bad schedule, scene, ...); the message says why."""


@dataclass(frozen=True)
class Fault:
    """One fault. Trigger: ``at_s`` wall seconds after ``mission`` became active (or, without a
    mission, after the first mission became active); with ``driving``, ``at_s`` seconds into a
    stretch of the robot driving (``nav_active``) once the mission is active.  Never before the
    previous fault converged."""

    action: Action
    target: str
    at_s: float = 0.0
    mission: str | None = None
    hold_s: float = 0.0
    change: str | None = None     # agenda change JSON (agents/agenda/changes.py wire form)
    driving: bool = False

    def __post_init__(self) -> None:
        if self.action not in ACTIONS:
            raise ChaosError(f"fault action must be one of {', '.join(ACTIONS)}, not {self.action!r}")
        if self.action in ("kill", "stop") and self.target not in processes():
            raise ChaosError(f"fault target must be one of {', '.join(processes())}, not {self.target!r}")
        if self.action == "agenda" and not self.change:
            raise ChaosError("an agenda fault needs a change (JSON of an add/cancel/move change)")
        if self.at_s < 0 or self.hold_s < 0:
            raise ChaosError(f"fault times must not be negative ({self.at_s}, {self.hold_s})")

    def describe(self) -> str:
        if self.action == "agenda":
            return f"agenda {json.loads(self.change or '{}').get('op', '?')}"
        return f"{self.action} {self.target}" + (f" {self.hold_s:.1f}s" if self.action == "stop" else "")



def clock_text(seconds: object) -> str:
    """A sim time as HH:MM:SS, ``-`` when there is none (not a number)."""
    if not isinstance(seconds, (int, float)) or isinstance(seconds, bool):
        return "-"
    from scenes.clock import format_clock

    return format_clock(seconds)


def random_agenda_change(rng: random.Random, scene: Any, known_ids: list[str], index: int, tag: str) -> str:
    """A plausible staff edit: add an activity on a scene object, move or cancel a known one."""
    from scenes.clock import format_clock_minutes, parse_clock   # here: `chronav --help` imports this module

    start_min = int(parse_clock(scene.clock.start) // 60)
    end_min = int(parse_clock(scene.clock.end) // 60)
    op = rng.choice(("add", "add", "move", "cancel")) if known_ids else "add"
    if op == "add" or not scene.objects:
        begin = rng.randrange(start_min, max(start_min + 1, end_min - 15))
        length = rng.choice((15, 30, 45, 60))
        activity_id = f"{tag}_{index}"
        known_ids.append(activity_id)
        return json.dumps({"op": "add", "activity": {
            "id": activity_id, "name": f"chaos activity {index}", "object": rng.choice(scene.objects).name,
            "start": format_clock_minutes(begin * 60), "end": format_clock_minutes(min(begin + length, 24 * 60 - 1) * 60)}})
    target = rng.choice(known_ids)
    if op == "cancel":
        return json.dumps({"op": "cancel", "id": target})
    begin = rng.randrange(start_min, max(start_min + 1, end_min - 15))
    return json.dumps({"op": "move", "id": target, "start": format_clock_minutes(begin * 60)})


def random_schedule(loaded: Any, *, seed: int, faults: int, duration_s: float) -> list[Fault]:
    """``faults`` faults spread evenly over the day's missions, each at a random time within
    ``duration_s`` wall seconds after its mission starts (so they hit missions under way).

    Deterministic for a seed.  Kills and stops pick any agent or the router; stops last 0.3-3 s
    (either side of the 2 s link lease); agenda edits add, move or cancel activities."""
    from scenes.clock import parse_clock

    missions = [m.id for m in sorted(loaded.scene.missions, key=lambda m: parse_clock(m.time))]
    if faults < 0 or duration_s <= 0:
        raise ChaosError(f"need faults >= 0 and duration > 0 (got {faults}, {duration_s})")
    if faults > MAX_FAULTS:
        raise ChaosError(f"--faults {faults:,}: a chaos run injects at most {MAX_FAULTS:,} faults (each waits "
                         "for the system to converge); run several shorter chaos runs instead")
    if faults and not missions:
        raise ChaosError(f"scene {loaded.scene.name!r} has no missions to inject faults into")
    rng = random.Random(seed)
    known_ids = list(loaded.agenda.ids())
    planned = sorted((index * len(missions) // max(faults, 1), round(rng.uniform(0.0, duration_s), 2))
                      for index in range(faults))
    out: list[Fault] = []
    for index, (mission_index, at_s) in enumerate(planned):
        mission = missions[mission_index]
        action = rng.choices(ACTIONS, weights=(4, 3, 3))[0]
        if action == "agenda":
            change = random_agenda_change(rng, loaded.scene, known_ids, index, f"chaos{seed}")
            out.append(Fault("agenda", "agenda", at_s=at_s, mission=mission, change=change))
        else:
            hold = round(rng.uniform(0.3, 3.0), 2) if action == "stop" else 0.0
            out.append(Fault(action, rng.choice(processes()), at_s=at_s, mission=mission, hold_s=hold))
    return out


def load_schedule(path: Path) -> list[Fault]:
    """A schedule file: a JSON list of faults (the "fault" objects of a chaos summary replay a run).

    ``change`` may be given as an object; errors name the file and the fault's index."""
    from scenes.errors import SourceError   # here, not at the top: `chronav --help` imports this module
    from scenes.files import read_text_bounded
    from scenes.names import shown

    try:   # a regular file of at most MAX_SCHEDULE_BYTES (docs/limits.md), never /dev/zero or a FIFO
        items = json.loads(read_text_bounded(path, max_bytes=MAX_SCHEDULE_BYTES, what="JSON schedule"))
    except SourceError as exc:
        raise ChaosError(str(exc)) from None
    except (json.JSONDecodeError, RecursionError) as exc:
        raise ChaosError(f"{path}: cannot read a JSON schedule: {shown(exc, 200)}") from None
    if not isinstance(items, list):
        raise ChaosError(f"{path}: a schedule is a JSON list of faults")
    if len(items) > MAX_FAULTS:
        raise ChaosError(f"{path}: {len(items):,} faults; a schedule has at most {MAX_FAULTS:,}")
    faults: list[Fault] = []
    for index, item in enumerate(items):
        try:
            if not isinstance(item, dict):
                raise TypeError("a fault is an object such as {\"action\": \"kill\", \"target\": \"router\"}")
            if isinstance(item.get("change"), dict):
                item = {**item, "change": json.dumps(item["change"])}
            faults.append(Fault(**item))
        except (TypeError, ChaosError) as exc:
            raise ChaosError(f"{path}: fault {index}: {exc}") from None
    return faults
