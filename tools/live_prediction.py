"""The live prediction error of a run: the human observer's predictions (``predictions.jsonl``,
agents/lib/perception/prediction_log.py) against what the people then did (``people.csv``).

Why after the run: the truth of a prediction is 4.8 s in the future.  For every logged prediction
of a walker, at each 0.4 s step ahead up to ``HORIZON_S``, the predicted point (held at its last
point where the prediction stops short: a wall, an arrival; ``prediction_eval.interpolated``) is
compared with where the simulator's truth had the person then.  A prediction is scored only when
the truth covers its whole horizon (people.csv is written while the robot drives, and a replayed
person may leave): ADE = mean distance over the 12 steps, FDE = the distance at 4.8 s, both
averaged over the scored predictions (metres).  Beside them, in the same windows, constant
velocity from the person's *true* position and velocity at the time of the prediction (the
benchmark's baseline, docs/prediction.md).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:
    from agents.lib.metrics.dynamic_metrics import PeopleTracks

HORIZON_S = 4.8
STEP_S = 0.4
MATCH_S = 0.06          # a truth sample this close to the wanted time (people.csv: every 0.1 s)


def live_prediction(run_dir: Path) -> dict[str, object] | None:
    """``result.json``'s ``prediction`` entry (module doc), or None when the run logged no
    prediction that the truth covers (no walker while the robot drove, or no run directory).
    Never raises on what a run left behind: result.json is written however the run ended (a
    crash can leave a log or a people.csv cut short)."""
    try:
        return _scored(run_dir)
    except (OSError, ValueError, KeyError, IndexError, TypeError):
        return None


def _scored(run_dir: Path) -> dict[str, object] | None:
    from agents.lib.perception.prediction_log import PREDICTIONS_FILE, read
    from agents.lib.metrics.metrics import TrajectoryFormatError, read_people_csv

    log, people = run_dir / PREDICTIONS_FILE, run_dir / "people.csv"
    if not log.exists() or not people.exists():
        return None
    try:
        tracks = present_rows(read_people_csv(people))     # who was really there, when
    except (TrajectoryFormatError, OSError, ValueError, KeyError):
        return None
    ahead = np.arange(1, round(HORIZON_S / STEP_S) + 1) * STEP_S
    errors, cv_errors = [], []
    for p in read(log):
        track = tracks.get(p.name)
        if track is None or not p.times or len(p.points) != len(p.times) or len(track) < 2:
            continue
        times = track[:, 0]
        wanted = np.concatenate([[p.t], p.t + ahead])
        rows = np.clip(np.searchsorted(times, wanted), 1, len(times) - 1)
        nearer = np.where(np.abs(times[rows - 1] - wanted) < np.abs(times[rows] - wanted), rows - 1, rows)
        if np.any(np.abs(times[nearer] - wanted) > MATCH_S):
            continue                        # the truth does not cover the horizon (robot parked, person gone)
        tx, ty = track[nearer, 1], track[nearer, 2]
        known_t = np.concatenate([[0.0], p.times])
        known = np.concatenate([[[p.x, p.y]], np.array(p.points)])
        px, py = np.interp(ahead, known_t, known[:, 0]), np.interp(ahead, known_t, known[:, 1])
        errors.append(np.hypot(px - tx[1:], py - ty[1:]))
        vx, vy = track[nearer[0], 3], track[nearer[0], 4]
        cv_errors.append(np.hypot(tx[0] + vx * ahead - tx[1:], ty[0] + vy * ahead - ty[1:]))
    if not errors:
        return None
    e, c = np.array(errors), np.array(cv_errors)
    return {"predictions": len(errors), "horizon_s": HORIZON_S, "step_s": STEP_S,
            "ade_m": round(float(e.mean()), 4), "fde_m": round(float(e[:, -1].mean()), 4),
            "cv_true_ade_m": round(float(c.mean()), 4), "cv_true_fde_m": round(float(c[:, -1].mean()), 4)}


def present_rows(tracks: PeopleTracks) -> dict[str, NDArray[np.float64]]:
    """Each person's samples while there: (n, 5) arrays of t, x, y, vx, vy in time order."""
    out = {}
    for j, name in enumerate(tracks.names):
        there = tracks.present[:, j]
        out[name] = np.column_stack([tracks.times[there], tracks.x[there, j], tracks.y[there, j],
                                     tracks.vx[there, j], tracks.vy[there, j]])
    return out
