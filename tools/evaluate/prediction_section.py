"""The evaluate report's live prediction section: per scene and planner, the human observer's
prediction error measured in each run (``result.json``'s ``prediction``, tools/live_prediction.py).

Why a section of its own: the planners' tables compare what the robot did; this says how well the
robot foresaw the people it met, which explains part of it (on a replayed crowd, on real human
motion).  Runs without a scored prediction (no walker met while driving) are counted, not averaged.
"""

from __future__ import annotations

import html
import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

KEYS = ("ade_m", "fde_m", "cv_true_ade_m", "cv_true_fde_m")


def run_prediction(run: Mapping[str, Any]) -> dict[str, Any] | None:
    """A run's live prediction entry, read from its result.json (None: none scored, or no run)."""
    run_dir = run.get("run_dir")
    if not run_dir:
        return None
    try:
        found = json.loads((Path(run_dir) / "result.json").read_text(encoding="utf-8")).get("prediction")
    except (OSError, ValueError, AttributeError):
        return None
    return found if isinstance(found, dict) else None


def live_prediction_html(runs: Sequence[Mapping[str, Any]]) -> list[str]:
    """``<h2>Live prediction</h2>`` and one row per (scene, planner): runs scored, predictions,
    mean ADE / FDE over the runs, and constant velocity from the truth in the same windows."""
    groups: dict[tuple[str, str], list[dict[str, Any] | None]] = {}
    for run in runs:
        spec = run["spec"]
        groups.setdefault((Path(spec["scene"]).stem, str(spec["planner"])), []).append(run_prediction(run))
    if not groups:
        return []
    esc = html.escape
    parts = ["<h2>Live prediction</h2><p class='note'>The human observer's predictions of the walkers it "
             "tracked, 0.4-4.8 s ahead, against where they then were (people.csv), metres; CV: constant "
             "velocity from the true position and velocity, same windows (docs/crowds.md).</p>"
             "<table><tr><th>scene</th><th>planner</th><th>runs scored</th><th>predictions</th>"
             "<th>ADE</th><th>FDE</th><th>CV ADE</th><th>CV FDE</th></tr>"]
    for (scene, planner), found in sorted(groups.items()):
        scored = [f for f in found if f]
        means = [sum(float(f.get(k, float("nan"))) for f in scored) / len(scored) if scored else float("nan")
                 for k in KEYS]
        cells = "".join(f"<td>{m:.3f}</td>" if m == m else "<td>-</td>" for m in means)
        parts.append(f"<tr><td>{esc(scene)}</td><td>{esc(planner)}</td><td>{len(scored)} / {len(found)}</td>"
                     f"<td>{sum(int(f.get('predictions', 0)) for f in scored)}</td>{cells}</tr>")
    parts.append("</table>")
    return parts
