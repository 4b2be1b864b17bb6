"""One simulated person's state: what they are doing (``Task``) and their own random stream.

Why a module of its own: the schedule, the routines, the escorts and the motion all read and
change a person's task; this is the one definition they share (crowd.py composes them).
"""

from __future__ import annotations

import math
import zlib
from dataclasses import dataclass, field

import numpy as np

from agents.lib.crowd.model import Walker

#: the random stream index of the start-of-day draw
FIRST_DECISION = 2**31
#: purposes of a person outside their ``hours``: not in the building yet (or any more), and on the way out
AWAY = "away"
LEAVE = "leave"


@dataclass
class Task:
    """What one person is doing: standing somewhere (until a time) or walking to a pose."""

    kind: str                         # "stand" | "walk"
    purpose: str                      # dwell | chat | attend | fetch | escort | stay | leave | away
    target: tuple[float, float, float]
    until_s: float = math.inf
    activity: str = ""
    other: str = ""                   # fetch/escort: the resident; chat: the group id
    route: list[tuple[float, float]] = field(default_factory=list)
    look_at: tuple[float, float] | None = None   # what they face when they settle short of the target
    best_m: float = math.inf
    progress_s: float = 0.0
    replans: int = 0


@dataclass
class Person:
    spec: Walker
    index: int
    task: Task
    decisions: int = 0
    next_check_s: float = -math.inf
    escorted_to: str = ""             # activity a staff member is walking them to


def person_rng(seed: int, name: str, k: int) -> np.random.Generator:
    """Person ``name``'s ``k``-th draw: a person's day does not change when someone else is added."""
    return np.random.default_rng([seed, zlib.crc32(name.encode()), k])
