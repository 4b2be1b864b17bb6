"""Time-series styles: one distinct, named colour per series.

Why: the viewer picks series colours by hashing entity paths, and on center_day two objects'
R(t) came out in look-alike colours (one hidden under the other when equal).  Each series gets a
colour from a categorical palette (Tableau 10, distinguishable and colour-blind aware) and a
line width that differs a little per series, so equal values still show both lines.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

PALETTE: tuple[tuple[int, int, int], ...] = (
    (31, 119, 180), (255, 127, 14), (44, 160, 44), (214, 39, 40), (148, 103, 189),
    (140, 86, 75), (227, 119, 194), (127, 127, 127), (188, 189, 34), (23, 190, 207),
)


def series_colour(index: int) -> tuple[int, int, int]:
    return PALETTE[index % len(PALETTE)]


def log_series_styles(rec: Any, prefix: str, names: Sequence[str]) -> None:
    """Static ``SeriesLines`` for ``<prefix>/<name>``, in the order given (sorted by the caller
    for stable colours across runs)."""
    if not rec.enabled:
        return
    import rerun as rr

    count = len(names)
    for i, name in enumerate(names):
        rec.log(f"{prefix}/{name}", rr.SeriesLines(colors=[series_colour(i)], names=[name],
                                                   widths=[1.5 + 1.5 * (count - 1 - i) / max(count - 1, 1)]),
                static=True)
