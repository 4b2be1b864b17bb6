"""``<run>/plans.jsonl``: every path the navigation adopted during a run, with its sim time.

Why a run file (beside trajectory.csv and people.csv): the DSR holds only the path in use, so
once a run ends the paths the robot followed are gone, and a bag exported from the run
(``chronav export --format mcap``) showed the robot move without the plan it followed.  The
navigation agent appends one line each time it adopts a path (a first plan or a replan), the
moment it writes the path into the DSR; a restarted navigation continues the file.

One JSON object a line: ``{"t_s": sim seconds of the day, "x": [...], "y": [...] (m, map
frame), "cost": path cost, "reason": why it was planned}``.  :func:`read_plans` reads it back
as a person-given file: bounded, every line checked, errors naming the file, line and key.
"""

from __future__ import annotations

import json
import logging
import math
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import IO

from agents.lib.metrics.metrics import MAX_COORDINATE_M, MAX_TRAJECTORY_TIME_S
from scenes.errors import SourceError
from scenes.files import read_text_bounded

log = logging.getLogger("chronav.plans_file")
PLANS_FILE = "plans.jsonl"
#: largest plans.jsonl read back (a day of replanning every few seconds with 500-point paths is
#: ~100 MB; more is not a run's file)
MAX_PLANS_BYTES = 256 * 1024 * 1024
#: most points of one path (a 1000 x 600 grid's longest path is far shorter)
MAX_PATH_POINTS = 100_000


@dataclass(frozen=True)
class AdoptedPlan:
    t_s: float
    x: tuple[float, ...]
    y: tuple[float, ...]
    cost: float
    reason: str


class PlansWriter:
    """Appends adopted paths to ``<run_dir>/plans.jsonl`` (nothing without a run directory).

    A file that cannot be opened or written (a full disk, a read-only run directory) is logged
    once and given up: keeping the record must never stop the navigation."""

    def __init__(self, run_dir: Path | None) -> None:
        self._handle: IO[str] | None = None
        if run_dir is not None:
            try:
                self._handle = (Path(run_dir) / PLANS_FILE).open("a", encoding="utf-8", buffering=1)
            except OSError as exc:
                log.warning("cannot keep the adopted plans in %s: %s", Path(run_dir) / PLANS_FILE, exc)

    def adopted(self, t_s: float, xs: Iterable[float], ys: Iterable[float], cost: float, reason: str) -> None:
        if self._handle is None:
            return
        line = {"t_s": round(float(t_s), 3), "x": [round(float(v), 4) for v in xs],
                "y": [round(float(v), 4) for v in ys], "cost": float(cost) if math.isfinite(cost) else None,
                "reason": str(reason)}
        try:
            self._handle.write(json.dumps(line, separators=(",", ":")) + "\n")
        except OSError as exc:
            log.warning("cannot keep the adopted plans any more (%s): later plans are not in %s", exc, PLANS_FILE)
            self.close()

    def close(self) -> None:
        if self._handle is not None:
            handle, self._handle = self._handle, None
            try:
                handle.close()
            except OSError:
                pass


def _numbers(file: str, lineno: int, key: str, values: object, lo: float, hi: float) -> tuple[float, ...]:
    if not isinstance(values, list) or not 0 < len(values) <= MAX_PATH_POINTS:
        raise SourceError(file, lineno, None, key, f"expected a list of 1 to {MAX_PATH_POINTS:,} numbers")
    out = []
    for value in values:
        if isinstance(value, bool) or not isinstance(value, int | float) or not lo <= value <= hi:
            raise SourceError(file, lineno, None, key, f"{str(value)[:40]!r} is not a number from {lo:g} to {hi:g}")
        out.append(float(value))
    return tuple(out)


def read_plans(path: Path) -> list[AdoptedPlan]:
    """The adopted paths of a run's plans.jsonl, in file order; SourceError at the first bad line."""
    file = str(path)
    text = read_text_bounded(path, max_bytes=MAX_PLANS_BYTES, what="plans file")
    plans = []
    for lineno, line in enumerate(text.splitlines(), start=1):
        if not line.strip():
            continue
        try:
            record = json.loads(line)
        except (ValueError, RecursionError) as exc:   # RecursionError: nesting thousands deep
            raise SourceError(file, lineno, None, "", f"not a JSON object ({str(exc)[:100]})") from None
        if not isinstance(record, dict):
            raise SourceError(file, lineno, None, "", "expected a JSON object with t_s, x, y")
        (t_s,) = _numbers(file, lineno, "t_s", [record.get("t_s")], 0.0, MAX_TRAJECTORY_TIME_S)
        xs = _numbers(file, lineno, "x", record.get("x"), -MAX_COORDINATE_M, MAX_COORDINATE_M)
        ys = _numbers(file, lineno, "y", record.get("y"), -MAX_COORDINATE_M, MAX_COORDINATE_M)
        if len(xs) != len(ys):
            raise SourceError(file, lineno, None, "y", f"{len(ys)} values for {len(xs)} x values")
        cost = record.get("cost")
        plans.append(AdoptedPlan(t_s, xs, ys, float(cost) if isinstance(cost, int | float) else math.nan,
                                 str(record.get("reason", ""))[:200]))
    return plans
