"""2-D rigid transforms for RT edges: pose of a child (x, y, theta) in its parent's frame.

Pure functions so planners can compose poses without a graph.
"""

from __future__ import annotations

import math
from collections.abc import Iterable

Pose = tuple[float, float, float]


def normalize_angle(theta: float) -> float:
    """Wrap an angle to (-pi, pi]."""
    wrapped = math.atan2(math.sin(theta), math.cos(theta))
    return math.pi if wrapped == -math.pi else wrapped


def compose(parent: Pose, child: Pose) -> Pose:
    """Pose of `child` (given in parent's frame) expressed in the frame `parent` is given in."""
    px, py, pt = parent
    cx, cy, ct = child
    c, s = math.cos(pt), math.sin(pt)
    return (px + c * cx - s * cy, py + s * cx + c * cy, normalize_angle(pt + ct))


def inverse(pose: Pose) -> Pose:
    x, y, t = pose
    c, s = math.cos(t), math.sin(t)
    return (-c * x - s * y, s * x - c * y, normalize_angle(-t))


def compose_chain(chain: Iterable[Pose]) -> Pose:
    """Compose poses from the root downwards: chain[0] is the child of the root."""
    result: Pose = (0.0, 0.0, 0.0)
    for pose in chain:
        result = compose(result, pose)
    return result
