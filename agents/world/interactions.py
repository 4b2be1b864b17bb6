"""Who interacts with whom: the ``interacting`` links the social map groups people by.

Why from the agenda: a resident at the table therapy interacts with the table and the therapist
while the therapy runs, and not after; links declared once in a scene and never ended kept an
object "in use" all day (center_a's table could never be approached).  So links come from the
running activities whose participants are actually at the object, the conversations a scene
declares between people, and the conversations the observer sees: two people standing close and
facing each other (an F-formation, Kendon 1990; the pair circles of agents/lib/crowd/formations.py).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping

from scenes.angles import wrap_angle
from scenes.model import Scene

INTERACTION_RANGE_M = 1.8   # a participant farther than this from the activity's object is not (yet) in it
CONVERSATION_RANGE_M = 1.6  # two people talking stand at most this far apart (Hall's personal distance + a bit)
CONVERSATION_FACING_RAD = math.radians(60)   # ... each facing the other within this
STILL_MPS = 0.2             # ... and neither walking


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


def observed_conversations(people: Mapping[str, tuple[float, float, float, float]]) -> list[tuple[str, str]]:
    """(person, person) pairs seen talking: ``people`` maps a name to (x, y, theta, speed); two
    still people within CONVERSATION_RANGE_M of each other, each facing the other within
    CONVERSATION_FACING_RAD (a circle of three or four facing its centre passes this pairwise)."""
    still = sorted((name, p) for name, p in people.items() if p[3] < STILL_MPS)
    pairs = []
    for i, (a, (ax, ay, ath, _)) in enumerate(still):
        for b, (bx, by, bth, _) in still[i + 1:]:
            dx, dy = bx - ax, by - ay
            if math.hypot(dx, dy) > CONVERSATION_RANGE_M:
                continue
            bearing = math.atan2(dy, dx)
            if abs(wrap_angle(bearing - ath)) <= CONVERSATION_FACING_RAD and \
                    abs(wrap_angle(bearing + math.pi - bth)) <= CONVERSATION_FACING_RAD:
                pairs += [(a, b), (b, a)]
    return pairs

