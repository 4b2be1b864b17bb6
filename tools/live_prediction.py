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

import math
from pathlib import Path

import numpy as np

HORIZON_S = 4.8
STEP_S = 0.4
MATCH_S = 0.06          # a truth sample this close to the wanted time (people.csv: every 0.1 s)


def live_prediction(run_dir: Path) -> dict[str, object] | None:
    """``result.json``'s ``prediction`` entry (module doc), or None when the run logged no
    prediction that the truth covers (no walker while the robot drove, or no run directory)."""
    from agents.lib.perception.prediction_log import PREDICTIONS_FILE, read
    from agents.lib.socialmap.metrics import TrajectoryFormatError, read_people_csv

    log, people = run_dir / PREDICTIONS_FILE, run_dir / "people.csv"
    if not log.exists() or not people.exists():
        return None
    try:
        tracks = read_people_csv(people)
    except (TrajectoryFormatError, OSError):
        return None
    if len(tracks.times) == 0:
        return None
    index = {name: i for i, name in enumerate(tracks.names)}
    ahead = np.arange(1, round(HORIZON_S / STEP_S) + 1) * STEP_S
    errors, cv_errors = [], []
    for p in read(log):
        col = index.get(p.name)
        if col is None or not p.times:
            continue
        wanted = np.concatenate([[p.t], p.t + ahead])
        rows = np.searchsorted(tracks.times, wanted)
        rows = np.clip(rows, 1, len(tracks.times) - 1)
        nearer = np.where(np.abs(tracks.times[rows - 1] - wanted) < np.abs(tracks.times[rows] - wanted), rows - 1, rows)
        if np.any(np.abs(tracks.times[nearer] - wanted) > MATCH_S):
            continue
        tx, ty = tracks.x[nearer, col], tracks.y[nearer, col]
        if not (np.all(np.isfinite(tx)) and np.all(np.isfinite(ty))):
            continue
        known_t = np.concatenate([[0.0], p.times])
        known = np.concatenate([[[p.x, p.y]], np.array(p.points)])
        px, py = np.interp(ahead, known_t, known[:, 0]), np.interp(ahead, known_t, known[:, 1])
        errors.append(np.hypot(px - tx[1:], py - ty[1:]))
        vx, vy = tracks.vx[nearer[0], col], tracks.vy[nearer[0], col]
        if math.isfinite(vx) and math.isfinite(vy):
            cv_errors.append(np.hypot(tx[0] + vx * ahead - tx[1:], ty[0] + vy * ahead - ty[1:]))
    if not errors:
        return None
    e = np.array(errors)
    out: dict[str, object] = {"predictions": len(errors), "horizon_s": HORIZON_S, "step_s": STEP_S,
                              "ade_m": round(float(e.mean()), 4), "fde_m": round(float(e[:, -1].mean()), 4)}
    if cv_errors:
        c = np.array(cv_errors)
        out.update(cv_true_ade_m=round(float(c.mean()), 4), cv_true_fde_m=round(float(c[:, -1].mean()), 4))
    return out
