"""`python -m tools.evaluate.markdown STUDY`: docs/baselines.md's tables from a study's table."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from tools.evaluate.markdown import main
from tools.evaluate.table import write_table


def _row(controller: str, seed: int, mission: str, state: str, duration: float, d_min: float,
         collisions: float = 0.0) -> dict[str, object]:
    return {"scene": "ward", "planner": "social", "controller": controller, "seed": seed, "mission": mission,
            "state": state, "mission_time_s": 36000.0 if mission == "m1" else 37000.0,
            "started_s": 0.0, "finished_s": duration, "duration_s": duration if state == "done" else math.nan,
            "distance_travelled_m": duration * 0.4, "dynamic.min_distance_to_people_m": d_min,
            "dynamic.intimate_intrusions_percent": 0.0, "dynamic.personal_intrusions_percent": 2.0,
            "dynamic.robot_on_person_collisions": collisions, "dynamic.person_on_robot_collisions": 0.0}


def test_the_study_tables_are_the_tables_numbers(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rows = []
    for seed in range(1, 7):   # six seeds: the band is always 2 s slower, a paired test can tell
        rows += [_row("elastic_band", seed, "m1", "done", 20.0 + seed, 1.0),
                 _row("orca", seed, "m1", "done", 18.0 + seed, 0.5, collisions=1.0),
                 _row("elastic_band", seed, "m2", "done", 30.0, 1.2),
                 _row("orca", seed, "m2", "failed" if seed == 1 else "done", 31.0, 0.4)]
    write_table(rows, tmp_path)
    assert main([str(tmp_path)]) == 0
    text = capsys.readouterr().out
    assert "24 missions over 6 seeds" in text
    # social (elastic band) is named as the report names it; social+orca did 11 of 12 missions
    assert "| social | 12/12 |" in text and "| social+orca | 11/12 |" in text
    band_times = [20.0 + s for s in range(1, 7)] + [30.0] * 6
    mean = sum(band_times) / 12
    assert f"| social | 12/12 | {mean:.2f} ± " in text
    assert "| m2 | 6/6, 30.00 s | 5/6, 31.00 s |" in text
    assert "| time to goal s | social+orca | 6 |" not in text, "m2 pairs too: 11 pairs"
    assert "| min dist. to people m | social+orca | 11 | +0.5 |" in text   # median of 0.5 x6, 0.8 x5
    assert "| collisions | social+orca | 11 | -1 |" in text


def test_a_folder_without_a_study_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main([str(tmp_path)]) == 2
    assert "finished `chronav evaluate`" in capsys.readouterr().err
