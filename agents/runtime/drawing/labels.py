"""Labels that stay readable on a crowded day: short ids and a declutter rule.

Why: on center_day 26 people and 4 objects stand in one building; full names ("nurse_rosa")
drawn at every body collide and hide each other.  A label is the name without its role prefix
("rosa"; the role is the colour and the hover text), and in a crowd a label is drawn only where
no label already drawn lies within ``min_gap_m`` (greedy, in a stable order, so labels do not
jump from frame to frame).  Every body keeps its full name on hover in the viewer.
"""

from __future__ import annotations

from collections.abc import Sequence

ROLE_PREFIXES = ("res_", "resident_", "nurse_", "staff_", "therapist_", "visitor_", "new_resident_")
LABEL_GAP_M = 1.0   # two label anchors closer than this: the later one is hidden


def short_id(name: str) -> str:
    """``"nurse_rosa"`` -> ``"rosa"``; names without a role prefix stay as they are."""
    for prefix in ROLE_PREFIXES:
        if name.startswith(prefix) and len(name) > len(prefix):
            return name[len(prefix):]
    return name


def short_ids(names: Sequence[str]) -> list[str]:
    """Short ids, falling back to the full name where two short ids would be the same."""
    shorts = [short_id(n) for n in names]
    return [s if shorts.count(s) == 1 else n for s, n in zip(shorts, names, strict=True)]


def declutter(texts: Sequence[str], anchors: Sequence[Sequence[float]], min_gap_m: float = LABEL_GAP_M,
              taken: Sequence[Sequence[float]] = ()) -> list[str]:
    """``texts`` with "" for every label whose anchor lies within ``min_gap_m`` of a label already
    kept (in the given order) or of a point in ``taken`` (labels of another layer)."""
    kept: list[tuple[float, float]] = [(float(p[0]), float(p[1])) for p in taken]
    out: list[str] = []
    gap2 = min_gap_m * min_gap_m
    for text, (x, y) in zip(texts, anchors, strict=True):
        if any((x - kx) ** 2 + (y - ky) ** 2 < gap2 for kx, ky in kept):
            out.append("")
            continue
        kept.append((float(x), float(y)))
        out.append(text)
    return out
