"""Who interacts with whom: the ``interacting`` links the social map groups people by.

Why from the agenda: a resident at the table therapy interacts with the table and the therapist
while the therapy runs, and not after; links declared once in a scene and never ended kept an
object "in use" all day (center_a's table could never be approached).  So links come from the
running activities whose participants are actually at the object, plus the conversations a scene
declares between people.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping

from scenes.model import Scene

INTERACTION_RANGE_M = 1.8   # a participant farther than this from the activity's object is not (yet) in it


def scene_conversations(scene: Scene) -> list[tuple[str, str]]:
    """(person, person) pairs the scene declares with ``interacting_with``."""
    return [(person.name, other) for person in scene.people for other in person.interacting_with]


def interaction_pairs(positions: Mapping[str, tuple[float, float]],
                      running: Iterable[tuple[str, tuple[float, float], Iterable[str]]],
                      conversations: Iterable[tuple[str, str]] = ()) -> set[tuple[str, str]]:
    """``interacting`` edges as (source, target) names.

    ``positions``: where each person is; ``running``: (object, its position, participants) of every
    running activity.  A participant within INTERACTION_RANGE_M of the object interacts with it and
    with every other participant there (both ways: they form one group); declared conversations
    hold between people who are both present."""
    pairs = {(a, b) for a, b in conversations if a in positions and b in positions}
    for obj, (ox, oy), participants in running:
        present = sorted(p for p in set(participants) if p in positions
                         and math.hypot(positions[p][0] - ox, positions[p][1] - oy) < INTERACTION_RANGE_M)
        for person in present:
            pairs.add((person, obj))
            pairs.update((person, other) for other in present if other != person)
    return pairs
