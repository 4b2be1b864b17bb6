"""A scene around recorded pedestrians (``chronav scene from-crowd``): an open plaza, the people
replaying their records, and robot missions that cross the crowd where and when it is busiest.

Why generated: testing social navigation on recorded people (as SocNavBench does with ETH/UCY) needs
a world the recording fits in and missions that meet the crowd; choosing them by hand for every
file is tedious and biased.  The plaza is the recordings' extent plus ``margin_m`` on every side
(one room, four walls): nobody's record can start inside a wall.  Missions are seeded:

1. the annotations are binned into ``CELL_M`` squares and ``BIN_S`` time bins; the (cell, bin)
   pairs holding the most person-samples are the busy ones (the top ``BUSY_SHARE``, at least one);
2. each mission draws a busy pair (spaced so that missions do not overlap) and a crossing direction,
   and goes from where the robot is, through the busy cell's centre, to the far side of the plaza
   (``INSET_M`` inside the walls), leaving so as to reach the cell in the middle of its busy bin at
   ``PLANNED_SPEED_MPS``.  The robot starts on the near side of the first crossing.

The recordings start ``LEAD_S`` after the day's start (the robot's first mission may leave before
the crowd's busy time); the day ends ``TAIL_S`` after the last recording or mission.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml

from scenes.clock import format_clock
from scenes.crowd_recording import Recording

CELL_M = 2.0
BIN_S = 10.0
BUSY_SHARE = 0.1
INSET_M = 1.0
PLANNED_SPEED_MPS = 0.45
LEAD_S = 60.0
TAIL_S = 60.0
DAY_START_S = 9 * 3600.0
MAX_MISSIONS = 50


class _NoAliases(yaml.SafeDumper):
    """Writes a repeated corner twice instead of as a YAML anchor and alias (``&id001``/``*id001``):
    a scene is read and edited by people."""

    def ignore_aliases(self, data: object) -> bool:
        return True


class CrowdSceneError(ValueError):
    """Options or recordings ``from-crowd`` cannot build a scene from."""


@dataclass(frozen=True)
class Crossing:
    """One robot mission: leave at ``time_s`` (clock) for ``goal``; it meets the busy cell ``via``."""

    time_s: float
    start: tuple[float, float]
    via: tuple[float, float]
    goal: tuple[float, float]
    busy_count: int
    busy_s: float             # clock time the robot should reach ``via`` (the busy bin's middle)


def recording_name(path: Path) -> str:
    """A recording's name in the scene: the file's stem, letters, digits and ``_`` only."""
    stem = "".join(ch if ch.isalnum() else "_" for ch in path.stem) or "recording"
    return stem if not stem[0].isdigit() else f"r_{stem}"


def _busy(recordings: list[Recording], bounds: tuple[float, float, float, float]) -> list[tuple[int, float, float, float]]:
    """(count, t, x, y) of every occupied (cell, time bin), busiest first; t the bin's middle (s
    since the recordings' start), (x, y) the cell's centre."""
    xmin, ymin, _, _ = bounds
    cells: dict[tuple[int, int, int], int] = {}
    for rec in recordings:
        for track in rec.tracks.values():
            ix = ((track.xy[:, 0] - xmin) // CELL_M).astype(int)
            iy = ((track.xy[:, 1] - ymin) // CELL_M).astype(int)
            ib = (track.t // BIN_S).astype(int)
            for key in zip(ib.tolist(), ix.tolist(), iy.tolist(), strict=True):
                cells[key] = cells.get(key, 0) + 1
    ranked = sorted(cells.items(), key=lambda kv: (-kv[1], kv[0]))
    return [(n, (b + 0.5) * BIN_S, xmin + (i + 0.5) * CELL_M, ymin + (j + 0.5) * CELL_M) for (b, i, j), n in ranked]


def _exit(point: tuple[float, float], direction: tuple[float, float], box: tuple[float, float, float, float]) -> tuple[float, float]:
    """Where the ray from ``point`` along ``direction`` leaves ``box`` (xmin, ymin, xmax, ymax)."""
    x, y = point
    dx, dy = direction
    steps = []
    for d, p, lo, hi in ((dx, x, box[0], box[2]), (dy, y, box[1], box[3])):
        if d > 1e-12:
            steps.append((hi - p) / d)
        elif d < -1e-12:
            steps.append((lo - p) / d)
    s = max(0.0, min(steps)) if steps else 0.0
    return (min(max(x + s * dx, box[0]), box[2]), min(max(y + s * dy, box[1]), box[3]))


def plan_crossings(recordings: list[Recording], bounds: tuple[float, float, float, float], missions: int, seed: int,
                   offset_s: float) -> list[Crossing]:
    """The robot's missions (module doc), in time order, from a seeded generator."""
    if missions == 0:
        return []
    rng = np.random.default_rng(seed)
    inner = (bounds[0] + INSET_M, bounds[1] + INSET_M, bounds[2] - INSET_M, bounds[3] - INSET_M)
    busy = _busy(recordings, bounds)
    top = busy[:max(1, int(math.ceil(BUSY_SHARE * len(busy))))]
    span = math.hypot(bounds[2] - bounds[0], bounds[3] - bounds[1])
    spacing = span / PLANNED_SPEED_MPS + BIN_S        # one crossing's time at most, plus a bin
    chosen: list[tuple[int, float, float, float]] = []
    for index in rng.permutation(len(top)).tolist():
        candidate = top[index]
        if all(abs(candidate[1] - c[1]) >= spacing for c in chosen):
            chosen.append(candidate)
        if len(chosen) == missions:
            break
    chosen.sort(key=lambda c: c[1])
    out: list[Crossing] = []
    angle = float(rng.uniform(0, 2 * math.pi))
    first = chosen[0] if chosen else None
    here = _exit((first[2], first[3]), (-math.cos(angle), -math.sin(angle)), inner) if first else (0.0, 0.0)
    free_s = offset_s - LEAD_S
    for count, t, x, y in chosen:
        dx, dy = x - here[0], y - here[1]
        if math.hypot(dx, dy) < 1.0:                 # already at the busy cell: cross it in a fresh direction
            angle = float(rng.uniform(0, 2 * math.pi))
            dx, dy = math.cos(angle), math.sin(angle)
        norm = math.hypot(dx, dy)
        goal = _exit((x, y), (dx / norm, dy / norm), inner)
        leave = max(free_s, offset_s + t - math.hypot(x - here[0], y - here[1]) / PLANNED_SPEED_MPS)
        leave = float(math.floor(leave))
        out.append(Crossing(leave, here, (x, y), goal, count, offset_s + t))
        free_s = leave + math.hypot(goal[0] - here[0], goal[1] - here[1]) / PLANNED_SPEED_MPS + BIN_S
        here = goal
    return out


