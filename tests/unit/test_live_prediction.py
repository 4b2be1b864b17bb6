"""The live prediction error of a run (tools/live_prediction.py): the observer's logged predictions
against people.csv, only where the truth covers the whole horizon; and its section in the
evaluate report."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from agents.lib.perception import prediction_log
from tools.evaluate.prediction_section import live_prediction_html
from tools.live_prediction import live_prediction


def _run(tmp_path: Path) -> Path:
    """ann walks east at 1 m/s for 10 s (truth every 0.1 s); three predictions: exact at 1 s, 0.5 m
    to the side at 2 s, and one at 8 s whose horizon the truth does not cover."""
    rows = ["t,name,role,x,y,theta,vx,vy,group"]
    rows += [f"{k / 10:.3f},ann,visitor,{k / 10:.4f},0.0000,0.00000,1.0000,0.0000," for k in range(101)]
    (tmp_path / "people.csv").write_text("\n".join(rows) + "\n", encoding="utf-8")
    ahead = [0.4 * k for k in range(1, 13)]
    lines = [prediction_log.record(1.0, "ann", 1.0, 0.0, ahead, [[1.0 + a, 0.0] for a in ahead]),
             prediction_log.record(2.0, "ann", 2.0, 0.5, ahead, [[2.0 + a, 0.5] for a in ahead]),
             prediction_log.record(8.0, "ann", 8.0, 0.0, ahead, [[8.0 + a, 0.0] for a in ahead]),
             prediction_log.record(3.0, "ghost", 0.0, 0.0, ahead, [[a, 0.0] for a in ahead]),
             '{"t": 4.0, "name": "ann", "x": 1'  # cut short by a crash: skipped
             ]
    (tmp_path / prediction_log.PREDICTIONS_FILE).write_text("".join(lines), encoding="utf-8")
    return tmp_path


def test_live_prediction_scores_what_the_truth_covers(tmp_path: Path) -> None:
    found = live_prediction(_run(tmp_path))
    assert found is not None
    assert found["predictions"] == 2
    assert found["ade_m"] == pytest.approx(0.25, abs=1e-4) and found["fde_m"] == pytest.approx(0.25, abs=1e-4)
    assert found["cv_true_ade_m"] == pytest.approx(0.0, abs=1e-4), "constant velocity is exact on a straight walk"


def test_a_prediction_stopping_short_holds_its_last_point(tmp_path: Path) -> None:
    run = _run(tmp_path)
    (run / prediction_log.PREDICTIONS_FILE).write_text(
        prediction_log.record(1.0, "ann", 1.0, 0.0, [0.4, 0.8], [[1.4, 0.0], [1.8, 0.0]]), encoding="utf-8")
    found = live_prediction(run)
    assert found is not None and found["fde_m"] == pytest.approx(4.8 - 0.8, abs=1e-3)


def test_a_person_who_left_is_not_scored_against_where_they_left(tmp_path: Path) -> None:
    """bob is in people.csv for 2 s only (a replayed record that ended): a prediction of him at
    1 s has no truth for its horizon and is not scored; ann's are."""
    run = _run(tmp_path)
    rows = (run / "people.csv").read_text(encoding="utf-8").splitlines()
    rows[1:22] = [line for k in range(21) for line in
                  (rows[1 + k], f"{k / 10:.3f},bob,visitor,5.0000,{k / 10:.4f},1.5708,0.0000,1.0000,")]
    (run / "people.csv").write_text("\n".join(rows) + "\n", encoding="utf-8")
    with (run / prediction_log.PREDICTIONS_FILE).open("a", encoding="utf-8") as handle:
        handle.write("\n" + prediction_log.record(1.0, "bob", 5.0, 1.0, [0.4 * k for k in range(1, 13)],
                                                  [[5.0, 1.0 + 0.4 * k] for k in range(1, 13)]))
    found = live_prediction(run)
    assert found is not None and found["predictions"] == 2


def test_no_log_or_nothing_scored_is_none(tmp_path: Path) -> None:
    assert live_prediction(tmp_path) is None
    (tmp_path / "people.csv").write_text("t,name,role,x,y,theta,vx,vy,group\n1.0,ann,visitor,x,0,0,0,0,\n",
                                         encoding="utf-8")
    (tmp_path / prediction_log.PREDICTIONS_FILE).write_text('{"t": 1, "name": "ann", "x": 0, "y": 0, '
                                                           '"times": [0.4], "points": []}\n', encoding="utf-8")
    assert live_prediction(tmp_path) is None, "a broken people.csv: no figure, and no exception"
    run = _run(tmp_path)
    (run / prediction_log.PREDICTIONS_FILE).write_text(
        prediction_log.record(9.0, "ann", 9.0, 0.0, [0.4], [[9.4, 0.0]]), encoding="utf-8")
    assert live_prediction(run) is None


def test_the_evaluate_report_section_averages_the_runs(tmp_path: Path) -> None:
    runs = []
    for seed, entry in enumerate([{"predictions": 10, "ade_m": 0.2, "fde_m": 0.4, "cv_true_ade_m": 0.3,
                                   "cv_true_fde_m": 0.6}, {"predictions": 30, "ade_m": 0.4, "fde_m": 0.8,
                                                           "cv_true_ade_m": 0.5, "cv_true_fde_m": 1.0}, None]):
        run_dir = tmp_path / f"run{seed}"
        run_dir.mkdir()
        (run_dir / "result.json").write_text(json.dumps({"prediction": entry}), encoding="utf-8")
        runs.append({"spec": {"scene": "crowds/circle_crossing.yaml", "planner": "social", "seed": seed},
                     "run_dir": str(run_dir)})
    html = "".join(live_prediction_html(runs))
    assert "<h2>Live prediction</h2>" in html
    assert "<td>circle_crossing</td><td>social</td><td>2 / 3</td><td>40</td><td>0.300</td><td>0.600</td>" in html


def test_predict_evaluate_on_a_runs_people_csv_counts_only_who_was_there(tmp_path: Path) -> None:
    """A replayed person who left the run (bob, 5 s) gives no window: read_people_csv's tracks
    would hold him at his exit for the rest of the file (22 windows of a ghost standing still)."""
    from typer.testing import CliRunner

    from tools.cli import app

    rows = ["t,name,role,x,y,theta,vx,vy,group"]
    for k in range(161):
        t = 32400 + 0.1 * k
        rows.append(f"{t:.3f},ann,visitor,{0.1 * k:.4f},0.0000,0.00000,1.0000,0.0000,")
        if k <= 50:
            rows.append(f"{t:.3f},bob,visitor,5.0000,{0.1 * k:.4f},1.57080,0.0000,1.0000,")
    data = tmp_path / "people.csv"
    data.write_text("\n".join(rows) + "\n", encoding="utf-8")
    result = CliRunner().invoke(app, ["predict", "evaluate", str(data), "--noise", "0", "--json"])
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout)["files"]["people.csv"]["tracks"] == 41 - 20 + 1, "ann's windows only"
