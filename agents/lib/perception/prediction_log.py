"""The live prediction log: what the human observer predicted for each tracked walker, every
``EVERY_S`` of sim time, one JSON object a line in ``<run>/predictions.jsonl``.

Why a log: the prediction's quality on real people inside the running system (the tracker fed the
observer's noisy detections, the social map's ``predict_many`` with the walls and the agenda) can
only be measured after the fact, against what the people then did (``people.csv``); the scoring is
``tools/live_prediction.py``.  One line: ``{"t": s, "name": str, "x": m, "y": m, "times": [s ahead],
"points": [[x, y], ...]}`` (``x, y`` the tracked position the prediction starts from).
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

PREDICTIONS_FILE = "predictions.jsonl"
EVERY_S = 0.4            # the benchmark's step (docs/prediction.md): one prediction per walker per 0.4 s


@dataclass(frozen=True)
class LoggedPrediction:
    t: float
    name: str
    x: float
    y: float
    times: tuple[float, ...]
    points: tuple[tuple[float, float], ...]


def record(t: float, name: str, x: float, y: float, times: list[float], points: list[list[float]]) -> str:
    """One line of the log (newline included)."""
    return json.dumps({"t": round(t, 3), "name": name, "x": round(x, 4), "y": round(y, 4),
                       "times": [round(v, 3) for v in times],
                       "points": [[round(p[0], 4), round(p[1], 4)] for p in points]}) + "\n"


def read(path: Path) -> Iterator[LoggedPrediction]:
    """The log's predictions in order; a line cut short by a crash (the last one) is skipped."""
    with path.open(encoding="utf-8") as handle:
        for line in handle:
            try:
                raw = json.loads(line)
                yield LoggedPrediction(float(raw["t"]), str(raw["name"]), float(raw["x"]), float(raw["y"]),
                                       tuple(float(v) for v in raw["times"]),
                                       tuple((float(p[0]), float(p[1])) for p in raw["points"]))
            except (ValueError, KeyError, TypeError, IndexError):
                continue