def _reference(path: Path, out: Path) -> str:
    """The recording as the scene names it: relative to the scene when near it (a scene and its data
    move together), else absolute."""
    relative = os.path.relpath(path.resolve(), out.resolve().parent)
    return str(path.resolve()) if relative.startswith(os.path.join("..", "..", "..")) else relative


def _round(values: list[float] | tuple[float, ...], digits: int = 3) -> list[float]:
    return [round(float(v), digits) for v in values]


def scene_text(recordings: list[Recording], out: Path, name: str, *, margin_m: float = 2.0, missions: int = 3,
               seed: int = 0, replay: str = "exact", command: str = "") -> str:
    """The scene as YAML (module doc): comments first, then the keys ``chronav scene check`` reads."""
    if not recordings:
        raise CrowdSceneError("no recording given")
    if not 0.5 <= margin_m <= 20.0:
        raise CrowdSceneError(f"the plaza's margin must be 0.5-20 m, got {margin_m:g}")
    if not 0 <= missions <= MAX_MISSIONS:
        raise CrowdSceneError(f"--missions must be 0-{MAX_MISSIONS}, got {missions}")
    extents = np.array([r.extent() for r in recordings])
    bounds = (float(extents[:, 0].min() - margin_m), float(extents[:, 1].min() - margin_m),
              float(extents[:, 2].max() + margin_m), float(extents[:, 3].max() + margin_m))
    bounds = (math.floor(bounds[0] * 10) / 10, math.floor(bounds[1] * 10) / 10,
              math.ceil(bounds[2] * 10) / 10, math.ceil(bounds[3] * 10) / 10)
    names = [recording_name(r.path) for r in recordings]
    if len(set(names)) != len(names):
        raise CrowdSceneError("two recordings have the same file name: "
                              f"{next(n for n in names if names.count(n) > 1)!r}; rename one")
    offset = DAY_START_S + LEAD_S
    crossings = plan_crossings(recordings, bounds, missions, seed, offset)
    end = max([offset + r.duration_s for r in recordings]
              + [c.time_s + math.dist(c.start, c.goal) / PLANNED_SPEED_MPS * 2 for c in crossings]) + TAIL_S
    end = min(math.ceil(end / 60.0) * 60.0, 23 * 3600.0 + 59 * 60.0)
    xmin, ymin, xmax, ymax = bounds
    corners = [[xmin, ymin], [xmax, ymin], [xmax, ymax], [xmin, ymax]]
    people = []
    for rec_name, rec in zip(names, recordings, strict=True):
        for pid, track in sorted(rec.tracks.items()):
            heading = 0.0
            if len(track.xy) > 1:
                d = track.xy[1] - track.xy[0]
                heading = math.atan2(d[1], d[0]) if float(np.hypot(*d)) > 1e-6 else 0.0
            person = {"name": f"{rec_name}_{pid}", "role": "visitor", "routine": "replay", "track": pid,
                      "pose": _round([track.xy[0, 0], track.xy[0, 1], heading])}
            if len(recordings) > 1:
                person["recording"] = rec_name
            people.append(person)
    robot_pose = crossings[0].start if crossings else ((xmin + xmax) / 2, ymin + INSET_M)
    first_heading = (math.atan2(crossings[0].goal[1] - robot_pose[1], crossings[0].goal[0] - robot_pose[0])
                     if crossings else math.pi / 2)
    body = {
        "name": name,
        "description": f"An open plaza around recorded pedestrians ({', '.join(r.path.name for r in recordings)}), "
                       f"replayed {replay}; {len(crossings)} robot crossings of the busiest places at their busy "
                       "times. Written by chronav scene from-crowd.",
        "clock": {"start": format_clock(DAY_START_S), "end": format_clock(end), "rate": 60, "skip_idle": True},
        "walls": [[*corners, corners[0]]],
        "rooms": [{"name": "plaza", "polygon": corners}],
        "crowd": {"seed": seed, "replay": replay},
        "recordings": [{"name": n, "file": _reference(r.path, out),
                        "dt": r.dt_s, "start": format_clock(offset)} for n, r in zip(names, recordings, strict=True)],
        "robot": {"pose": _round([robot_pose[0], robot_pose[1], first_heading])},
        "missions": [{"id": f"cross_{k + 1}", "time": format_clock(c.time_s),
                      "goal": {"pose": _round([c.goal[0], c.goal[1],
                                               math.atan2(c.goal[1] - c.start[1], c.goal[0] - c.start[0])])},
                      "description": f"cross the plaza through ({c.via[0]:.1f}, {c.via[1]:.1f}), busy around "
                                     f"{format_clock(c.busy_s)} ({c.busy_count} person-samples in {CELL_M:g} m x "
                                     f"{BIN_S:g} s)"}
                     for k, c in enumerate(crossings)],
    }
    header = (f"# Written by `{command or 'chronav scene from-crowd'}`.\n"
              "# An open plaza (the recordings' extent plus a margin) where recorded pedestrians walk their\n"
              "# records (routine: replay; crowd.replay: exact walks them whatever the robot does, reactive\n"
              "# starts on them and avoids the robot). Missions cross the busiest places at their busy times\n"
              "# (seeded). docs/crowds.md. ETH/UCY data: cite its source (UCY: Lerner, Chrysanthou,\n"
              "# Lischinski, \"Crowds by Example\", 2007; see scenes/data/pedestrians/SOURCES.md).\n")
    lines = "".join(f"- {yaml.dump(p, Dumper=_NoAliases, sort_keys=False, default_flow_style=True, width=10_000, allow_unicode=True)}"
                    for p in people)           # one person a line: hundreds of them stay readable
    return (header + yaml.dump(body, Dumper=_NoAliases, sort_keys=False, default_flow_style=None, width=120,
                               allow_unicode=True) + "people:\n" + lines)
